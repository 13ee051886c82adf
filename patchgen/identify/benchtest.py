"""Recordings of every standard test for a plant on a bench, as a class would record them: the
bench profile's actuator, sensors, noise and random forces, the machine's integrator drift and
amplifier noise, and patchgen's own plant and actuator models (patchgen.identify.motion). The
open-loop tests need no patch. docs/identify.md gives each test's procedure; the sample rates and
lengths here are the ones it recommends.

A bench driven by a DC motor (patchgen.plant.drive) coasts and slides with the rotor on the cart
and the back-EMF braking it (the amplifier on, at 0 V); the held cart's force is the motor's at
standstill. A quantity the bench reads on an encoder is recorded in whole counts (``s_counts``,
``theta_counts``), a filtered velocity as the filter gives it from the encoder's position; such
recordings name their bench (``# bench = <id>``), whose counts identify needs. The incline is not
recorded for a motor-driven cart (B.2 has no rotor and no back-EMF; its coast-down gives the
damping), and the masses name the pendulum's centre of mass when it is a rigid body (J > 0).

Recording i of seed N draws from ``numpy.random.default_rng([N, i])``: the same seed gives the same
bytes.
"""

from __future__ import annotations

import math

import numpy as np

from patchgen.identify import motion
from patchgen.identify.encoders import filtered_rate
from patchgen.identify.figures import (
    ASSUMED_ANGLE_UNCERTAINTY_DEG,
    ASSUMED_DISTANCE_UNCERTAINTY_M,
    ASSUMED_TIME_UNCERTAINTY_S,
)
from patchgen.inputs.drive_fields import motor_of
from patchgen.plant.cart_pendulum import MEASURED
from patchgen.plant.compiled import plant_vector
from patchgen.plant.drive import driven
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

DYNAMIC_DT_S = 0.005  # 200 Hz for the step, ramp, coast-down and swing (docs/identify.md)
FINE_STEPS = 5  # the motions are integrated at a fifth of the recording's interval
GAUGE_NOISE_N_RMS = 0.02  # N: a load cell's noise, white at the recording rate (assumed)
STEP_LEVELS = (0.4, 0.6, 0.8, 1.0)  # the step test's command levels, as fractions of the largest
PEAK_FORCE_FRACTION = 0.8  # the largest step's force, as a fraction of the force limit
RAMP_FORCE_FRACTION = 0.6  # the ramp's largest force, likewise
RAMP_DURATION_S = 48.0  # zero, up, down through zero, back to zero
COAST_TRAVEL_FRACTION = 0.6  # of the track: how far the cart would coast with viscous friction alone
MAX_COAST_SPEED = 1.0  # m/s
SWING_ANGLE_DEG = 15.0  # the free swing's release angle
SWING_DURATION_S = 60.0
QUIET_SAMPLES = 20000
QUIET_OVERSAMPLING = 10.0  # the quiet recording samples at ten times the sensors' bandwidth ...
QUIET_MIN_RATE_HZ = 1000.0  # ... and at 1 kHz at least
DRIFT_DT_S = 0.02
DRIFT_DURATION_S = 60.0
INCLINE_DEG = 9.5  # the thesis's slope (B.2.1)
FILES = ("masses.toml", "calibration.csv", "actuator-step.csv", "actuator-ramp.csv", "coast-down-1.csv",
         "coast-down-2.csv", "incline.toml", "free-swing.csv", "quiet.csv", "integrator-drift.csv")


def _csv(test: str, header: tuple[str, ...], cols: list[np.ndarray], about: str, bench: str = "") -> bytes:
    lines = [f"# test = {test}", *([f"# bench = {bench}"] if bench else []), f"# {about}", ", ".join(header)]
    row = ", ".join("%.10g" if h == "t_s" else "%d" if h.endswith("_counts") else "%.7g" for h in header)
    data = np.column_stack([np.asarray(c, dtype=float) for c in cols]).tolist()
    lines.extend(row % tuple(r) for r in data)  # one format per row: the same text as cell by cell
    return ("\n".join(lines) + "\n").encode()


