"""bench-test and identify on a rotary pendulum's bench (the shipped QUBE-Servo 2): seven
recordings, the same bytes for the same seed; identify recovers the motor (R_m, k_t = k_m), the
dampings (D_r, D_p) and the pendulum's inertia (J_p) inside their 95 % intervals in at least 90 %
of seeds; its bench.toml is a rotary bench whose [measured_plant] the bench simulates and its
plant.toml a spec's [plant]; a cart's test on it, or its tests on a cart's bench, is one line; a
motor whose constants differ fails the check that the step and the coasts agree on D_r."""

from __future__ import annotations

import json
import tomllib

import pytest

from patchgen.design.model import plant_params
from patchgen.identify.identify import identify
from patchgen.identify.rotary_benchtest import ROTARY_FILES
from patchgen.inputs.resources import resolve
from patchgen.pipeline.identify import run_bench_test
from patchgen.pipeline.inputs import load_inputs
from patchgen.profiles.bench import load_bench
from patchgen.profiles.measured_plant import as_on_bench
from tests.conftest import run_patchgen

pytestmark = pytest.mark.heavy(90)  # seconds, roughly: see tests/conftest.py
SEEDS = range(40)  # 95 % intervals: at 90 % required, 40 seeds leave room for the chance misses
FIGURES = ("R_m", "k_t", "k_m", "D_r", "D_p", "J_p")  # the motor, the friction, the pendulum


def _write(folder, recordings: dict[str, bytes]) -> str:
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in recordings.items():
        (folder / name).write_bytes(data)
    return str(folder)


@pytest.fixture(scope="module")
def qube():
    inputs = load_inputs("qube-servo-2", command="bench-test")
    return inputs, as_on_bench(plant_params(inputs.spec), inputs.bench)


def _truth(plant) -> dict[str, float]:
    return {"R_m": plant.R_m, "k_t": plant.k_t, "k_m": plant.k_m, "D_r": plant.D_r, "D_p": plant.D_p,
            "J_p": plant.pendulum_inertia()}


@pytest.fixture(scope="module")
def identified(qube, tmp_path_factory):
    inputs, _ = qube
    top = tmp_path_factory.mktemp("qube-seeds")
    return [identify([_write(top / str(s), run_bench_test(inputs, s).recordings)]) for s in SEEDS]


def test_bench_test_writes_the_rotary_s_seven_recordings_the_same_for_the_same_seed(qube):
    inputs, plant = qube
    first, again, other = (run_bench_test(inputs, s).recordings for s in (3, 3, 4))
    assert tuple(first) == ROTARY_FILES and first == again and first != other
    links = tomllib.loads(first["links.toml"].decode())
    assert links["test"] == "links" and links["m_p_kg"] == pytest.approx(plant.m_p, abs=4 * 0.5e-3)
    assert all(b"# bench = qube-servo-2" in first[f] for f in ROTARY_FILES if f.endswith(".csv"))
    assert plant.D_p == 5e-5  # the bench's measured figure, not the workbook's 5e-4


