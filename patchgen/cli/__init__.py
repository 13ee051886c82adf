"""patchgen's command line: one click group, one module per command."""

from __future__ import annotations

import sys

import click

from .. import __version__
from ..errors import InputError


class _Group(click.Group):
    """Turns an InputError anywhere into one line on stderr and its exit status."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except InputError as exc:
            click.echo(f"patchgen: {exc.line()}", err=True)
            sys.exit(exc.exit_status)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="patchgen")
def cli() -> None:
    """From an optimal cart-pendulum controller to a checked Comdyna GP-6 patch.

    \b
    patchgen design SPEC        LQR / Kalman / LTR design and its margins
    patchgen patch SPEC -o DIR  netlist, pot table, patch sheet, wiring diagram
    patchgen sweep SPEC         gains, margins and pots with parameters off by 10%
    patchgen recommend SPEC -o DIR  simulate every realisation on the bench, write the best patch
    """


def _register() -> None:
    from . import design as _design  # noqa: F401
    from . import patch as _patch  # noqa: F401
    from . import recommend as _recommend  # noqa: F401
    from . import simulate as _simulate  # noqa: F401
    from . import spice as _spice  # noqa: F401
    from . import sweep as _sweep  # noqa: F401
    from . import swingup as _swingup  # noqa: F401


_register()


def main() -> None:
    cli(prog_name="patchgen")