def _toml(items: dict, about: str) -> bytes:
    out = [f"# {about}"]
    for k, v in items.items():
        out.append(f'{k} = "{v}"' if isinstance(v, str) else f"{k} = {v:.10g}")
    return ("\n".join(out) + "\n").encode()


def _step_command(act, dt: float) -> np.ndarray:
    reach = act.K_U / act.tau if act.model == "lag_zero" and act.tau > 0 else act.K_U
    top = act.dead_zone_V + PEAK_FORCE_FRACTION * act.force_limit_N / reach
    hold = max(2.0, 8 * act.tau)
    seq = [0.0]
    for f in STEP_LEVELS:
        seq += [f * top, 0.0, -f * top, 0.0]
    per = int(round(hold / dt))
    return np.repeat(np.array(seq), per)


def _ramp_command(act, dt: float) -> np.ndarray:
    reach = act.K_U / act.tau if act.model == "lag_zero" and act.tau > 0 else act.K_U
    top = act.dead_zone_V + RAMP_FORCE_FRACTION * act.force_limit_N / reach
    t = np.arange(int(round(RAMP_DURATION_S / dt)) + 1) * dt
    q = RAMP_DURATION_S / 4
    return np.interp(t, [0, q, 3 * q, 4 * q], [0.0, top, -top, 0.0])


def quiet_step(bandwidth_Hz: float) -> float:
    """The quiet recording's sample interval (s) for sensors of that noise bandwidth."""
    return 1.0 / max(QUIET_MIN_RATE_HZ, QUIET_OVERSAMPLING * bandwidth_Hz)


def _held(rng, n: int, rms: float, bandwidth: float, fine: float) -> np.ndarray:
    """A random force held over each fine step: n * FINE_STEPS values."""
    return motion.coloured(rng, rms, bandwidth, fine, n * FINE_STEPS)


