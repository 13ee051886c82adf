"""What each command loads: `patchgen --help` and --version no command (the list comes from each
command's docstring read from its source, equal to what click would write from the commands
themselves), a design neither the simulator nor the plotting and drawing libraries."""

import subprocess
import sys

import click
import pytest

from patchgen.cli import COMMANDS, cli, command_help

HEAVY = ("numpy", "scipy", "numba", "matplotlib", "schemdraw", "pydantic", "rich", "jinja2", "control")


@pytest.mark.parametrize("name", COMMANDS)
def test_summary_is_the_commands_own_short_help(name):
    cmd = cli.get_command(click.Context(cli), name)
    for limit in range(20, 400, 7):
        assert click.Command(name, help=command_help(name)).get_short_help_str(limit) == cmd.get_short_help_str(limit)


def loaded(*args, cwd=None) -> tuple[str, set[str]]:
    """Run the CLI in a fresh interpreter; its output and the modules it had loaded."""
    code = ("import sys\nfrom patchgen.cli import main\nsys.argv = ['patchgen', *sys.argv[1:]]\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\nprint('LOADED', *sorted(sys.modules))")
    r = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, cwd=cwd)
    assert r.returncode == 0, r.stderr
    out, last = r.stdout.rsplit("LOADED", 1)
    return out, set(last.split())


@pytest.mark.parametrize("args", [["--help"], ["--version"]])
def test_help_and_version_import_nothing_heavy(args):
    out, mods = loaded(*args)
    assert not {m.split(".")[0] for m in mods} & set(HEAVY)
    if args == ["--help"]:
        for name in COMMANDS:
            assert f"\n  {name} " in out


def test_design_loads_neither_the_simulator_nor_plotting():
    _, mods = loaded("design", "bench-recommended", "--json")
    assert not mods & {"numba", "matplotlib", "schemdraw", "jinja2", "scipy.optimize", "control"}


def test_patch_without_prediction_loads_no_simulator_and_no_matplotlib(tmp_path):
    """A spec that keeps its sensor constants simulates nothing without the prediction; one scaled
    for signal-to-noise (the default) simulates its envelope, and solves for its scales, even then."""
    from tests.conftest import design_path

    spec = tmp_path / "sensors.toml"
    spec.write_text(design_path("bench-recommended").read_text() + '\n[patch]\nscaling = "sensors"\n')
    _, mods = loaded("patch", str(spec), "-o", str(tmp_path / "p"), "--no-predict")
    assert "schemdraw" in mods
    assert not mods & {"numba", "matplotlib", "scipy.optimize", "control"}
    _, mods = loaded("patch", "bench-recommended", "-o", str(tmp_path / "q"), "--no-predict")
    assert {"numba", "scipy.optimize"} <= mods and not mods & {"matplotlib", "control"}
