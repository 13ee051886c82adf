"""What --help tells a new user: the top-level summary names every command and fits 80 columns,
patch names every file it writes, --scenario and --machine name what is shipped."""

from __future__ import annotations

import re

import pytest

from patchgen.cli import COMMANDS
from patchgen.inputs.resources import shipped
from patchgen.render.patchfiles import PATCH_FILES
from tests.cli_run import run_patchgen


def _help(*args) -> str:
    r = run_patchgen(*args, "--help", env={"COLUMNS": "80"})
    assert r.returncode == 0, r.stderr
    return r.stdout


def _words(text: str) -> str:
    """The help as one line, a word click broke at its hyphen joined again."""
    return re.sub(r"(?<=\w)- ", "-", " ".join(text.split()))


def test_the_summary_names_every_command_and_fits_80_columns():
    text = _help()
    summary = text[text.index("patchgen design"):text.index("Options:")]
    for name in COMMANDS:
        assert f"patchgen {name} " in summary, name
    assert "--machine" in summary
    assert max(len(line) for line in text.splitlines()) <= 80


@pytest.mark.parametrize("name", COMMANDS)
def test_every_help_fits_80_columns(name):
    assert max(len(line) for line in _help(name).splitlines()) <= 80


def test_patch_names_every_file_it_writes():
    text = _words(_help("patch"))
    for f in PATCH_FILES:
        assert f in text, f


@pytest.mark.parametrize("name", ["simulate", "spice"])
def test_scenario_and_machine_name_what_is_shipped(name):
    text = _words(_help(name))
    for sc in shipped("scenario"):
        assert sc in text
    for m in shipped("machine"):
        assert m in text


@pytest.mark.parametrize("folder", ["out", "."])
def test_the_command_examples_suggests_runs_after_the_readmes_first(tmp_path, folder):
    """README: `patchgen patch bench-recommended -o out/` first; examples' suggestion then still runs."""
    assert run_patchgen("patch", "bench-recommended", "-o", "out/", "--no-predict", cwd=tmp_path).returncode == 0
    r = run_patchgen("examples", folder, cwd=tmp_path, env={"COLUMNS": "80"})
    assert r.returncode == 0, r.stderr
    suggested = r.stdout.split("try:", 1)[1].split()
    assert suggested[:2] == ["patchgen", "patch"]
    again = run_patchgen(*suggested[1:], "--no-predict", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
