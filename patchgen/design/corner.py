"""Choosing an estimator's speed from the bench's noise levels.

A differentiator's roll-off (or a reduced observer's pole) trades two errors in theta_dot (and in
any other estimated state): a fast one passes more sensor noise, a slow one lags the closed
loop's own motion. The rule: pick the value that minimises the predicted variance of the force
error caused by estimation,

    e_u = u - u_ideal,   u_ideal = -K x (true states; integral states as the controller has them),

in the linear closed loop of the design model and the controller, driven by

- each sensor's noise as on the bench profile: rms sigma_i (V, turned into SI units by the
  sensor constant), first-order band-limited at the profile's noise bandwidth (a white sequence
  would give a differentiator's output infinite variance);
- the actuator's dead zone as a force disturbance on the plant input: rms K_U * delta / sqrt(3)
  (the error of a dead zone +/-delta is spread over +/-delta, a uniform spread's rms), band-limited
  like the noise. It is what keeps the loop moving, so it sets the lag error.

The variance comes from the Lyapunov equation of the augmented loop, so both terms of the
trade (noise gain through the estimator, lag error on the closed-loop signal) are in it, with
their correlation. The minimum is taken over a fixed logarithmic grid (deterministic);
candidates whose loop is unstable, or whose phase margin at the plant input is below
MIN_PM_DEG, are skipped: the variance is linear and blind to the dead zone and the force limit,
which in simulation turn a loop with a thin phase margin into a limit cycle that walks the cart
into the switches (a 0.03 s roll-off with 18 degrees trips in every seed where 0.003 s with 32
degrees holds in every seed), so the rule minimises the error among robust candidates only.
K_w (w_hat - w) weighs each estimated state by its gain, so for a differentiator the rule is
the theta_dot error variance (plus terms that do not depend on the roll-off).

When no value on the grid reaches MIN_PM_DEG the spec is refused, with a way forward when there
is one: the value of least error among those with SUGGEST_PM_DEG, to be set in the spec, offered
only once the design made with it passes and keeps that margin (:func:`way_forward`). The floor
is bench evidence, not theory: bench-recommended with M = 4 kg and a theta excursion of 0.02 rad
reaches 29.6 deg at best; its roll-offs of 28.0 and 27.8 deg held in every standard scenario on
uw-1991, 26.8 deg tripped the switches after the cart step and 25.3 deg in every scenario.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from patchgen.design.controller import Controller
from patchgen.design.model import LinearModel
from patchgen.inputs.errors import Cure, InputError
from patchgen.inputs.spec import DesignSpec
from patchgen.profiles.bench import BenchProfile

ROLLOFF_GRID_S = np.logspace(-3, 0, 61)  # differentiator roll-off candidates, s
POLE_GRID = np.logspace(0, 3, 61)  # observer pole candidates, rad/s
MIN_PM_DEG = 30.0  # the least phase margin a chosen estimator may leave the loop
SUGGEST_PM_DEG = 28.0  # the least a refusal's suggested speed may leave (the module's docstring)
SUGGEST_TRIES = 3  # designs a refusal makes with suggested speeds before it gives up suggesting
DECAY_TOL = 1e-9  # 1/s: the noisy loop's slowest mode must decay at least this fast to have a variance


@dataclass(frozen=True)
class NoiseModel:
    """Sensor noise (SI rms per measured output), its bandwidth (rad/s), dead-zone force rms (N)."""

    sensor_rms: np.ndarray
    bandwidth: float
    force_rms: float


@dataclass(frozen=True)
class CornerChoice:
    """The chosen roll-off (s) or pole (rad/s), its predicted force error (N), the grid's size."""

    value: float
    force_error_rms_N: float
    tried: int


def noise_model(spec: DesignSpec, bench: BenchProfile, model: LinearModel) -> NoiseModel:
    """The bench's sensor noise (in SI units, through the spec's sensor constants) and dead zone.

    Parameters
    ----------
    spec : DesignSpec
        Gives the sensor constants (V per SI unit).
    bench : BenchProfile
        Gives the sensor noise rms and bandwidth and the actuator's dead zone.
    model : LinearModel
        Gives the measured outputs, in order.

    Returns
    -------
    NoiseModel
        What :func:`force_error_rms` drives the loop with.
    """
    ks = spec.sensors.constants()
    rms = np.array([bench.sensors.noise_V_rms.get(m, 0.0) / ks[m] for m in model.measured])
    dead_zone_rms = bench.actuator.K_U * bench.actuator.dead_zone_V / math.sqrt(3.0)  # uniform over +/-delta
    return NoiseModel(rms, 2 * math.pi * bench.sensors.noise_bandwidth_Hz, dead_zone_rms)


