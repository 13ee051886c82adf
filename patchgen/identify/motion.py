"""The bench's open-loop motions for the standard tests, from patchgen's own models: the actuator
of a bench profile (dead zone, lag or lag with a zero, force limit, as patchgen.bench.lanes drives
it), the cart with the pendulum fixed to it (eq. B.1), the pendulum swinging with the cart clamped
(eq. 2.16-2.19 through patchgen.plant.compiled, the cart held by the force that keeps it still),
and band-limited noise as the simulator draws it (patchgen.bench.engine.noise_process).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from scipy.signal import lfilter

from patchgen.bench.engine import noise_process
from patchgen.plant.compiled import N_COEF, plant_accel, plant_coefficients, sincos
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchActuator

_JIT = {"cache": True, "error_model": "numpy"}
# numba stamps this file's cache with this file alone; plant/compiled.py's functions are compiled
# into it, so its digest is kept here (first 16 hex digits of sha256): a change there changes this
# file (tests/bench/test_kernel.py says when it is out of date)
COMPILED_FILES = ("plant/compiled.py",)
COMPILED_IN = "7a78a4c79b409aea"


def coloured(rng: np.random.Generator, rms: float, bandwidth_Hz: float, dt: float, n: int) -> np.ndarray:
    """n samples at step dt of noise of ``rms`` over ``bandwidth_Hz``, as the simulator holds it over a
    step (an AR(1) sequence started from its stationary spread)."""
    a, std = noise_process(rms, bandwidth_Hz, dt)
    w = rng.standard_normal(n + 1)
    if std == 0.0:
        return np.zeros(n)
    if a == 0.0:
        return std * w[1:]
    return lfilter([std], [1.0, -a], w[1:], zi=[a * rms * w[0]])[0]


def actuator_force(u: np.ndarray, act: BenchActuator, dt: float) -> np.ndarray:
    """The force (N) of a bench actuator for the command u (V) held over each step, read at the end
    of each step before the command changes, from rest at u[0]. A DC motor's (patchgen.plant.drive)
    with the cart held: no back-EMF, the command limited at the amplifier, then its electrical lag."""
    dz = act.dead_zone_V
    v = np.where(u > dz, u - dz, np.where(u < -dz, u + dz, 0.0))
    F = np.empty(u.size)
    tau = act.tau
    if act.model == "dc_motor":  # the amplifier's limit on the voltage, then the current's lag (cart held)
        top = act.force_limit_N / act.K_U
        v = np.clip(v, -top, top)
        tau = act.motor_lag()
        model = 1 if tau > 0 else 0
    else:
        model = 0 if act.model == "gain" or tau <= 0 else (1 if act.model == "lag" else 2)
    decay = math.exp(-dt / tau) if tau > 0 else 0.0
    _actuator_steps(v, float(act.K_U), float(tau), decay, model, F)
    return np.clip(F, -act.force_limit_N, act.force_limit_N)


@nb.njit(**_JIT)
def _actuator_steps(v, K_U, tau, decay, model, F):
    """actuator_force's steps into F: model 0 a gain, 1 a lag, 2 a lag with a zero at the origin."""
    held = v[0]  # the command over the step that ends at each sample
    x = v[0] if model == 2 else K_U * v[0]
    for k in range(v.size):
        if model == 0:
            F[k] = K_U * held
        elif model == 1:
            F[k] = x
        else:
            F[k] = K_U / tau * (held - x)
        held = v[k]
        target = held if model == 2 else K_U * held
        x = target + (x - target) * decay


def slide(plant: PlantParams, s0: float, v0: float, push: np.ndarray, h: float,
          coulomb_N: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The cart with the pendulum fixed to it (B.1 with the slope's force in ``push``):
    (M + m) s'' = push - b_VF s' - F_c sgn(s'), RK4 at step h with push held over each step.
    Returns s and s' at every step (len(push) + 1 samples)."""
    s, v = np.empty(push.size + 1), np.empty(push.size + 1)
    _slide(float(plant.M + plant.m), float(plant.b_VF), float(coulomb_N), float(s0), float(v0),
           np.ascontiguousarray(push, dtype=float), float(h), s, v)
    return s, v


@nb.njit(**_JIT)
def _slide_acc(f, vv, mass, b_VF, coulomb_N):
    return (f - b_VF * vv - coulomb_N * np.sign(vv)) / mass


@nb.njit(**_JIT)
def _slide(mass, b_VF, coulomb_N, s0, v0, push, h, s, v):
    """slide's RK4 steps into s and v."""
    s[0], v[0] = s0, v0
    for k in range(push.size):
        f = push[k]
        k1v = _slide_acc(f, v[k], mass, b_VF, coulomb_N)
        k2v = _slide_acc(f, v[k] + 0.5 * h * k1v, mass, b_VF, coulomb_N)
        k3v = _slide_acc(f, v[k] + 0.5 * h * k2v, mass, b_VF, coulomb_N)
        k4v = _slide_acc(f, v[k] + h * k3v, mass, b_VF, coulomb_N)
        v[k + 1] = v[k] + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        s[k + 1] = s[k] + h / 6 * (v[k] + 2 * (v[k] + 0.5 * h * k1v) + 2 * (v[k] + 0.5 * h * k2v) + v[k] + h * k3v)
        if coulomb_N > 0 and v[k] != 0 and np.sign(v[k + 1]) != np.sign(v[k]) and abs(f) <= coulomb_N:
            v[k + 1] = 0.0  # static friction holds a cart that has stopped


@nb.njit(**_JIT)
def _clamped_accel(q, sn, cs, thd, tip):
    """theta'' with the cart held still: eq. 2.16-2.19 are linear in the cart force, which is
    chosen so that s'' = 0."""
    sdd0, thdd0 = plant_accel(q, 0, sn, cs, 0.0, thd, 0.0, tip)
    sdd1, thdd1 = plant_accel(q, 0, sn, cs, 0.0, thd, 1.0, tip)
    return thdd0 - sdd0 / (sdd1 - sdd0) * (thdd1 - thdd0)


@nb.njit(**_JIT)
def swing(p, theta0, h, tip, out):
    """The pendulum with the cart clamped, from rest at theta0, RK4 at step h with the tip force
    tip[k] held over step k; theta at every step into out (len(tip) + 1)."""
    q = np.empty((N_COEF, 1))
    plant_coefficients(p, q[:, 0])
    th, om = theta0, 0.0
    out[0] = th
    for k in range(tip.size):
        f = tip[k]
        sn, cs = sincos(th)
        a1 = _clamped_accel(q, sn, cs, om, f)
        sn, cs = sincos(th + 0.5 * h * om)
        a2 = _clamped_accel(q, sn, cs, om + 0.5 * h * a1, f)
        sn, cs = sincos(th + 0.5 * h * (om + 0.5 * h * a1))
        a3 = _clamped_accel(q, sn, cs, om + 0.5 * h * a2, f)
        sn, cs = sincos(th + h * (om + 0.5 * h * a2))
        a4 = _clamped_accel(q, sn, cs, om + h * a3, f)
        th += h / 6 * (om + 2 * (om + 0.5 * h * a1) + 2 * (om + 0.5 * h * a2) + om + h * a3)
        om += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        out[k + 1] = th
