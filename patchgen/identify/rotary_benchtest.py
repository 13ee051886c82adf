"""Recordings of every standard test of a rotary pendulum's bench (a QUBE-Servo 2, say), as a lab
records them: the links weighed and measured and the motor's resistance read (links.toml), the
encoders' analog outputs against protractor marks (calibration.csv), a motor step with the
pendulum fixed to the arm (motor-step.csv), two coast-downs of the arm with the amplifier off
(arm-coast-1.csv, arm-coast-2.csv), the pendulum's free swing with the arm clamped
(free-swing.csv), and the sensors at rest (quiet.csv). docs/identify.md gives each procedure.

The motions are the plant's own equations (patchgen.plant.rotary_equations) with the bench's
random torque on the arm and force at the pendulum's tip; encoders read whole counts. Recording i
of seed N draws from ``numpy.random.default_rng([N, i])``: the same seed gives the same bytes.
"""

from __future__ import annotations

import math

import numpy as np

from patchgen.identify import motion
from patchgen.identify.benchtest import DYNAMIC_DT_S, FINE_STEPS, QUIET_SAMPLES, _csv, _toml, quiet_step
from patchgen.identify.figures import ASSUMED_LENGTH_UNCERTAINTY_M, ASSUMED_MASS_UNCERTAINTY_KG
from patchgen.plant.rotary_equations import RotaryParams, generalised_forces, inertias, potential_gradient
from patchgen.plant.rotary_pendulum import MEASURED
from patchgen.profiles.bench import BenchProfile

OHMMETER_FRACTION = 0.01  # the ohmmeter's standard uncertainty, a fraction of its reading (assumed)
STEP_VOLTS = 1.5  # V: the motor step's level, +/-: the arm turns about +/-1 rad, well inside the cable
STEP_HALF_PERIOD_S = 0.5  # s: a square wave of 1 Hz, two arm time constants a level
STEP_DURATION_S = 20.0
COAST_SPEED = 6.0  # rad/s: the hand's spin before the arm coasts (1.6 rad of coast on a QUBE, inside the cable)
COAST_PUSH_S = 0.1  # s: how long the hand pushes
COAST_DECAYS = 8.0  # the coast is recorded for this many of its time constants (the random torque keeps it wandering)
SWING_ANGLE_DEG = 30.0  # the release, from hanging: a QUBE's light pendulum is pushed about by the random force
# at the tip, and a larger swing stands out of it (15 deg gave D_p intervals that held the truth in 85 % of seeds)
SWING_DURATION_S = 30.0  # about six of the swing's decay times at D_p = 5e-5
REST_S = 0.5  # s at rest before each motion
CALIBRATION_MARKS = 11  # protractor marks per angle
# the marks span what each sensor is used over: the arm about half its way to a QUBE's cable limit,
# the pendulum the balance's +/-0.3 rad (rad)
CALIBRATION_SPAN = {"alpha": 1.5, "theta": 0.3}
ROTARY_FILES = ("links.toml", "calibration.csv", "motor-step.csv", "arm-coast-1.csv", "arm-coast-2.csv",
                "free-swing.csv", "quiet.csv")


def _arm(J_0: float, drive: np.ndarray, damping: float, fine: float) -> np.ndarray:
    """The arm's angle (rad), the pendulum fixed to it: J_0 alpha'' = drive - damping alpha', the
    drive (N m) held over each fine step and integrated exactly; one angle per step and the last."""
    a = damping / J_0
    e = math.exp(-a * fine)
    w1 = (1 - e) / a
    alpha, v = 0.0, 0.0
    out = np.empty(drive.size + 1)
    out[0] = 0.0
    for k, f in enumerate(drive / J_0):
        alpha += v * w1 + f * (fine - w1) / a
        v = v * e + f * w1
        out[k + 1] = alpha
    return out


