"""patchgen simulate through its pipeline function: the report holds every verdict the command
prints, summary.json and --json carry the same, and the linear verdicts are the diagnosis's."""

from __future__ import annotations

import json

import pytest

from patchgen.bench.diagnosis import diagnose
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.simulate import SimulatePlan, run_simulate
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from tests.cli_run import run_patchgen as run


@pytest.fixture(scope="module")
def inputs():
    spec = load_spec("thesis-ch5")
    return spec, load_machine(spec.machine), load_bench(spec.bench)


def test_the_report_carries_the_linear_verdicts(inputs):
    spec, machine, bench = inputs
    report = run_simulate(Inputs(spec, machine, bench), load_scenario("finger-push"), SimulatePlan(runs=3))
    d = design_on(spec, machine, bench)
    want = diagnose(build_patch(d, machine), plant_params(d.spec), bench)
    summary = report.summary()
    assert [x["verdict"] for x in summary["linear"]] == [lp.verdict for lp in want]
    assert "MARGINAL" in summary["linear"][0]["line"] and summary["linear"][0]["conserved"]  # thesis-ch5's int theta
    assert summary["linear_notes"] and "dead zone" in summary["linear_notes"][0]
    assert summary["distribution"]["runs"] == 3 and len(report.result.runs) == 3


def test_a_bench_spread_without_ranges_is_refused(inputs):
    spec, machine, bench = inputs
    with pytest.raises(InputError, match="no \\[uncertainty\\] ranges"):
        run_simulate(Inputs(spec, machine, bench), load_scenario("finger-push"), SimulatePlan(bench_spread=True))


def test_summary_json_and_json_output_are_the_report(tmp_path):
    r = run("simulate", "bench-recommended", "--scenario", "finger-push", "--runs", "4", "--json",
            "-o", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    printed = json.loads(r.stdout)
    written = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert printed == written and [x["verdict"] for x in printed["linear"]] == ["stable", "stable"]
