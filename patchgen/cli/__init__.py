"""patchgen's command line: one click group, one module per command."""

from __future__ import annotations

import importlib
import os
import sys

import click

from patchgen.inputs.errors import InputError

from .. import __version__

# patchgen's matrices are a few states wide: OpenBLAS's worker threads only add start-up and
# spin-waits (twice the time of a design on a busy machine) and take cores from the simulator's
# threads. Set before numpy loads; a user's own setting wins. The results are the same.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

COMMANDS = ("design", "patch", "check", "simulate", "spice", "recommend", "swingup", "sweep", "identify",
            "bench-test", "examples")

# The first sentence of each command's docstring, for `patchgen --help` without importing every
# command (and so numpy, scipy, numba, matplotlib). tests/cli/test_cli_imports.py keeps them in step.
SUMMARIES = {
    "design": "Compute the LQR gain, Kalman estimator, loop transfer recovery and loop margins of SPEC.",
    "patch": "Scale SPEC's gains, allocate the machine and write the patch: netlist.json, pots.csv, "
             "patch-sheet.html, patch-sheet.md (with the bench prediction) and wiring.svg.",
    "check": "Compare a filled static check with SPEC's patch and name the likeliest wrong pot, cord or sign.",
    "simulate": "Simulate SPEC's patched circuit (built from its netlist) on the bench.",
    "spice": "Export SPEC's patch and the bench as an ngspice deck, run it, and compare with patchgen's own "
             "simulation of the same scenario.",
    "recommend": "Run every realisation of SPEC on the bench in every scenario; write the best patch and its spec.",
    "swingup": "Pump SPEC's pendulum up from hanging at rest, hand it to the patched controller when the state "
               "enters the zone of the linear design, and hold it on the bench (actuator lag and dead zone, "
               "noise, drift).",
    "sweep": "Re-design SPEC with each plant parameter off by --by (thesis tables 4.1, 4.2): the gains, the "
             "margins, the pots that would change, and how the nominal patch (as wired) does on that plant.",
    "identify": "Fit a bench profile and the plant's friction and length to recordings of the standard tests.",
    "bench-test": "Record every standard bench test of SPEC's plant on its bench (noise and random forces as the "
                  "profile says), for practice and to check identify against known values.",
    "examples": "Copy the shipped designs (DIR/designs), scenarios (DIR/sims) and machine and bench profiles "
                "(DIR/machines, DIR/benches) into DIR, to edit and run by path.",
}


class _Group(click.Group):
    """Loads each command's module only when that command runs (a design need not import the
    simulator), and turns an InputError anywhere into one line on stderr and its exit status."""

    def list_commands(self, ctx):
        return sorted(COMMANDS)

    def get_command(self, ctx, name):
        if name in COMMANDS and name not in self.commands:
            importlib.import_module(f"{__name__}.{name.replace('-', '_')}")  # its @cli.command registers it
        return super().get_command(ctx, name)

    def format_commands(self, ctx, formatter):
        """The command list from SUMMARIES, as click would write it from the loaded commands."""
        names = self.list_commands(ctx)
        limit = formatter.width - 6 - max(len(n) for n in names)
        cmds = [self.commands.get(n) or click.Command(n, help=SUMMARIES[n]) for n in names]
        rows = [(n, c.get_short_help_str(limit)) for n, c in zip(names, cmds)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except InputError as exc:
            click.echo(f"patchgen: {_one_line(exc.line())}", err=True)
            sys.exit(exc.exit_status)
        finally:
            helper = sys.modules.get("patchgen.render.plot_helper")  # only where a command loaded it
            if helper is not None:
                helper.stop()


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="patchgen")
def cli() -> None:
    """From an optimal cart-pendulum controller to a checked Comdyna GP-6 patch.

    \b
    patchgen design SPEC                 LQR / Kalman / LTR design and its margins
    patchgen patch SPEC -o DIR           netlist, pot table, patch sheet, wiring diagram
    patchgen simulate SPEC --scenario X -o DIR   the patched circuit on the bench
    patchgen spice SPEC --scenario X -o DIR      the patch checked by ngspice
    patchgen recommend SPEC -o DIR       every realisation on the bench, the best patch
    patchgen swingup SPEC -o DIR         pump-up, hand-off, hold with the patch
    patchgen sweep SPEC                  gains, margins, pots with parameters off by 10%
    patchgen bench-test SPEC -o DIR      recordings of the standard bench tests
    patchgen identify DIR -o OUT         a bench profile and the plant from recordings
    patchgen examples DIR                copy the shipped designs and scenarios to edit

    SPEC is a TOML file or a shipped design by name (bench-recommended,
    thesis-ch5, thesis-case1, ...); --scenario likewise (hold-120s, ...).
    """


def _one_line(text: str) -> str:
    return " ".join(text.splitlines())


def main() -> None:
    """Run the CLI; a usage error (bad option, missing argument) or bad input anywhere is one line
    on stderr and exit 2. Anything else is a bug, and its traceback shows."""
    try:
        rv = cli.main(prog_name="patchgen", standalone_mode=False)
    except InputError as exc:  # raised while click converts an option, outside a command
        click.echo(f"patchgen: {_one_line(exc.line())}", err=True)
        sys.exit(exc.exit_status)
    except click.UsageError as exc:
        cmd = exc.ctx.command_path if exc.ctx else "patchgen"
        click.echo(f"{cmd}: {_one_line(exc.format_message())} (see {cmd} --help)", err=True)
        sys.exit(2)
    except click.ClickException as exc:
        click.echo(f"patchgen: {_one_line(exc.format_message())}", err=True)
        sys.exit(exc.exit_code)
    except BrokenPipeError:  # the reader of stdout went away (patchgen ... | head): nothing to say
        sys.stdout = open(os.devnull, "w")  # Python flushes stdout at exit: let that go nowhere
        sys.exit(1)
    except click.Abort:
        click.echo("patchgen: aborted", err=True)
        sys.exit(1)
    sys.exit(rv if isinstance(rv, int) else 0)
