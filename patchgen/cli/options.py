"""Option types the commands share: numbers that must be finite and in range, seeds, and the
plant parameters and fraction a sweep or a spread varies them by.

click's FloatRange lets ``nan`` through (every comparison with it is false) and has no upper
bound unless given one; ``FiniteFloat`` refuses nan and inf and checks both ends.
"""

from __future__ import annotations

import math

import click

from patchgen.inputs.errors import InputError
from patchgen.inputs.resources import shipped

SEED = click.IntRange(0, 2**63 - 1)  # numpy's generators take a non-negative 64-bit seed


def out_option(what: str):
    """The ``-o/--out DIR`` option every writing command takes; ``what`` says what goes there."""
    return click.option("-o", "--out", "out_dir", required=True, type=click.Path(file_okay=False),
                        help=f"Directory for {what}.")


def json_option(what: str):
    """The ``--json`` flag: print ``what`` as one JSON object instead of the terminal view."""
    return click.option("--json", "as_json", is_flag=True, help=f"Print {what} as JSON.")


def svg_option(what: str):
    """The ``--svg`` flag: also write ``what`` as SVG."""
    return click.option("--svg", is_flag=True, help=f"Also write {what} as SVG (PNG only by default).")


def seed_option(default: int | None, what: str):
    """The ``--seed`` option: ``what`` it seeds."""
    return click.option("--seed", type=SEED, default=default, show_default=default is not None, help=what)


# replace what a command would write: every writing command takes it
FORCE = click.option("--force", is_flag=True, help="Replace output files that already exist.")

# a scenario the command must be given
SCENARIO = click.option("--scenario", "scenario_path", required=True, metavar="SCENARIO",
                        help=f"Scenario: a TOML file, or a shipped one by name ({', '.join(shipped('scenario'))}; "
                             "patchgen examples copies them out to edit).")

# another machine than the spec's: every command that patches takes it (patchgen.pipeline.inputs.load_inputs)
MACHINE = click.option("--machine", "machine", default=None, metavar="MACHINE",
                       help=f"Machine to patch instead of the spec's: a shipped one ({', '.join(shipped('machine'))}) "
                            "or a machine profile's TOML file.")


def bench_option(extra: str = ""):
    """The ``--bench`` option: another bench profile than the spec's; ``extra`` says what follows."""
    return click.option("--bench", "bench_name", default=None, metavar="BENCH",
                        help="Bench profile (a shipped id or a TOML file) instead of the spec's" + (
                            f"; {extra}" if extra else "."))


class FiniteFloat(click.ParamType):
    """A finite float within [lo, hi]."""

    name = "number"

    def __init__(self, lo: float | None = None, hi: float | None = None):
        self.lo, self.hi = lo, hi

    def convert(self, value, param, ctx) -> float:
        if isinstance(value, float):
            x = value
        else:
            try:
                x = float(value)
            except (TypeError, ValueError):
                self.fail(f"{value!r} is not a number", param, ctx)
        if not math.isfinite(x):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        if (self.lo is not None and x < self.lo) or (self.hi is not None and x > self.hi):
            self.fail(f"{value!r} is not within {self.lo:g} to {self.hi:g}", param, ctx)
        return x


def parse_vary(text: str | None, option: str = "--vary", plant=None) -> list[str]:
    """Comma-separated parameters of ``plant`` a sweep may vary (patchgen.studies.sweep.variable;
    the cart's by default), or, when ``text`` is None, those a bench may have wrong (gravity not
    among them); an InputError naming ``option`` otherwise."""
    from patchgen.studies.sweep import VARIABLE, variable  # the sweep's own (and its process pool): for sweep alone

    allowed = VARIABLE if plant is None else variable(plant)
    uncertain = tuple(n for n in allowed if n != "g")
    names = list(uncertain) if text is None else [t.strip() for t in text.split(",") if t.strip()]
    for n in names:
        if n not in allowed:
            raise InputError(option, "", f"unknown parameter {n!r} (choose from {', '.join(allowed)})")
    if not names:
        raise InputError(option, "", "name at least one parameter")
    return names


def parse_by(text: str, option: str = "--by") -> float:
    """A fraction ("0.1") or percentage ("10%") strictly between 0 and 1; an InputError otherwise."""
    t = text.strip()
    try:
        v = float(t[:-1]) / 100 if t.endswith("%") else float(t)
    except ValueError:
        raise InputError(option, "", f"{text!r} is not a fraction or a percentage (e.g. 10%)") from None
    if not (0 < v < 1):
        raise InputError(option, "", f"{text!r} must be between 0 and 100%")
    return v
