"""The residual checks say when the data reject the model: a second-order actuator, a zero at the
origin, Coulomb friction on the track, hysteresis in the dead zone. Each is shown on recordings
made with that effect, and shown silent on recordings without it."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from patchgen.identify.actuator import fit_ramp, fit_step
from patchgen.identify.benchtest import bench_test_files
from patchgen.identify.friction import fit_coast
from patchgen.identify.recording import parse_recording
from patchgen.profiles.machine import load_machine
from tests.identify.benches import TRUE_PLANT, csv, true_bench

DT = 0.005
RNG = np.random.default_rng(7)


def check(fit, name: str):
    return next(c for c in fit.checks if c.name == name)


def recorded(tmp_path, name: str, seed: int = 3, **actuator):
    files = bench_test_files(TRUE_PLANT, true_bench(**actuator), load_machine("gp6"), seed)
    return parse_recording(files[name].decode(), name)


def _dead(u, dz):
    return np.where(u > dz, u - dz, np.where(u < -dz, u + dz, 0.0))


def _lag(x, tau):
    a = np.exp(-DT / tau)
    return lfilter([1 - a], [1, -a], x)


def _step_command() -> np.ndarray:
    levels = [0.0]
    for f in (0.4, 0.6, 0.8, 1.0):
        levels += [f * 1.3, 0.0, -f * 1.3, 0.0]
    return np.repeat(levels, int(2.4 / DT))


def test_a_first_order_actuator_passes_every_check(tmp_path):
    fit = fit_step(recorded(tmp_path, "actuator-step.csv"))
    assert check(fit, "zero at the origin").rejected  # a steady force: the data reject a zero
    assert not check(fit, "first order").rejected and not check(fit, "same gain both ways").rejected
    assert "model: lag" in fit.notes


def test_a_second_order_actuator_is_rejected_as_first_order(tmp_path):
    u = _step_command()
    f = 11.0 * _lag(_lag(_dead(u, 0.35), 0.25), 0.08) + 0.05 * RNG.standard_normal(u.size)
    rec = parse_recording(csv(tmp_path / "s.csv", "actuator_step", {"t_s": np.arange(u.size) * DT, "u_c_V": u,
                                                                     "force_N": f}).read_text(), "s.csv")
    c = check(fit_step(rec), "first order")
    assert c.rejected and "second lag" in c.text


def test_a_zero_at_the_origin_is_found(tmp_path):
    fit = fit_step(recorded(tmp_path, "actuator-step.csv", model="lag_zero"))
    assert not check(fit, "zero at the origin").rejected  # no steady force: the data support the zero
    assert "model: lag_zero" in fit.notes


def test_hysteresis_is_seen_only_when_there(tmp_path):
    plain = fit_ramp(recorded(tmp_path, "actuator-ramp.csv"))
    assert not check(plain, "hysteresis").rejected
    rec = recorded(tmp_path, "actuator-ramp.csv")
    u = rec.columns["u_c_V"]
    up = np.concatenate([[True], np.diff(u) >= 0])
    shifted = np.where(up, u - 0.06, u + 0.06)  # the edges move 0.06 V against the travel
    f = 11.0 * _lag(_dead(shifted, 0.35), 0.3) + 0.05 * RNG.standard_normal(u.size)
    hyst = fit_ramp(parse_recording(csv(tmp_path / "h.csv", "actuator_ramp", {
        "t_s": rec.columns["t_s"], "u_c_V": u, "force_N": f}).read_text(), "h.csv"))
    assert check(hyst, "hysteresis").rejected
    assert hyst.estimates["hysteresis"].covers(0.12) or hyst.estimates["hysteresis"].covers(-0.12)


@pytest.mark.parametrize("coulomb_N", [0.0, 1.5])
def test_coulomb_friction_is_seen_only_when_there(tmp_path, coulomb_N):
    mass, b, k_s, k_v = 3.876, 3.5, 4.5, 0.62
    n = int(5.0 / DT)
    v = np.empty(n)
    v[0] = 0.8
    a, f = b / mass, coulomb_N / mass
    for i in range(1, n):  # the cart coasting from 0.8 m/s, viscous and Coulomb friction, exact steps
        v[i] = max((v[i - 1] + f / a) * np.exp(-a * DT) - f / a, 0.0) if v[i - 1] > 0 else 0.0
    s = -0.45 + np.concatenate([[0.0], np.cumsum(v[:-1]) * DT])
    t = np.arange(n) * DT
    rec = parse_recording(csv(tmp_path / "c.csv", "coast_down", {
        "t_s": t, "s_V": k_s * s + 0.002 * RNG.standard_normal(n),
        "s_dot_V": k_v * v + 0.005 * RNG.standard_normal(n)}).read_text(), "c.csv")
    fit = fit_coast(rec, 5.0)
    assert check(fit, "Coulomb friction").rejected == (coulomb_N > 0)
    assert fit.estimates["decay"].covers(b / mass)
