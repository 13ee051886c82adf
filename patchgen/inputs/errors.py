"""The one error type for bad user input: file, field path and what is wrong, on one line, with
the change to the spec that lifts it when the search that refused found one."""

from __future__ import annotations

import json
from dataclasses import dataclass


@dataclass(frozen=True)
class Cure:
    """A change to one field of the spec that lifts a refusal: found by the search that refused,
    and checked by running the refusing stage again with it before it is offered.

    Parameters
    ----------
    field : str
        The field's dotted path in the spec (``estimator.rolloff_s``).
    value : float, int or str
        The value that passes.
    gives : str
        What the stage gives with it, in a few words (``gives 28 deg of phase margin``).
    """

    field: str
    value: float | int | str
    gives: str

    def line(self) -> str:
        """``estimator.rolloff_s = 0.00708 gives ... (set it in [estimator])``."""
        table = self.field.rpartition(".")[0]
        value = json.dumps(self.value) if isinstance(self.value, str) else f"{self.value:g}"
        return f"{self.field} = {value} {self.gives} (set it in [{table}])"


class InputError(Exception):
    """Bad input from the user (spec, scenario, option). The CLI prints it as one line, exit 2.

    Parameters
    ----------
    source : str
        The file at fault, or the run-plan field (``runs``, ``bench_spread``): the command line
        names a field by the option that set it (``--runs``).
    field : str
        The field path inside it (``weights.Q.theta``), or "" for the file as a whole.
    message : str
        What is wrong, in words a user can act on.
    cure : Cure, optional
        A change to the spec that lifts the refusal, checked (the line ends with it).
    """

    exit_status = 2

    def __init__(self, source: str, field: str, message: str, cure: Cure | None = None):
        self.source = str(source)
        self.field = field
        self.message = message
        self.cure = cure
        super().__init__(self.line())

    def __reduce__(self):
        # rebuilt from its parts (a sweep's worker process sends it back pickled)
        return (type(self), (self.source, self.field, self.message, self.cure))

    def line(self) -> str:
        """``source: field: message``, the one line the CLI prints, and the cure when there is one."""
        where = f"{self.source}: {self.field}" if self.field else self.source
        return f"{where}: {self.message}" + (f"; {self.cure.line()}" if self.cure is not None else "")


class ResourceError(InputError):
    """A design needs more of the machine than the profile has."""
