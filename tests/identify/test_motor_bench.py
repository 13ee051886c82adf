"""A Quanser IP02 practised and identified in its own units: bench-test records its encoders in
counts and its filtered velocity as the bench has it, with the motor's back-EMF and rotor on the
coasting cart; identify reads the counts with the profile the recordings name and fits the
motor-driven bench (K_U as the amplifier's gain, b_VF as the total damping less the back-EMF's)."""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest

from patchgen.design.model import plant_params
from patchgen.identify.recording import read_recording
from patchgen.inputs.drive_fields import motor_of
from patchgen.profiles.bench import load_bench
from tests.cli_run import run_patchgen

run = run_patchgen
IP02 = load_bench("quanser-ip02")


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """bench-test on the IP02's design and bench (seed 1), then identify the folder with no --base."""
    tmp = tmp_path_factory.mktemp("ip02")
    r = run("bench-test", "quanser-ip02", "--seed", "1", "-o", str(tmp / "rec"))
    assert r.returncode == 0, r.stderr
    r = run("identify", str(tmp / "rec"), "-o", str(tmp / "fit"), "--json")
    assert r.returncode == 0, r.stderr
    return tmp, json.loads(r.stdout)


def _true_plant():
    from patchgen.pipeline.inputs import load_inputs

    return plant_params(load_inputs("quanser-ip02")[0])


def test_encoders_are_recorded_in_whole_counts_that_read_back(fitted):
    tmp, _ = fitted
    rec = tmp / "rec"
    assert not (rec / "incline.toml").exists()  # B.2 has no rotor and no back-EMF: not recorded on a motor
    per_m, per_rad = IP02.sensors.counts_per_m["s"], IP02.sensors.counts_per_rev["theta"] / (2 * math.pi)
    cal = read_recording(rec / "calibration.csv")
    assert cal.notes["bench"] == "quanser-ip02"
    for ref, col, per in (("s_m", "s_counts", per_m), ("theta_rad", "theta_counts", per_rad)):
        counts = cal.columns[col]
        assert np.array_equal(counts, np.round(counts))
        assert np.max(np.abs(counts / per - cal.columns[ref])) <= 0.5 / per  # the nearest count
    coast = read_recording(rec / "coast-down-1.csv")
    assert set(coast.columns) == {"t_s", "s_counts", "s_dot_V"}
    swing = read_recording(rec / "free-swing.csv")
    assert np.array_equal(swing.columns["theta_counts"], np.round(swing.columns["theta_counts"]))
    # the filtered velocity lags the encoder's rate: a 10 Hz filter, not a tachometer
    t, s = coast.columns["t_s"], coast.columns["s_counts"] / per_m
    rate, v = np.gradient(s, t), coast.columns["s_dot_V"] / IP02.sensors.s_dot
    k = int(np.argmax(np.abs(rate)))
    assert int(np.argmax(np.abs(v))) > k


def test_the_plant_is_recovered_within_its_intervals(fitted):
    _, report = fitted
    true = _true_plant()
    plant = report["plant"]
    assert report["base_profile"] == "quanser-ip02"  # named by the recordings
    for name in ("c", "J"):
        lo, hi = plant[name]["interval_95"]
        assert lo <= getattr(true, name) <= hi, (name, plant[name])
    # the coast-down's damping to 5 % (its own interval is too narrow in about one recording in
    # twenty with the filtered velocity, this seed's among them: a known defect of that fit)
    assert plant["b_VF"]["value"] == pytest.approx(true.b_VF, rel=0.05)
    assert plant["J"]["value"] == pytest.approx(true.J, rel=0.03)
    assert plant["l"]["value"] == true.l and plant["M"]["value"] == true.M
    swing = report["extra"]["swing length L"]
    assert swing["interval_95"][0] <= true.swing_length() <= swing["interval_95"][1]


def test_the_motor_bench_is_recovered_and_reported_honestly(fitted):
    _, report = fitted
    motor = motor_of(IP02.actuator)
    a, b = motor.force_per_volt(), motor.back_emf_damping()
    bench, extra = report["bench"], report["extra"]
    assert bench["actuator.model"]["value"] == "dc_motor"
    assert "actuator.K_U" not in bench and "actuator.force_limit_N" not in bench
    lo, hi = extra["K_U"]["interval_95"]
    assert lo <= a <= hi  # the held cart's force per volt: amp_gain 1 x a
    lo, hi = bench["actuator.amp_gain"]["interval_95"]
    assert lo <= 1.0 <= hi
    true = _true_plant()
    total = extra["damping_total"]
    assert total["value"] == pytest.approx(true.b_VF + b, rel=0.025)  # see the plant's test: not its interval
    assert bench["sensors.s_dot"]["value"] == pytest.approx(IP02.sensors.s_dot, rel=1e-3)
    assert "back-EMF" in report["plant"]["b_VF"]["origin"]
    # this seed's two coast-downs disagree beyond their (too narrow) intervals, and the report says so
    assert any("disagree" in w and "b_VF" in w for w in report["warnings"]), report["warnings"]


def test_the_fitted_profile_loads_as_a_dc_motor_bench(fitted):
    tmp, _ = fitted
    text = (tmp / "fit" / "bench.toml").read_text()
    data = tomllib.loads(text)
    assert "K_U" not in data["actuator"] and "force_limit_N" not in data["actuator"]  # they follow from the motor
    bench = load_bench(str(tmp / "fit" / "bench.toml"))
    assert bench.actuator.model == "dc_motor"
    assert bench.actuator.K_U == pytest.approx(IP02.actuator.K_U, rel=0.01)
    assert bench.actuator.force_limit_N == pytest.approx(bench.actuator.K_U / bench.actuator.amp_gain * 10.0)
    assert bench.sensors.quanta() == IP02.sensors.quanta() and bench.sensors.filters() == IP02.sensors.filters()
    r = run("simulate", "quanser-ip02", "--bench", str(tmp / "fit" / "bench.toml"), "--scenario",
            "ip02-release-5deg", "--bench-spread", "--runs", "2", "-o", str(tmp / "sim"))
    assert r.returncode == 0, r.stderr


def test_counts_on_a_bench_without_encoders_name_the_file_and_column(fitted, tmp_path):
    tmp, _ = fitted
    r = run("identify", str(tmp / "rec" / "free-swing.csv"), "--base", "uw-1991", "-o", str(tmp_path / "out"))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "free-swing.csv: theta_counts:" in lines[0] and "uw-1991" in lines[0], r.stderr
    assert not (tmp_path / "out").exists()