def _swing(p: RotaryParams, phi0: float, tip: np.ndarray, fine: float) -> np.ndarray:
    """The pendulum's angle from hanging (rad), the arm clamped: the plant's second equation with the
    arm still (RK4), a force at the tip held over each fine step."""
    c = inertias(p)

    def acc(phi, om, f):
        theta = math.pi + phi  # from upright, as the plant's equations take it
        q = generalised_forces(p, 0.0, om, 0.0)[1] - potential_gradient(c, theta)[1]
        return (q + f * p.L_p * math.cos(phi)) / c.J_2

    phi, om = phi0, 0.0
    out = np.empty(tip.size + 1)
    out[0] = phi
    for k, f in enumerate(tip):
        k1p, k1v = om, acc(phi, om, f)
        k2p, k2v = om + 0.5 * fine * k1v, acc(phi + 0.5 * fine * k1p, om + 0.5 * fine * k1v, f)
        k3p, k3v = om + 0.5 * fine * k2v, acc(phi + 0.5 * fine * k2p, om + 0.5 * fine * k2v, f)
        k4p, k4v = om + fine * k3v, acc(phi + fine * k3p, om + fine * k3v, f)
        phi += fine / 6 * (k1p + 2 * k2p + 2 * k3p + k4p)
        om += fine / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        out[k + 1] = phi
    return out


def _square(dt: float) -> np.ndarray:
    """The motor step's command: a quarter level first, so the arm swings about its start."""
    n = int(round(STEP_DURATION_S / dt))
    t = np.arange(n) * dt + STEP_HALF_PERIOD_S / 2
    return np.where(np.floor(t / STEP_HALF_PERIOD_S) % 2 == 0, STEP_VOLTS, -STEP_VOLTS)


