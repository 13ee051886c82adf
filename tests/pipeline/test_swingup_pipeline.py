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
