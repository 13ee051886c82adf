"""The QUBE-Servo 2's arm identified from its encoder: simulated motor steps and coast-downs, read in
whole counts, fitted, and held to their intervals over many seeds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from patchgen.identify import encoder_coast, rotary_motor
from patchgen.identify.recording import Recording
from patchgen.inputs.errors import InputError

PER_RAD = 2048 / (2 * math.pi)  # the QUBE's encoders: 2048 counts a turn
BANDWIDTH_HZ = 5.0  # the random torque's band (the bench profile's)
ACCEL_RMS = 5e-4 / 4.0e-4  # rad/s^2: 0.5 mN m rms on the arm's 4e-4 kg m^2
RATE_HZ, SUBSTEPS = 200.0, 5  # recorded at 200 Hz, simulated at 1 kHz
A_DRIVEN, K_MOTOR = 4.25, 12.4  # 1/s and rad/s^2/V: (D_r + k_t k_m / R_m) / J and k_t / (R_m J)
A_FREE = 3.73  # 1/s: D_r / J with the amplifier disabled
SEEDS = 30
MIN_COVERED = 27  # of SEEDS: 95 % intervals, 90 % allowed for the draw


def simulate(a: float, accel: np.ndarray, rng: np.random.Generator, accel_rms: float = ACCEL_RMS) -> np.ndarray:
    """The arm's angle at each sample, from rest at 0: alpha'' = -a alpha' + accel + d, accel held from each
    sample to the next, d an Ornstein-Uhlenbeck process relaxing at 4 x BANDWIDTH_HZ held per sub-step;
    each sub-step exact for what it holds."""
    h = 1.0 / (RATE_HZ * SUBSTEPS)
    memory = math.exp(-4.0 * BANDWIDTH_HZ * h)
    kicks = accel_rms * math.sqrt(1 - memory * memory) * rng.standard_normal(accel.size * SUBSTEPS)
    d = accel_rms * rng.standard_normal()
    decay, lag = math.exp(-a * h), -math.expm1(-a * h) / a
    z = v = 0.0
    out = np.empty(accel.size)
    for i, f in enumerate(accel):
        out[i] = z
        for j in range(SUBSTEPS):
            top = (f + d) / a
            z += top * h + (v - top) * lag
            v = top + (v - top) * decay
            d = memory * d + kicks[i * SUBSTEPS + j]
    return out


def read(z: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The encoder's whole counts, its zero anywhere within a count."""
    return np.round(z * PER_RAD + rng.uniform(-0.5, 0.5))


def motor_step(seed: int, recorded: float = 1.0, accel_rms: float = ACCEL_RMS) -> Recording:
    """20 s of a +/-1.5 V square wave at 1 Hz; the voltage written ``recorded`` x what drove the arm."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(20 * RATE_HZ)) / RATE_HZ
    volts = np.where(t % 1.0 < 0.5, 1.5, -1.5)
    z = simulate(A_DRIVEN, K_MOTOR * volts, rng, accel_rms)
    return Recording(f"step-{seed}.csv", "motor_step", {"t_s": t, "V_m_V": recorded * volts,
                                                        "alpha_counts": read(z, rng)})


def arm_coast(seed: int) -> Recording:
    """At rest, spun by hand for 0.3 s to some 4 rad/s, then 2 s of coasting."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(2.5 * RATE_HZ)) / RATE_HZ
    hand = np.where((t >= 0.2) & (t < 0.5), 22.0, 0.0)
    return Recording(f"coast-{seed}.csv", "arm_coast", {"t_s": t, "alpha_counts": read(simulate(A_FREE, hand, rng),
                                                                                         rng)})


def half_width(e) -> float:
    """An interval's half-width relative to its value."""
    return (e.high - e.low) / (2 * abs(e.value))


def _plain_filter(z, u, dt, a, k, lam, q, r, z0, v0) -> float:
    """The same likelihood written plainly (scipy's expm, Van Loan's noise, matrix products): an
    independent oracle for the compiled filter."""
    F = np.array([[0.0, 1.0, 0.0], [0.0, -a, 1.0], [0.0, 0.0, -lam]])
    G = np.array([0.0, 1.0, 0.0])
    aug = np.zeros((4, 4))
    aug[:3, :3], aug[:3, 3] = F, G
    E = expm(aug * dt)
    Phi, c = E[:3, :3], E[:3, 3]
    W = np.diag([0.0, 0.0, q])
    van = expm(np.block([[-F, W], [np.zeros((3, 3)), F.T]]) * dt)
    Q = van[3:, 3:].T @ van[:3, 3:]
    x, P = np.array([z0, v0, 0.0]), np.diag([0.0, 0.0, q / (2 * lam)])
    total = 0.0
    for zt, ut in zip(z, u):
        s = P[0, 0] + r
        e = zt - x[0]
        total += 0.5 * (math.log(s) + e * e / s)
        K = P[:, 0] / s
        x, P = x + K * e, P - np.outer(K, P[0])
        x, P = Phi @ x + c * k * ut, Phi @ P @ Phi.T + Q
    return total


