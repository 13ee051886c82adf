"""patchgen swingup through its pipeline function: the report's summary is manoeuvre.json and
--json, and its verdicts are the manoeuvre's own."""

from __future__ import annotations

import json

from patchgen.inputs.spec import load_spec
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.swingup import SwingupPlan, run_swingup
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from tests.cli_run import run_patchgen


def test_the_report_holds_the_manoeuvre_and_its_verdicts():
    spec = load_spec("bench-recommended")
    report = run_swingup(Inputs(spec, load_machine(spec.machine), load_bench(spec.bench)), SwingupPlan(hold_s=5.0))
    s = report.summary()
    m = report.manoeuvre
    assert s["reached_zone"] == m.pump.reached and s["held"] == m.held and s["hold_s"] == 5.0
    assert s["force_limit_N"] == load_bench(spec.bench).actuator.force_limit_N  # the bench's, unless given
    assert s["track_half_m"] == spec.plant.d / 2 and "comparison" not in s
    assert s["switching_table"] == m.pump.table_rows() and s["switching_table"][-1]["phase"] is None  # hand-off


def test_manoeuvre_json_is_the_printed_json(tmp_path):
    r = run_patchgen("swingup", "bench-recommended", "--hold", "5", "--json", "-o", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == json.loads((tmp_path / "o" / "manoeuvre.json").read_text())


def _said(report, inputs) -> tuple[dict, str, str]:
    """What the report says: manoeuvre.json, the patch sheet (Markdown) and the terminal."""
    from rich.console import Console

    from patchgen.render.swingup_view import print_swingup, swingup_files

    files = swingup_files(report, inputs.machine, inputs.bench, svg=False)
    console = Console(record=True, width=200)
    print_swingup(report, [], console)
    return json.loads(files["manoeuvre.json"]), files["patch-sheet.md"], console.export_text()


def test_the_schedule_says_when_its_optimiser_kept_the_seed():
    from dataclasses import replace

    spec = load_spec("bench-recommended")
    inputs = Inputs(spec, load_machine(spec.machine), load_bench(spec.bench))
    report = run_swingup(inputs, SwingupPlan(strategy="schedule", hold_s=3.0))
    pump = report.manoeuvre.pump
    assert pump.notes["kept_seed"]  # on this design the supervisory table is already the quickest near it
    assert all(r["reason"] == "seed" for r in pump.table_rows() if r["phase"] is not None)
    s, sheet, said = _said(report, inputs)
    assert s["schedule"]["kept_seed"] and "optimiser kept its seed" in s["schedule"]["note"]
    assert "Pump-up schedule (schedule, 15 N): the optimiser kept its seed" in sheet
    assert "optimiser kept its seed" in " ".join(said.split())
    # the same run, had the optimiser moved the switches: no note anywhere
    moved = replace(pump, notes={**pump.notes, "kept_seed": False, "kept_seed_note": None, "optimised": True})
    report = replace(report, manoeuvre=replace(report.manoeuvre, pump=moved))
    s, sheet, said = _said(report, inputs)
    assert not s["schedule"]["kept_seed"] and "note" not in s["schedule"]
    assert "kept its seed" not in sheet and "kept its seed" not in said
    assert "Pump-up schedule (schedule, 15 N)" in sheet


def test_other_strategies_have_no_schedule_note():
    spec = load_spec("bench-recommended")
    inputs = Inputs(spec, load_machine(spec.machine), load_bench(spec.bench))
    report = run_swingup(inputs, SwingupPlan(hold_s=3.0))
    s, sheet, said = _said(report, inputs)
    assert "schedule" not in s and report.schedule_note is None
    assert "kept its seed" not in sheet and "kept its seed" not in said
