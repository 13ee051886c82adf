"""--machine: another machine than the spec's, by shipped id or profile file, for every command that
patches; the spec's machine field replaced, so every later stage (and a spec written from it)
names it; a bad value is one line naming the option, exit 2."""

from __future__ import annotations

import json
import shutil

import click
import pytest

from patchgen.cli import cli
from patchgen.inputs.resources import folder
from patchgen.pipeline.inputs import load_inputs
from tests.cli_run import run_patchgen

PATCHING = ("design", "patch", "check", "simulate", "spice", "recommend", "swingup", "sweep")


@pytest.mark.parametrize("name", PATCHING)
def test_every_command_that_patches_takes_it(name):
    cmd = cli.get_command(click.Context(cli), name)
    assert any("--machine" in p.opts for p in cmd.params)


def test_patch_on_the_analog_thing(tmp_path):
    r = run_patchgen("patch", "bench-recommended", "--machine", "the-analog-thing", "--no-predict",
                     "-o", tmp_path / "tat", env={"COLUMNS": "80"})
    assert r.returncode == 0, r.stderr
    net = json.loads((tmp_path / "tat" / "netlist.json").read_text())
    assert net["machine_name"] == "THE ANALOG THING"
    assert "Pot settings for bench-recommended on THE ANALOG THING" in r.stdout
    gp6 = run_patchgen("patch", "bench-recommended", "--no-predict", "-o", tmp_path / "gp6")
    assert gp6.returncode == 0, gp6.stderr
    assert json.loads((tmp_path / "gp6" / "netlist.json").read_text())["machine_name"] != net["machine_name"]


def test_design_by_a_profile_file(tmp_path):
    shutil.copy(folder("machine").joinpath("the-analog-thing.toml"), tmp_path / "mine.toml")
    by_id = run_patchgen("design", "thesis-ch5", "--machine", "the-analog-thing", "--json")
    by_path = run_patchgen("design", "thesis-ch5", "--machine", "mine.toml", "--json", cwd=tmp_path)
    assert by_id.returncode == by_path.returncode == 0, by_path.stderr
    assert json.loads(by_id.stdout) == json.loads(by_path.stdout)


def test_the_spec_names_the_machine_chosen(tmp_path):
    assert load_inputs("thesis-ch5", machine="the-analog-thing").spec.machine == "the-analog-thing"
    shutil.copy(folder("machine").joinpath("gp6.toml"), tmp_path / "mine.toml")
    got = load_inputs("thesis-ch5", machine=str(tmp_path / "mine.toml"))
    assert got.spec.machine == str(tmp_path / "mine.toml") and got.machine.id == "gp6"


@pytest.mark.parametrize("value, says", [
    ("nope", "unknown machine 'nope' (known: gp6, lucidac, the-analog-thing)"),
    ("nope.toml", "no machine profile file 'nope.toml'"),
    ("", "unknown machine ''"),
])
@pytest.mark.parametrize("command", [("design", "thesis-ch5"), ("patch", "thesis-ch5", "-o", "out")])
def test_a_bad_machine_is_one_line_naming_the_option(tmp_path, command, value, says):
    r = run_patchgen(*command, "--machine", value, cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.splitlines() == [r.stderr.strip()] and r.stderr.startswith("patchgen: --machine: ")
    assert says in r.stderr
    assert not (tmp_path / "out").exists()