def rotary_bench_test_files(plant: RotaryParams, bench: BenchProfile, seed: int, label: str = "") -> dict[str, bytes]:
    """Every standard test's recording (CSV) or figures (TOML) of a rotary pendulum's bench.

    Parameters
    ----------
    plant : RotaryParams
        The plant as the bench has it (the spec's, with the bench's measured figures).
    bench : BenchProfile
        A rotary bench: its amplifier, encoders, the card's analog outputs and their noise, the
        random torque on the arm and force at the tip.
    seed : int
        The noise seed.
    label : str
        Words for each file's second comment line.

    Returns
    -------
    dict
        ROTARY_FILES, by name.
    """
    sens, dist = bench.sensors, bench.disturbance
    nrms = lambda k: float(sens.noise_V_rms.get(k, 0.0))
    about = f"recorded by patchgen bench-test{': ' + label if label else ''}, seed {seed}"
    rng = lambda i: np.random.default_rng([seed, i])
    dt, fine = DYNAMIC_DT_S, DYNAMIC_DT_S / FINE_STEPS
    per_rad = {q: sens.counts_per_rev[q] / (2 * math.pi) for q in MEASURED}  # the QUBE's encoders
    count = lambda q, x: np.floor(x * per_rad[q] + 0.5)
    csv = lambda *a: _csv(*a, bench=bench.id)
    c = inertias(plant)
    files: dict[str, bytes] = {}
    r = rng(1)
    mass_u, length_u = ASSUMED_MASS_UNCERTAINTY_KG, ASSUMED_LENGTH_UNCERTAINTY_M
    read = lambda x, u: x + u * r.standard_normal()
    files["links.toml"] = _toml({
        "test": "links", "m_r_kg": read(plant.m_r, mass_u), "L_r_m": read(plant.L_r, length_u),
        "m_p_kg": read(plant.m_p, mass_u), "L_p_m": read(plant.L_p, length_u),
        "R_m_ohm": read(plant.R_m, OHMMETER_FRACTION * plant.R_m), "g_m_per_s2": plant.g,
        "mass_uncertainty_kg": mass_u, "length_uncertainty_m": length_u,
        "R_m_uncertainty_ohm": OHMMETER_FRACTION * plant.R_m},
        "links weighed and measured, the motor's resistance on an ohmmeter; " + about)
    r = rng(2)
    marks = {q: np.linspace(-span, span, CALIBRATION_MARKS) for q, span in CALIBRATION_SPAN.items()}
    cols, header = [], []
    for q in MEASURED:
        header += [f"{q}_rad", f"{q}_V"]
        cols += [marks[q], getattr(sens, q) * marks[q] + nrms(q) * r.standard_normal(CALIBRATION_MARKS)]
    files["calibration.csv"] = csv("calibration", tuple(header), cols,
                                   "arm and pendulum set at protractor marks, the card's analog outputs read; " + about)
    r = rng(3)
    command = _square(dt)
    volts = np.clip(bench.actuator.K_U * command, -bench.actuator.V_limit, bench.actuator.V_limit)
    n = volts.size
    torque = np.repeat(plant.torque_per_volt() * volts, FINE_STEPS) + motion.coloured(
        r, dist.arm_torque_Nm_rms, dist.bandwidth_Hz, fine, n * FINE_STEPS)
    alpha = _arm(c.J_0, torque, plant.D_r + plant.back_emf_damping(), fine)[:-1:FINE_STEPS]
    files["motor-step.csv"] = csv("motor_step", ("t_s", "V_m_V", "alpha_counts"),
                                  [np.arange(n) * dt, volts, count("alpha", alpha)],
                                  "pendulum fixed hanging to the arm, the motor driven by a square wave; " + about)
    for j, direction in enumerate((1.0, -1.0)):
        r = rng(4 + j)
        n = int(round((REST_S + COAST_PUSH_S + COAST_DECAYS * c.J_0 / plant.D_r) / dt))
        push = np.zeros(n * FINE_STEPS)
        push[int(REST_S / fine):int((REST_S + COAST_PUSH_S) / fine)] = direction * c.J_0 * COAST_SPEED / COAST_PUSH_S
        torque = push + motion.coloured(r, dist.arm_torque_Nm_rms, dist.bandwidth_Hz, fine, n * FINE_STEPS)
        alpha = _arm(c.J_0, torque, plant.D_r, fine)[:-1:FINE_STEPS]
        files[f"arm-coast-{j + 1}.csv"] = csv("arm_coast", ("t_s", "alpha_counts"),
                                              [np.arange(n) * dt, count("alpha", alpha)],
                                              "pendulum fixed hanging to the arm, the arm spun by hand and let go, "
                                              "the amplifier off; " + about)
    r = rng(6)
    n = int(round(SWING_DURATION_S / dt))
    hold = int(round(1.0 / dt))
    tip = np.repeat(motion.coloured(r, dist.tip_force_N_rms, dist.bandwidth_Hz, dt, n - hold), FINE_STEPS)
    phi = _swing(plant, math.radians(SWING_ANGLE_DEG), tip, fine)[:-1:FINE_STEPS]
    phi = np.concatenate([np.full(hold, math.radians(SWING_ANGLE_DEG)), phi])
    files["free-swing.csv"] = csv("free_swing", ("t_s", "theta_counts"), [np.arange(n) * dt, count("theta", phi)],
                                  f"arm clamped, pendulum held at {SWING_ANGLE_DEG:g} deg from hanging and let go, "
                                  "its encoder zeroed hanging; " + about)
    r = rng(7)
    qdt = quiet_step(sens.noise_bandwidth_Hz)
    cols = [np.arange(QUIET_SAMPLES) * qdt] + [motion.coloured(r, nrms(q), sens.noise_bandwidth_Hz, qdt, QUIET_SAMPLES)
                                               for q in MEASURED]
    files["quiet.csv"] = csv("quiet", ("t_s", *(f"{q}_V" for q in MEASURED)), cols,
                             "arm and pendulum at rest, motor off, the card's analog outputs read; " + about)
    return files