def test_the_compiled_filter_is_the_plain_one_and_a_coast_is_its_constant_input():
    rng = np.random.default_rng(1)
    z = np.cumsum(rng.normal(0, 0.01, 300))
    pred, terms = np.empty(z.size), np.empty(z.size)
    u = np.sign(np.sin(np.arange(z.size) * 0.05))
    for k, drive in ((12.4, u), (0.0, u), (-0.7, np.ones(z.size))):
        driven = encoder_coast.driven_nll(z, drive, 0.005, 4.0, k, 20.0, 3.0, 1e-5, 0.01, 0.2, pred, terms)
        assert driven == pytest.approx(_plain_filter(z, drive, 0.005, 4.0, k, 20.0, 3.0, 1e-5, 0.01, 0.2), rel=1e-9)
    coast = encoder_coast.position_nll(z, 0.005, 4.0, 0.7, 20.0, 3.0, 1e-5, 0.01, 0.2, terms)
    assert coast == pytest.approx(_plain_filter(z, -0.7 * np.ones(z.size), 0.005, 4.0, 1.0, 20.0, 3.0, 1e-5, 0.01,
                                                0.2), rel=1e-9)


def test_motor_step_intervals_hold_the_truth_and_are_narrow():
    fits = [rotary_motor.fit_motor_step(motor_step(seed), PER_RAD, BANDWIDTH_HZ) for seed in range(SEEDS)]
    a, k = [f.estimates["a"] for f in fits], [f.estimates["k"] for f in fits]
    assert sum(e.covers(A_DRIVEN) for e in a) >= MIN_COVERED
    assert sum(e.covers(K_MOTOR) for e in k) >= MIN_COVERED
    assert np.median([half_width(e) for e in a]) < 0.05
    assert np.median([half_width(e) for e in k]) < 0.03
    assert (a[0].unit, k[0].unit) == ("1/s", "rad/s^2/V")
    panel = fits[0].panels[0]
    assert panel.fitted.shape == panel.measured.shape == (int(20 * RATE_HZ),)


def test_a_voltage_recorded_a_fifth_low_is_not_hidden_in_the_interval():
    for seed in range(5):
        fit = rotary_motor.fit_motor_step(motor_step(100 + seed, recorded=0.8), PER_RAD, BANDWIDTH_HZ)
        assert not fit.estimates["k"].covers(K_MOTOR)
        assert fit.estimates["k"].value == pytest.approx(K_MOTOR / 0.8, rel=0.03)
        assert fit.estimates["a"].value == pytest.approx(A_DRIVEN, rel=0.05)


def test_a_tenfold_random_torque_widens_the_intervals_to_hold_the_truth():
    fits = [rotary_motor.fit_motor_step(motor_step(200 + seed, accel_rms=10 * ACCEL_RMS), PER_RAD, BANDWIDTH_HZ)
            for seed in range(10)]
    for name, truth in (("a", A_DRIVEN), ("k", K_MOTOR)):
        assert sum(f.estimates[name].covers(truth) for f in fits) >= 8
    assert np.median([half_width(f.estimates["a"]) for f in fits]) > 0.05  # 2 % with the bench's own


def test_a_flat_voltage_or_a_still_arm_is_refused():
    rec = motor_step(0)
    flat = Recording("flat.csv", "motor_step", {**rec.columns, "V_m_V": np.full(rec.columns["t_s"].size, 1.5)})
    with pytest.raises(InputError, match="V_m_V"):
        rotary_motor.fit_motor_step(flat, PER_RAD, BANDWIDTH_HZ)
    still = Recording("still.csv", "motor_step", {**rec.columns, "alpha_counts": np.zeros(rec.columns["t_s"].size)})
    with pytest.raises(InputError, match="alpha_counts"):
        rotary_motor.fit_motor_step(still, PER_RAD, BANDWIDTH_HZ)


def test_arm_coast_intervals_hold_the_truth():
    fits = [rotary_motor.fit_arm_coast(arm_coast(seed), PER_RAD, BANDWIDTH_HZ) for seed in range(SEEDS)]
    a = [f.estimates["a"] for f in fits]
    assert sum(e.covers(A_FREE) for e in a) >= MIN_COVERED
    assert np.median([half_width(e) for e in a]) < 0.25
    assert sum("coulomb" in f.estimates for f in fits) <= 2  # a viscous arm: Coulomb friction seen by chance alone
    assert all(f.panels[0].x[0] >= 0.5 for f in fits)  # nothing of the hand's push
