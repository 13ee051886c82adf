"""The one error type for bad user input: file, field path and what is wrong, on one line."""

from __future__ import annotations


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
    """

    exit_status = 2

    def __init__(self, source: str, field: str, message: str):
        self.source = str(source)
        self.field = field
        self.message = message
        super().__init__(self.line())

    def __reduce__(self):
        # rebuilt from its three parts (a sweep's worker process sends it back pickled)
        return (type(self), (self.source, self.field, self.message))

    def line(self) -> str:
        """``source: field: message``, the one line the CLI prints."""
        where = f"{self.source}: {self.field}" if self.field else self.source
        return f"{where}: {self.message}"


class ResourceError(InputError):
    """A design needs more of the machine than the profile has."""