def bench_test_files(plant: PlantParams, bench: BenchProfile, machine: MachineProfile, seed: int,
                     label: str = "") -> dict[str, bytes]:
    """Every standard test's recording (CSV) or figures (TOML), as file name -> bytes.

    Parameters
    ----------
    plant : PlantParams
        The plant (a spec's [plant]).
    bench, machine : BenchProfile, MachineProfile
        The bench (actuator, sensors, noise, random forces) and the machine (integrator drift,
        amplifier noise).
    seed : int
        The noise seed.
    label : str
        Words for each file's second comment line (the spec's name, say).

    Returns
    -------
    dict
        masses.toml, calibration.csv, actuator-step.csv, actuator-ramp.csv, coast-down-1.csv,
        coast-down-2.csv, incline.toml (not for a motor-driven cart), free-swing.csv, quiet.csv,
        integrator-drift.csv.
    """
    sens, act, dist = bench.sensors, bench.actuator, bench.disturbance
    nrms = lambda k: float(sens.noise_V_rms.get(k, 0.0))
    about = f"recorded by patchgen bench-test{': ' + label if label else ''}, seed {seed}"
    rng = lambda i: np.random.default_rng([seed, i])
    dt, fine = DYNAMIC_DT_S, DYNAMIC_DT_S / FINE_STEPS
    motor, counts = motor_of(act), {q: 1.0 / c for q, c in sens.quanta().items()}
    named = bench.id if motor is not None or counts else ""  # identify needs such a bench's motor and counts
    csv = lambda *a: _csv(*a, bench=named)
    files: dict[str, bytes] = {}
    figures = {"test": "masses", "M_kg": plant.M, "m_kg": plant.m, "g_m_per_s2": plant.g, "d_m": plant.d}
    if plant.J > 0:
        figures["l_cm_m"] = plant.l
    files["masses.toml"] = _toml(figures, "weighed and measured (thesis B.1); " + about)
    r = rng(1)
    s_ref = np.linspace(-0.4 * plant.d, 0.4 * plant.d, 11)
    th_ref = np.linspace(-0.3, 0.3, 11)
    s_col, s_read = _reading("s", s_ref, counts, sens.s, nrms("s") * r.standard_normal(11))
    th_col, th_read = _reading("theta", th_ref, counts, sens.theta, nrms("theta") * r.standard_normal(11))
    files["calibration.csv"] = csv("calibration", ("s_m", s_col, "theta_rad", th_col), [
        s_ref, s_read, th_ref, th_read], "cart set at marks on the track, pendulum at protractor marks; " + about)
    for i, (name, command) in enumerate((("actuator-step", _step_command(act, dt)),
                                         ("actuator-ramp", _ramp_command(act, dt))), start=2):
        r = rng(i)
        n = command.size
        cart = motion.coloured(r, dist.cart_force_N_rms, dist.bandwidth_Hz, dt, n)
        force = motion.actuator_force(command, act, dt) + cart + GAUGE_NOISE_N_RMS * r.standard_normal(n)
        files[f"{name}.csv"] = csv(name.replace("-", "_"), ("t_s", "u_c_V", "force_N"),
                                   [np.arange(n) * dt, command, force], "cart held against a force gauge; " + about)
    moving = driven(plant, motor)  # with a motor, the rotor on the cart and the back-EMF braking it
    mass = moving.M + moving.m
    filt = sens.filters().get("s_dot")
    v0 = min(COAST_TRAVEL_FRACTION * plant.d * moving.b_VF / mass, MAX_COAST_SPEED) if moving.b_VF > 0 else 0.5
    for j, direction in enumerate((1.0, -1.0)):
        r = rng(4 + j)
        push_s = 0.3
        decay = moving.b_VF / mass if moving.b_VF > 0 else 0.1
        n = int(round((0.5 + push_s + 3.5 / decay + (0.5 if filt else 0.0)) / dt))
        push = np.zeros(n * FINE_STEPS)
        k_on, k_off = int(0.5 / fine), int((0.5 + push_s) / fine)
        push[k_on:k_off] = direction * mass * v0 / push_s * (1 + moving.b_VF / mass * push_s / 2)
        force = push + _held(r, n, dist.cart_force_N_rms, dist.bandwidth_Hz, fine)
        s_fine, v = motion.slide(moving, -direction * 0.45 * plant.d, 0.0, force, fine)
        s, v = s_fine[:-1:FINE_STEPS], v[:-1:FINE_STEPS]
        if "s" in counts:  # the encoder's count; a filtered velocity is the filter's rate of that count
            s_col, s_read = "s_counts", np.floor(s * counts["s"] + 0.5)
        else:
            s_col, s_read = "s_V", sens.s * s + motion.coloured(r, nrms("s"), sens.noise_bandwidth_Hz, dt, n)
        if filt is not None:
            q = 1.0 / counts["s"] if "s" in counts else 0.0
            v = filtered_rate(q * np.floor(s_fine / q + 0.5) if q else s_fine, fine, filt)[:-1:FINE_STEPS]
        files[f"coast-down-{j + 1}.csv"] = csv("coast_down", ("t_s", s_col, "s_dot_V"), [
            np.arange(n) * dt, s_read,
            sens.s_dot * v + motion.coloured(r, nrms("s_dot"), sens.noise_bandwidth_Hz, dt, n)],
            "pendulum fixed to the cart, cart pushed by hand and let go" +
            (", the amplifier on at 0 V; " if motor is not None else "; ") + about)
    r = rng(6)
    if motor is None:
        files["incline.toml"] = _incline(plant, r, fine, dist, about)
    r = rng(7)
    n = int(round(SWING_DURATION_S / dt))
    hold = int(round(1.0 / dt))
    tip = _held(r, n - hold, dist.tip_force_N_rms, dist.bandwidth_Hz, fine)
    theta = np.empty(tip.size + 1)
    p = plant_vector(plant)
    motion.swing(p, math.pi + math.radians(SWING_ANGLE_DEG), fine, tip, theta)
    phi = np.concatenate([np.full(hold, math.radians(SWING_ANGLE_DEG)), theta[:-1:FINE_STEPS] - math.pi])
    th_col, th_read = _reading("theta", phi, counts, sens.theta, None)
    if th_read is None:
        th_read = sens.theta * phi + motion.coloured(r, nrms("theta"), sens.noise_bandwidth_Hz, dt, n)
    files["free-swing.csv"] = csv("free_swing", ("t_s", th_col), [np.arange(n) * dt, th_read],
                                  "cart clamped, pendulum held at 15 deg from hanging and let go, angle "
                                  f"{'encoder' if th_col.endswith('counts') else 'pot'} zeroed hanging; " + about)
    r = rng(8)
    qdt = quiet_step(sens.noise_bandwidth_Hz)
    cols = [np.arange(QUIET_SAMPLES) * qdt]
    for k in MEASURED:
        cols.append(motion.coloured(r, nrms(k), sens.noise_bandwidth_Hz, qdt, QUIET_SAMPLES))
    files["quiet.csv"] = csv("quiet", ("t_s", *(f"{k}_V" for k in MEASURED)), cols,
                             "cart and pendulum clamped at rest, motor off; " + about)
    r = rng(9)
    n = int(round(DRIFT_DURATION_S / DRIFT_DT_S))
    t = np.arange(n) * DRIFT_DT_S
    rate = machine.integrator_drift_V_per_s() * (1 if r.random() < 0.5 else -1)
    imp = machine.imperfections
    out = rate * t + motion.coloured(r, imp.amplifier_noise_V_rms, imp.noise_bandwidth_Hz, DRIFT_DT_S, n)
    files["integrator-drift.csv"] = csv("integrator_drift", ("t_s", "out_V"), [t, out],
                                        "an integrator in OP with its inputs grounded, IC 0 V; " + about)
    return files


