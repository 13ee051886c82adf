"""patchgen's command line: one click group, one module per command."""

from __future__ import annotations

import ast
import atexit
import gc
import importlib
import os
import sys
from pathlib import Path

import click

from patchgen.inputs.errors import InputError

from .. import __version__

# patchgen's matrices are a few states wide: OpenBLAS's worker threads only add start-up and
# spin-waits (twice the time of a design on a busy machine) and take cores from the simulator's
# threads. Set before numpy loads; a user's own setting wins. The results are the same.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# A command is one short process that builds a few hundred thousand objects (numpy, scipy, numba,
# the pydantic models) and keeps most of them to its end. At the collector's default pace (every 700
# new objects, a full pass as the heap grows by a quarter) it traverses them again and again, and once
# more on the way out: patchgen patch thesis-case2 spent 0.1-0.2 s collecting and 0.2 s exiting. The
# first threshold is raised so that it runs a tenth as often, and the survivors are frozen as the
# interpreter exits (before it clears the modules), so that the exit leaves them be. Nothing computed
# changes; the memory held between collections is a few megabytes at most.
GC_FIRST_THRESHOLD = 10_000

COMMANDS = ("design", "patch", "check", "simulate", "spice", "export", "recommend", "swingup", "sweep", "identify",
            "bench-test", "examples")

def command_help(name: str) -> str:
    """A command's help as its own docstring says it, read from its module's source without
    importing it (so `patchgen --help` loads neither numpy nor the simulator, and no copy of the
    docstrings is kept by hand)."""
    source = Path(__file__).with_name(f"{name.replace('-', '_')}.py").read_text(encoding="utf-8")
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.FunctionDef) and any(
                isinstance(d, ast.Call) and d.args and isinstance(d.args[0], ast.Constant) and d.args[0].value == name
                for d in node.decorator_list):
            return ast.get_docstring(node) or ""
    return ""


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
        """The command list from the commands' docstrings, as click would write it from the loaded commands."""
        names = self.list_commands(ctx)
        limit = formatter.width - 6 - max(len(n) for n in names)
        cmds = [self.commands.get(n) or click.Command(n, help=command_help(n)) for n in names]
        rows = [(n, c.get_short_help_str(limit)) for n, c in zip(names, cmds)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except InputError as exc:
            click.echo(f"patchgen: {_one_line(_named_by_option(self.commands.get(ctx.invoked_subcommand), exc))}",
                       err=True)
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
    patchgen design SPEC              LQR / Kalman / LTR design and its margins
    patchgen patch SPEC -o DIR        netlist, pot table, patch sheet, wiring
    patchgen check SPEC --readings F  static check readings: agree, or the fault
    patchgen simulate SPEC --scenario X -o DIR    the patched circuit on the bench
    patchgen spice SPEC --scenario X -o DIR       the patch checked by ngspice
    patchgen export SPEC --machine lucidac -o DIR the LUCIDAC's configuration
    patchgen recommend SPEC -o DIR    every realisation on the bench, the best
    patchgen swingup SPEC -o DIR      pump-up, hand-off, hold with the patch
    patchgen sweep SPEC               gains, margins, pots with parameters off 10%
    patchgen bench-test SPEC -o DIR   recordings of the standard bench tests
    patchgen identify DIR -o OUT      bench profile and plant from recordings
    patchgen examples DIR             the shipped designs and scenarios to edit

    \b
    SPEC is a TOML file or a shipped design by name (bench-recommended,
    thesis-ch5, thesis-case1, ...); --scenario likewise (hold-120s, ...);
    --machine another machine than the spec's (gp6, the-analog-thing,
    lucidac, or a machine profile's TOML file).
    """


def _named_by_option(command: click.Command | None, exc: InputError) -> str:
    """The error's line, a run-plan field it names (``runs``) given as the command's option that
    set it (``--runs``): the library speaks of its plans, the user of the options they typed."""
    for p in command.params if command is not None else ():
        if isinstance(p, click.Option) and p.name == exc.source and not exc.field:
            return InputError(max(p.opts, key=len), "", exc.message).line()
    return exc.line()


def _one_line(text: str) -> str:
    return " ".join(text.splitlines())


def main() -> None:
    """Run the CLI; a usage error (bad option, missing argument) or bad input anywhere is one line
    on stderr and exit 2. Anything else is a bug, and its traceback shows."""
    gc.set_threshold(GC_FIRST_THRESHOLD, *gc.get_threshold()[1:])
    atexit.unregister(gc.freeze)  # once, however often main() runs in one process
    atexit.register(gc.freeze)
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
