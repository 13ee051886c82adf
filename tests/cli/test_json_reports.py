"""Every verdict a command prints is in its --json: the design's notes and actuator, the patch's
bench prediction and margins as patched, bench-test's and examples' files. (simulate, spice,
swingup, recommend, identify and check have their own tests of the same.)"""

from __future__ import annotations

import json

from click.testing import CliRunner

from patchgen.cli import cli
from patchgen.inputs.spec import load_spec


def _run(*argv):
    r = CliRunner().invoke(cli, list(argv))
    return r, json.loads(r.stdout) if "--json" in argv and r.exit_code == 0 else None


def test_design_json_carries_the_actuator_and_the_notes_it_prints():
    text, _ = _run("design", "bench-recommended")
    r, got = _run("design", "bench-recommended", "--json")
    assert r.exit_code == 0, r.output
    actuator = load_spec("bench-recommended").actuator  # the figures as the spec states them
    assert got["actuator_K_U"] == actuator.K_U and got["actuator_tau_s"] == actuator.tau
    assert f"K_U = {got['actuator_K_U']} N/V, tau = {got['actuator_tau_s']} s" in text.output
    assert len(got["notes"]) == 1 and f"dead zone ({actuator.dead_zone_V} V)" in got["notes"][0]
    _, gain_only = _run("design", "thesis-ch5", "--json")
    assert gain_only["notes"] == [] and gain_only["actuator_tau_s"] is None


def test_patch_json_carries_the_prediction_the_sheet_shows(tmp_path):
    r, got = _run("patch", "bench-recommended", "-o", str(tmp_path / "p"), "--runs", "2", "--json")
    assert r.exit_code == 0, r.output
    pred = got["prediction"]
    sheet = (tmp_path / "p" / "patch-sheet.md").read_text()
    assert pred["runs_hold"] == 2 and [s["name"] for s in pred["scenarios"]][-1] == "hold-120s"
    for s in pred["scenarios"]:  # each row of the sheet's table, figure for figure
        assert f"| {s['name']} | {s['runs']} | {100 * s['fraction_held']:.0f} % |" in sheet
    assert pred["holds"] == all(s["fraction_held"] >= 0.95 for s in pred["scenarios"])
    assert [lp["verdict"] for lp in pred["linear"]] == ["stable", "stable"]
    assert all(lp["line"] in sheet for lp in pred["linear"])
    written = json.loads((tmp_path / "p" / "margins.json").read_text())
    assert got["margins"] == {k: v for k, v in written.items() if k not in ("design", "schema")}
    _, bare = _run("patch", "bench-recommended", "-o", str(tmp_path / "q"), "--no-predict", "--json")
    assert bare["prediction"] is None
    assert "Predicted on the bench" not in (tmp_path / "q" / "patch-sheet.md").read_text()


def test_bench_test_and_examples_json_name_what_they_wrote(tmp_path):
    r, got = _run("bench-test", "thesis-ch5", "-o", str(tmp_path / "rec"), "--seed", "3", "--json")
    assert r.exit_code == 0, r.output
    assert (got["spec"], got["bench"], got["seed"]) == ("thesis-ch5", "uw-1991", 3)
    assert sorted(got["written"]) == sorted(str(p) for p in (tmp_path / "rec").iterdir())
    r, got = _run("examples", str(tmp_path / "ex"), "--json")
    assert r.exit_code == 0, r.output
    assert "bench-recommended" in got["copied"]["designs"] and "hold-120s" in got["copied"]["sims"]
    assert len(got["written"]) == sum(1 for p in (tmp_path / "ex").rglob("*") if p.is_file())