def _reading(q: str, x: np.ndarray, counts: dict[str, float], volts_per_unit: float, noise: np.ndarray | None
             ) -> tuple[str, np.ndarray | None]:
    """A sensor's column and reading of x: an encoder's whole counts where the bench counts q (no
    noise: a count is exact), else the sensor's voltage plus ``noise`` (None: left to the caller)."""
    if q in counts:
        return f"{q}_counts", np.floor(x * counts[q] + 0.5)
    return f"{q}_V", None if noise is None else volts_per_unit * x + noise


def _incline(plant: PlantParams, r: np.random.Generator, fine: float, dist, about: str) -> bytes:
    """The inclined slide over the track between the switches, timed by hand."""
    mass = plant.M + plant.m
    push = np.full(int(round(10.0 / fine)), mass * plant.g * math.sin(math.radians(INCLINE_DEG)))
    push += _held(r, push.size // FINE_STEPS, dist.cart_force_N_rms, dist.bandwidth_Hz, fine)[:push.size]
    s, _ = motion.slide(plant, 0.0, 0.0, push, fine)
    k = int(np.argmax(s >= plant.d))
    t_f = (k - 1 + (plant.d - s[k - 1]) / (s[k] - s[k - 1])) * fine
    return _toml({"test": "incline", "angle_deg": INCLINE_DEG + ASSUMED_ANGLE_UNCERTAINTY_DEG * r.standard_normal(),
                  "distance_m": plant.d + ASSUMED_DISTANCE_UNCERTAINTY_M * r.standard_normal(),
                  "time_s": t_f + ASSUMED_TIME_UNCERTAINTY_S * r.standard_normal(), "mass_kg": mass,
                  "g_m_per_s2": plant.g},
                 "pendulum fixed to the cart, let go at the high end, timed to the low switch (thesis B.2.1); " + about)
