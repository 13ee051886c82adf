"""A bench profile's ``[measured_plant]``: the bench's own figures replace the spec's in every
bench stage (the kernel, the linear bench loop, the SPICE deck, bench-test, a sweep's rows), the
design keeps the spec's, and a key or value the plant cannot have is one line naming the field."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest
import tomli_w

from patchgen.bench.bench_linear import bench_plant
from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config
from patchgen.design.lqg import design_on
from patchgen.inputs.resources import resolve
from patchgen.inputs.scenario import load_scenario
from patchgen.pipeline.inputs import load_inputs
from patchgen.pipeline.scaling import scaled_patch
from patchgen.pipeline.spice import SpicePlan, spice_job
from patchgen.plant.plant_model import ROTARY
from patchgen.plant.rotary_compiled import rotary_vector
from patchgen.profiles.measured_plant import as_on_bench, measured_words, scaled_measured
from tests.conftest import run_patchgen

BENCH_D_P = 5e-5  # the shipped QUBE bench's measured pendulum damping
SPEC_D_P = 5e-4  # the workbook's, in designs/qube-servo-2.toml


@pytest.fixture(scope="module")
def qube():
    inputs = load_inputs("qube-servo-2", command="patch")
    d = design_on(*inputs)
    return inputs, d, scaled_patch(d, inputs.machine, inputs.bench).netlist


def test_the_design_keeps_the_spec_figure_and_the_bench_has_its_own(qube):
    (spec, machine, bench), d, _ = qube
    assert d.plant.D_p == SPEC_D_P and bench.measured_plant == {"D_p": BENCH_D_P}
    on = as_on_bench(d.plant, bench)
    assert on.D_p == BENCH_D_P and on.m_p == d.plant.m_p and on.L_p == d.plant.L_p
    assert measured_words(d.plant, bench) == ["D_p = 5e-05 (spec 0.0005)"]
    assert as_on_bench(on, bench) == on  # applying it twice changes nothing


def test_the_kernel_and_the_linear_bench_loop_simulate_the_bench_figure(qube):
    (spec, machine, bench), d, net = qube
    circuit = compile_circuit(net, machine, bench)
    cfg, _ = engine_config(circuit, d.plant, bench, machine, load_scenario("qube-release-5deg"))
    np.testing.assert_array_equal(cfg.plant, rotary_vector(as_on_bench(d.plant, bench)))
    assert not np.array_equal(cfg.plant, rotary_vector(d.plant))
    on, spec_only = bench_plant(net, d.plant, bench), bench_plant(net, d.plant, bench.model_copy(
        update={"measured_plant": {}}))
    i = ROTARY.state_names.index("theta_dot")
    # the pendulum's own damping term in A: -D_p / J_2 scaled by the inertia determinant; 10x less on the bench
    ratio = on.A[i, i] / spec_only.A[i, i]
    assert 0.05 < ratio < 0.2


def test_the_spice_deck_carries_the_bench_figure(qube):
    inputs, _, _ = qube
    job = spice_job(inputs, load_scenario("qube-release-5deg"), SpicePlan(ideal=True))
    assert job.plant.D_p == BENCH_D_P
    assert "-5e-05*" in job.deck.text and "-0.0005*" not in job.deck.text


def test_a_sweep_row_puts_the_bench_figure_off_by_its_factor(qube):
    (_, _, bench), _, _ = qube
    assert scaled_measured(bench, {"D_p": 1.1}).measured_plant["D_p"] == pytest.approx(1.1 * BENCH_D_P, rel=1e-12)
    assert scaled_measured(bench, {"m_p": 1.1}) is bench


@pytest.mark.parametrize("table, field, words", [
    ({"D_q": 1e-5}, "measured_plant.D_q", "not a parameter of the rotary-pendulum"),
    ({"D_p": -1e-5}, "measured_plant.D_p", "outside its physical bounds"),
    ({"L_p": 5.0}, "measured_plant.L_p", "outside its physical bounds"),
    ({"D_p": "5e-5"}, "measured_plant.D_p", ""),
    ({"D_p": float("inf")}, "measured_plant.D_p", ""),
])
def test_a_figure_the_plant_cannot_have_is_one_line_naming_it(tmp_path, table, field, words):
    data = tomllib.loads(resolve("bench", "qube-servo-2").read_text())
    data["measured_plant"] = table
    bench = tmp_path / "lab.toml"
    bench.write_text(tomli_w.dumps(data))
    spec = tmp_path / "qube.toml"
    shipped = resolve("design", "qube-servo-2").read_text()
    spec.write_text(shipped.replace('bench = "qube-servo-2"', f'bench = "{bench}"'))
    r = run_patchgen("patch", str(spec), "-o", str(tmp_path / "out"))
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and str(bench) in lines[0] and field in lines[0] and words in lines[0], r.stderr
    assert not (tmp_path / "out").exists()


def test_the_sheet_says_which_figures_the_bench_has_its_own(tmp_path):
    r = run_patchgen("patch", "qube-servo-2", "-o", str(tmp_path / "out"))
    assert r.returncode == 0, r.stderr
    sheet = (tmp_path / "out" / "patch-sheet.md").read_text()
    assert sheet.count("the plant as this bench has it, D_p = 5e-05 (spec 0.0005)") == 1


def test_summary_json_states_the_bench_figures_only_where_a_bench_has_them(tmp_path):
    for spec, scenario, expected in (("qube-servo-2", "qube-tap", {"D_p": BENCH_D_P}), ("bench-recommended",
                                                                                       "offset-10deg", None)):
        out = tmp_path / spec
        r = run_patchgen("simulate", spec, "--scenario", scenario, "--runs", "2", "-o", str(out))
        assert r.returncode == 0, r.stderr
        settings = json.loads((out / "summary.json").read_text())["settings"]
        assert settings.get("measured_plant") == expected