def test_identify_recovers_the_motor_friction_and_pendulum_inside_their_intervals(qube, identified):
    _, plant = qube
    truth = _truth(plant)
    for name in FIGURES:
        inside = [r.plant[name].estimate.covers(truth[name]) for r in identified]
        assert sum(inside) >= 0.9 * len(SEEDS), (name, sum(inside))
        mid = sorted(r.plant[name].value for r in identified)[len(SEEDS) // 2]
        assert mid == pytest.approx(truth[name], rel=0.15), name  # not a wide interval around a wrong value
        widths = sorted((r.plant[name].estimate.high - r.plant[name].estimate.low) / truth[name] for r in identified)
        assert widths[len(SEEDS) // 2] < 1.5, name  # an interval that says something
    for r in identified:
        assert {"sensors.alpha", "sensors.theta"} <= set(r.bench)
    # each check rejects a right model at 1 %: a few false alarms over 40 seeds' checks, not many
    alarms = [c.text for r in identified for c in r.checks if c.rejected]
    assert len(alarms) <= 0.1 * len(SEEDS), alarms


def test_the_identified_bench_and_plant_are_taken_by_every_command(qube, tmp_path):
    inputs, plant = qube
    rec = _write(tmp_path / "rec", run_bench_test(inputs, 1).recordings)
    r = run_patchgen("identify", rec, "-o", str(tmp_path / "id"), "--id", "our-qube")
    assert r.returncode == 0, r.stderr
    bench = load_bench(str(tmp_path / "id" / "bench.toml"))
    assert bench.plant == "rotary-pendulum" and set(bench.measured_plant) >= set(FIGURES) | {"m_p", "L_p"}
    assert bench.measured_plant["D_p"] == pytest.approx(plant.D_p, rel=0.6)
    table = tomllib.loads((tmp_path / "id" / "plant.toml").read_text())["plant"]
    assert table["model"] == "rotary-pendulum" and table["k_t"] == pytest.approx(plant.k_t, rel=0.1)
    spec = resolve("design", "qube-servo-2").read_text()
    head, _, rest = spec.partition("[plant]")
    rest = rest[rest.index("[sensors]"):]
    plant_lines = "\n".join(f"{k} = {json.dumps(v)}" for k, v in table.items())
    ours = tmp_path / "ours.toml"
    ours.write_text(head.replace('bench = "qube-servo-2"', f'bench = "{tmp_path / "id" / "bench.toml"}"')
                    + "[plant]\n" + plant_lines + "\n\n" + rest)
    r = run_patchgen("simulate", str(ours), "--scenario", "qube-release-5deg", "--runs", "5", "--json",
                     "-o", str(tmp_path / "sim"))
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["distribution"]["fraction_held"] == 1.0


def test_a_motor_whose_constants_differ_fails_the_agreement_on_d_r(qube, tmp_path):
    """k_m four times k_t (a motor voltage recorded at the wrong point, say): the step's D_r
    (a_s J_0 - k_t^2 / R_m) is then k_t (k_m - k_t) / R_m, some 40 %, above the coasts': the check
    that they agree rejects it (identify takes k_m = k_t) and says so. (At k_m = 2 k_t, 14 %, it
    catches about half: the coasts' D_r carries some 16 % each.)"""
    inputs, plant = qube
    bench = inputs.bench.model_copy(update={"measured_plant": {**inputs.bench.measured_plant, "k_m": 4 * plant.k_t}})
    for s in range(3):
        r = identify([_write(tmp_path / str(s), run_bench_test(inputs._replace(bench=bench), s).recordings)])
        assert any(c.rejected for c in r.checks), s
        assert any(w.startswith("D_r from the step and the coasts") for w in r.warnings), r.warnings


@pytest.mark.parametrize("bench, names", [("uw-1991", "motor_step"), ("qube-servo-2", "masses")])
def test_another_plant_s_test_is_one_line(qube, tmp_path, bench, names):
    inputs, _ = qube
    folder = tmp_path / "rec"
    if names == "motor_step":
        recs = run_bench_test(inputs, 0).recordings
        _write(folder, {"motor-step.csv": recs["motor-step.csv"].replace(b"# bench = qube-servo-2\n", b"")})
    else:
        _write(folder, {**run_bench_test(inputs, 0).recordings,
                        "masses.toml": b'test = "masses"\nM_kg = 1.0\nm_kg = 0.1\n'})
    r = run_patchgen("identify", str(folder), "-o", str(tmp_path / "id"), "--base", bench)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert names.replace("_", "") in r.stderr.replace("_", "") and "Traceback" not in r.stderr
    assert not (tmp_path / "id").exists()


def test_the_machine_s_drift_is_read_on_a_rotary_bench_too(qube, tmp_path):
    """integrator_drift is the machine's, recorded beside any bench: a cart bench's recording of it
    is fitted on the rotary's too and reported."""
    inputs, _ = qube
    cart = run_bench_test(load_inputs("bench-recommended", command="bench-test"), 0).recordings
    folder = _write(tmp_path / "rec", {**run_bench_test(inputs, 0).recordings,
                                       "integrator-drift.csv": cart["integrator-drift.csv"]})
    r = identify([folder])
    drift = r.extra["drift_V_per_s"]
    assert drift.value > 0 and drift.low < drift.value < drift.high
    assert any(f.test == "integrator_drift" for f in r.fits) and "D_p" in r.plant