def force_error_rms(model: LinearModel, K: np.ndarray, ctl: Controller, noise: NoiseModel) -> float:
    """Predicted rms of u - u_ideal (N) in the noisy linear loop; inf when the loop is unstable."""
    keep = [i for i, s in enumerate(model.states) if not s.startswith("int_")]
    Ap, Bp, Cp = model.A[np.ix_(keep, keep)], model.B[keep], model.C[:, keep]
    Kp = K[:, keep]
    Ki = np.zeros((1, ctl.Ac.shape[0]))
    for j, name in enumerate(ctl.states):
        if name.startswith("int_"):
            Ki[0, j] = K[0, model.index(name)]
    n, nc, ny = Ap.shape[0], ctl.Ac.shape[0], Cp.shape[0]
    N = n + nc + ny + 1
    A = np.zeros((N, N))
    ix, ic, iN, iD = slice(0, n), slice(n, n + nc), slice(n + nc, n + nc + ny), n + nc + ny
    A[ix, ix] = Ap + Bp @ ctl.Dc @ Cp
    A[ix, ic] = Bp @ ctl.Cc
    A[ix, iN] = Bp @ ctl.Dc
    A[ix, iD] = Bp[:, 0]
    A[ic, ix] = ctl.Bc @ Cp
    A[ic, ic] = ctl.Ac
    A[ic, iN] = ctl.Bc
    wb = noise.bandwidth
    A[iN, iN] = -wb * np.eye(ny)
    A[iD, iD] = -wb
    if np.max(np.linalg.eigvals(A).real) >= -DECAY_TOL:
        return math.inf
    # first-order shaping: intensity 2 sigma^2 / wb gives variance sigma^2
    Gd = np.zeros(N)
    Gd[n + nc:n + nc + ny] = wb * np.sqrt(2.0 / wb) * noise.sensor_rms
    Gd[iD] = wb * math.sqrt(2.0 / wb) * noise.force_rms
    Qn = np.diag(Gd**2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        try:
            X = sla.solve_continuous_lyapunov(A, -Qn)
        except RuntimeWarning:  # a mode so near the axis that the solver perturbs it: no variance to speak of
            return math.inf
    e = np.zeros(N)
    e[ix] = (ctl.Dc @ Cp + Kp)[0]
    e[ic] = (ctl.Cc + Ki)[0]
    e[iN] = ctl.Dc[0]
    return float(math.sqrt(max(e @ X @ e, 0.0)))


@dataclass(frozen=True)
class Scored:
    """A grid value (to three digits) that missed the margin: its force error (N) and phase
    margin (deg; None for a loop that is not stable)."""

    value: float
    force_error_rms_N: float
    pm_deg: float | None


class NoRobustSpeed(ValueError):
    """No value on the grid leaves the loop MIN_PM_DEG of phase margin; ``scored`` holds every
    value tried, with its error and margin, from the least error up."""

    def __init__(self, scored: list[Scored], min_pm_deg: float = MIN_PM_DEG):
        self.scored = tuple(scored)
        best = max((s.pm_deg for s in self.scored if s.pm_deg is not None), default=None)
        most = "" if best is None else f" (the most is {best:.1f} deg)"
        super().__init__(f"no estimator speed on the grid gives a stable loop with {min_pm_deg:g} deg of phase "
                         f"margin{most}")

    def fallbacks(self, floor: float = SUGGEST_PM_DEG) -> list[Scored]:
        """The values with at least ``floor`` deg of margin, the least error first."""
        return [s for s in self.scored if s.pm_deg is not None and s.pm_deg >= floor]


def choose(model: LinearModel, K: np.ndarray, build: Callable[[float], Controller], noise: NoiseModel,
           grid: np.ndarray, margin: Callable[[Controller], float | None] = lambda c: math.inf,
           min_pm_deg: float = MIN_PM_DEG) -> CornerChoice:
    """The grid value whose controller gives the smallest predicted force error among those whose
    ``margin`` (the phase margin it leaves the loop, deg, None when the loop is not stable) is at
    least ``min_pm_deg``; ties to the first on the grid. ``margin``, the costly part, runs on the
    candidates from the smallest error up, until one passes; when none does, NoRobustSpeed says
    so and holds them all."""
    scored = []
    for k, v in enumerate(grid):
        try:
            ctl = build(float(v))
        except ValueError:
            continue
        r = force_error_rms(model, K, ctl, noise)
        if math.isfinite(r):
            scored.append((r, k, float(v), ctl))
    missed = []
    for r, _, v, ctl in sorted(scored, key=lambda c: c[:2]):
        pm = margin(ctl)
        if pm is not None and pm >= min_pm_deg:
            return CornerChoice(_round3(v), r, len(grid))
        missed.append(Scored(_round3(v), r, pm))
    raise NoRobustSpeed(missed, min_pm_deg)


def way_forward(refusal: NoRobustSpeed, field: str, margin_with: Callable[[float], float | None]) -> Cure | None:
    """The speed to set in the spec when the search refused: of the values with SUGGEST_PM_DEG,
    the least error first, the first whose whole design passes and keeps that margin.

    Parameters
    ----------
    refusal : NoRobustSpeed
        The search's refusal, with every value it tried.
    field : str
        The spec's field that fixes the speed (``estimator.rolloff_s``, ``estimator.observer_pole``).
    margin_with : callable
        The phase margin (deg, None when not stable) of the spec designed with ``field`` set to a
        value; an InputError when that design refuses.

    Returns
    -------
    Cure or None
        The field, the value and the margin it gives; None when no value passes.
    """
    for s in refusal.fallbacks()[:SUGGEST_TRIES]:
        try:
            pm = margin_with(s.value)
        except InputError:
            continue
        if pm is not None and pm >= SUGGEST_PM_DEG:
            return Cure(field, s.value, f"gives {pm:.1f} deg, the least force error of the speeds that reach "
                                        f"{SUGGEST_PM_DEG:g}")
    return None


def _round3(x: float) -> float:
    """Three significant digits: a component value, not a float artefact."""
    return float(f"{x:.3g}")
