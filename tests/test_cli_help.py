"""`patchgen --help` and --version load no command: its list comes from SUMMARIES, kept equal to
what click would write from the commands themselves."""

import subprocess
import sys

import click
import pytest

from patchgen.cli import COMMANDS, SUMMARIES, cli

HEAVY = ("numpy", "scipy", "numba", "matplotlib", "schemdraw", "pydantic", "rich", "jinja2", "control")


@pytest.mark.parametrize("name", COMMANDS)
def test_summary_is_the_commands_own_short_help(name):
    cmd = cli.get_command(click.Context(cli), name)
    for limit in range(20, 400, 7):
        assert click.Command(name, help=SUMMARIES[name]).get_short_help_str(limit) == cmd.get_short_help_str(limit)


@pytest.mark.parametrize("args", [["--help"], ["--version"]])
def test_help_and_version_import_nothing_heavy(args):
    code = ("import sys\nfrom patchgen.cli import main\nsys.argv = ['patchgen', *sys.argv[1:]]\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            f"print('LOADED', sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))")
    r = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[-1] == "LOADED []"
    if args == ["--help"]:
        for name in COMMANDS:
            assert f"\n  {name} " in r.stdout
