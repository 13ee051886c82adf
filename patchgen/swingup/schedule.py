"""Optimised open-loop bang-bang schedule (thesis 3.2-3.3) and its sensitivity to parameter error.

The decision variables are the phase durations of a seed schedule (normally the table the
supervisory logic produced on the same model); the force levels and their order stay. The
problem is the minimum-time one of section 3.2: minimise the final time T_F subject to

- the terminal conditions: x(T_F) inside the hand-off zone with a margin (theta ~ 0, small
  theta_dot, s near 0, small s_dot, as the zone's quadratic form and box weigh them);
- the path constraint: |s(t)| below a fraction of d/2 on [0, T_F].

Solved with SLSQP; every evaluation simulates the seed and its finite-difference neighbours as
one batch on a fixed grid (the force over a step is averaged, so the state depends smoothly on
the switching times).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba as nb
import numpy as np
from scipy.optimize import minimize

from patchgen.plant.cart_pendulum import UNCERTAIN
from patchgen.plant.compiled import N_COEF, plant_accel, plant_coefficients, plant_vector, sincos
from patchgen.plant.equations import PlantParams
from patchgen.swingup.handoff import Zone, wrapped
from patchgen.swingup.pumping import HOLD_S, PUMP_T_MAX_S, STEP_S, SwingUpResult, saturated_state_feedback, simulate
from patchgen.swingup.strategies import Schedule, ScheduleReplay, Switch, hanging_state

# numba stamps this file's cache with this file alone; plant/compiled.py's functions are compiled
# into it, so its digest is kept here (first 16 hex digits of sha256): a change there changes this
# file (tests/bench/test_kernel.py says when it is out of date)
COMPILED_FILES = ("plant/compiled.py",)
COMPILED_IN = "7a78a4c79b409aea"
PARAMETERS = UNCERTAIN  # the plant's physical parameters (patchgen.plant.cart_pendulum)
# how far each parameter is put off in the robustness runs: the thesis asks for experiment because
# its figures are uncertain (3.5, "plant model inaccuracies"); 10 % is assumed, not a thesis figure
PARAMETER_ERROR = 0.10


@dataclass(frozen=True)
class ScheduleSettings:
    """Tuning of the schedule optimiser: its search bounds and finite-difference step."""

    zone_margin: float = 0.8      # x(T_F) must satisfy V < zone_margin * r
    track_margin: float = 0.95    # |s| < track_margin * d/2 along the way
    step_s: float = 2e-3          # grid of the batch simulation
    fd_step_s: float = 1e-3       # finite-difference step on the durations
    maxiter: int = 15              # SLSQP iterations per trust-region round
    rounds: int = 10
    trust_s: float = 0.01          # how far a round may move each duration
    longest_phase_s: float = 1.0  # upper bound on a phase (unless the seed's is longer)


@dataclass
class OptimisedSchedule:
    """The optimised schedule, its predicted final time, and the seed it started from."""

    schedule: Schedule
    T_F: float
    seed: Schedule
    seed_T_F: float
    success: bool
    message: str
    iterations: int
    constraints: dict = field(default_factory=dict)
    kept_seed: bool = False  # the switching times returned are the seed's, unchanged
    why_kept: str = ""  # why, when kept

    def note(self) -> str | None:
        """What the operator is told when the optimiser kept its seed (None when it moved it)."""
        if not self.kept_seed:
            return None
        return f"the optimiser kept its seed (the supervisory logic's switching table): {self.why_kept}"


def schedule_from_result(result: SwingUpResult) -> tuple[Schedule, float]:
    """The switching table a run produced (up to its hand-off) as a schedule, with T_F."""
    if result.handoff_time is None:
        raise ValueError("the run never reached the hand-off zone; no schedule to take")
    rows = [s for s in result.switches if s.time_s < result.handoff_time]
    return Schedule(tuple(rows)), float(result.handoff_time)


def _batch_terminal(
    plant: PlantParams, starts: np.ndarray, forces: np.ndarray, T_F: np.ndarray, h: float
) -> tuple[np.ndarray, np.ndarray]:
    """Simulate B schedules from hanging at rest: starts (n, B) switching times, T_F (B,).

    Returns x(T_F) (4, B) by cubic Hermite interpolation on the grid, and max |s| on [0, T_F].
    The optimiser calls this hundreds of times, so the loop is compiled (the plant's equations are
    the engine's, eq. 2.16-2.19).
    """
    p = plant_vector(plant)
    return _terminal_kernel(p, np.ascontiguousarray(starts, dtype=float), np.asarray(forces, dtype=float),
                            np.asarray(T_F, dtype=float), float(h), hanging_state().astype(float))


@nb.njit(cache=True, error_model="numpy", inline="always")
def _rhs(q, th, sd, thd, u):
    sn, cs = sincos(th)
    sdd, thdd = plant_accel(q, 0, sn, cs, sd, thd, u, 0.0)
    return sd, thd, sdd, thdd


@nb.njit(cache=True, error_model="numpy")
def _terminal_kernel(p, starts, forces, T_F, h, x0):
    n, B = starts.shape
    q = np.empty((N_COEF, 1))
    plant_coefficients(p, q[:, 0])
    x_T = np.zeros((4, B))
    s_max = np.zeros(B)
    for b in range(B):
        s, th, sd, thd = x0[0], x0[1], x0[2], x0[3]
        k_T = int(math.floor(T_F[b] / h))
        for k in range(k_T + 1):
            t0 = k * h
            u = 0.0
            for j in range(n):  # the force held over [t0, t0 + h], averaged over the step
                end = starts[j + 1, b] if j + 1 < n else np.inf
                u += forces[j] * max(min(end, t0 + h) - max(starts[j, b], t0), 0.0)
            u /= h
            a0, a1, a2, a3 = _rhs(q, th, sd, thd, u)
            b0, b1, b2, b3 = _rhs(q, th + 0.5 * h * a1, sd + 0.5 * h * a2, thd + 0.5 * h * a3, u)
            c0, c1, c2, c3 = _rhs(q, th + 0.5 * h * b1, sd + 0.5 * h * b2, thd + 0.5 * h * b3, u)
            d0, d1, d2, d3 = _rhs(q, th + h * c1, sd + h * c2, thd + h * c3, u)
            s1 = s + (h / 6.0) * (a0 + 2.0 * b0 + 2.0 * c0 + d0)
            th1 = th + (h / 6.0) * (a1 + 2.0 * b1 + 2.0 * c1 + d1)
            sd1 = sd + (h / 6.0) * (a2 + 2.0 * b2 + 2.0 * c2 + d2)
            thd1 = thd + (h / 6.0) * (a3 + 2.0 * b3 + 2.0 * c3 + d3)
            s_max[b] = max(s_max[b], abs(s))
            if k == k_T:  # cubic Hermite between the grid points, slopes f(x) and f(x1)
                e0, e1, e2, e3 = _rhs(q, th1, sd1, thd1, u)
                tau = T_F[b] / h - k
                h00 = 2 * tau**3 - 3 * tau**2 + 1
                h10 = tau**3 - 2 * tau**2 + tau
                h01 = -2 * tau**3 + 3 * tau**2
                h11 = tau**3 - tau**2
                x_T[0, b] = h00 * s + h10 * h * a0 + h01 * s1 + h11 * h * e0
                x_T[1, b] = h00 * th + h10 * h * a1 + h01 * th1 + h11 * h * e1
                x_T[2, b] = h00 * sd + h10 * h * a2 + h01 * sd1 + h11 * h * e2
                x_T[3, b] = h00 * thd + h10 * h * a3 + h01 * thd1 + h11 * h * e3
            s, th, sd, thd = s1, th1, sd1, thd1
    return x_T, s_max


class _Problem:
    """Durations -> (T_F, constraint values), with batched forward-difference Jacobians."""

    def __init__(self, plant: PlantParams, zone: Zone, forces: np.ndarray, cfg: ScheduleSettings):
        self.plant, self.zone, self.forces, self.cfg = plant, zone, forces, cfg
        self._cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def _constraints(self, x_T: np.ndarray, s_max: np.ndarray) -> np.ndarray:
        """Rows: zone margin, track, then the zone's box on each state (all >= 0 when met)."""
        rows = [1.0 - np.asarray(self.zone.value(x_T)) / (self.cfg.zone_margin * self.zone.r),
                1.0 - s_max / (self.cfg.track_margin * self.plant.d / 2.0)]
        if self.zone.half_widths is not None:
            y = wrapped(x_T)
            for i, hw in enumerate(self.zone.half_widths):
                rows.append(1.0 - (y[i] / (self.cfg.zone_margin * hw)) ** 2)
        return np.vstack(rows)

    def _evaluate(self, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = d.tobytes()
        if key not in self._cache:
            n = d.size
            D = np.repeat(d[:, None], n + 1, axis=1)
            D[np.arange(n), np.arange(1, n + 1)] += self.cfg.fd_step_s
            D = np.clip(D, 0.0, None)
            starts = np.vstack([np.zeros((1, n + 1)), np.cumsum(D[:-1], axis=0)])
            T_F = D.sum(axis=0)
            x_T, s_max = _batch_terminal(self.plant, starts, self.forces, T_F, self.cfg.step_s)
            c = self._constraints(x_T, s_max)
            value = c[:, 0]
            jac = (c[:, 1:] - c[:, :1]) / self.cfg.fd_step_s
            self._cache = {key: (value, jac)}
        return self._cache[key]

    def fun(self, d: np.ndarray) -> np.ndarray:
        return self._evaluate(np.asarray(d, dtype=float))[0]

    def jac(self, d: np.ndarray) -> np.ndarray:
        return self._evaluate(np.asarray(d, dtype=float))[1]


def seed_final_time(plant: PlantParams, zone: Zone, seed: Schedule, after: float, cfg: ScheduleSettings,
                    window_s: float = 1.5) -> float:
    """T_F for the seed: where, coasting on after its last switch, the state is deepest in the zone.

    Parameters
    ----------
    plant : PlantParams
        The model the schedule is worked out on.
    zone : Zone
        The hand-off zone.
    seed : Schedule
        The seed table.
    after : float
        The earliest final time looked at (s).
    cfg : ScheduleSettings
        Its grid step is the search's.
    window_s : float
        How long after the last switch the coast is searched (s).

    Returns
    -------
    float
        The seed's final time (s).
    """
    grid = np.arange(max(after, seed.times[-1]), max(after, seed.times[-1]) + window_s, cfg.step_s)
    starts = np.repeat(seed.times[:, None], grid.size, axis=1)
    x_T, _ = _batch_terminal(plant, starts, seed.forces, grid, cfg.step_s)
    return float(grid[int(np.argmin(np.asarray(zone.value(x_T))))])


def optimise_schedule(
    plant: PlantParams,
    zone: Zone,
    seed: Schedule,
    seed_T_F: float,
    settings: ScheduleSettings | None = None,
) -> OptimisedSchedule:
    """Minimum-time switching times from a seed table (force levels and order kept).

    The seed's final time is moved to where its coast goes deepest into the zone, so that the
    search starts from a point that meets the terminal margin when the seed can.

    Parameters
    ----------
    plant : PlantParams
        The model the schedule is worked out on.
    zone : Zone
        The hand-off zone the schedule must end in, with a margin.
    seed : Schedule
        The seed table (normally the supervisory run's).
    seed_T_F : float
        The seed run's time to the zone (s).
    settings : ScheduleSettings, optional
        The optimiser's tuning.

    Returns
    -------
    OptimisedSchedule
        The switching times, the predicted final time and whether the optimiser converged.
    """
    cfg = settings or ScheduleSettings()
    times = seed.times
    forces = seed.forces
    T0 = seed_final_time(plant, zone, seed, seed_T_F, cfg)
    d0 = np.append(np.diff(times), T0 - times[-1])
    problem = _Problem(plant, zone, forces, cfg)
    d, iterations, message = d0.copy(), 0, "seed"
    for _ in range(cfg.rounds):
        # a trust region around the current point: the terminal state is very sensitive to
        # early switching times, so long SLSQP steps leave the feasible set
        lo = np.clip(d - cfg.trust_s, 0.0, None)
        hi = np.minimum(d + cfg.trust_s, np.maximum(cfg.longest_phase_s, 2.0 * d0))
        res = minimize(
            lambda v: float(np.sum(v)), d, jac=lambda v: np.ones_like(v), method="SLSQP",
            bounds=list(zip(lo, hi)),
            constraints=[{"type": "ineq", "fun": problem.fun, "jac": problem.jac}],
            options={"maxiter": cfg.maxiter, "ftol": 1e-6},
        )
        iterations += int(res.nit)
        candidate = np.clip(res.x, lo, hi)
        if np.all(problem.fun(candidate) >= -1e-4) and candidate.sum() < d.sum() - 1e-4:
            d, message = candidate, str(res.message)
        else:
            break
    c = problem.fun(d)
    feasible = bool(np.all(c >= -1e-4))
    if not feasible:
        d, c = d0, problem.fun(d0)
    kept = bool(np.array_equal(d, d0))
    starts = np.concatenate([[0.0], np.cumsum(d[:-1])])
    rows = tuple(
        Switch(s.series, s.phase, s.force_N, round(float(t), 4), "seed" if kept else "optimised")
        for s, t in zip(seed.switches, starts)
    )
    why = ("" if not kept else "no shorter schedule near it meets the zone and track margins" if feasible
           else "it misses the zone or track margin, and no schedule near it meets them")
    return OptimisedSchedule(
        schedule=Schedule(rows), T_F=float(np.sum(d)), seed=seed, seed_T_F=seed_T_F,
        success=bool(feasible and d.sum() < d0.sum()), message=message, iterations=iterations,
        constraints={"zone": float(c[0]), "track": float(c[1])}, kept_seed=kept, why_kept=why,
    )


def replay(
    plant: PlantParams,
    schedule: Schedule,
    zone: Zone,
    force_limit: float,
    K: np.ndarray | None = None,
    *,
    t_max: float = PUMP_T_MAX_S,
    hold_s: float = HOLD_S,
    dt: float = STEP_S,
) -> SwingUpResult:
    """Play a schedule open-loop on a plant; hand off to sat(-K x) when the zone is entered.

    Parameters
    ----------
    plant : PlantParams
        The plant simulated.
    schedule : Schedule
        The switching table.
    zone : Zone
        The hand-off zone.
    force_limit : float
        Largest force (N), for the hold.
    K : array_like, optional
        Gain of the hold; without one the run ends at the hand-off.
    t_max, hold_s, dt : float
        Longest pump-up, hold after hand-off and step (s).

    Returns
    -------
    SwingUpResult
        The run.
    """
    hold = None if K is None else saturated_state_feedback(K, force_limit)
    return simulate(plant, ScheduleReplay(schedule, dt), zone, strategy="schedule",
                    force_limit=force_limit, hold=hold, t_max=t_max, hold_s=hold_s, dt=dt)


@dataclass(frozen=True)
class SensitivityRow:
    """One perturbed plant: which parameter, by what factor, and what the schedule did there."""

    parameter: str
    factor: float
    reached: bool
    time_to_zone_s: float | None
    max_abs_s_m: float
    on_track: bool


def perturbed_plants(plant: PlantParams, by: float = PARAMETER_ERROR, parameters=PARAMETERS):
    """Each parameter off by -by and +by, one at a time.

    Parameters
    ----------
    plant : PlantParams
        The nominal plant.
    by : float
        The fractional error (PARAMETER_ERROR).
    parameters : sequence of str
        The parameters put off (PARAMETERS).

    Yields
    ------
    (str, float, PlantParams)
        Parameter name, its factor and the plant with it.
    """
    for name in parameters:
        for f in (1.0 - by, 1.0 + by):
            yield name, f, plant.scaled(**{name: f})


def schedule_sensitivity(
    plant: PlantParams,
    schedule: Schedule,
    zone: Zone,
    force_limit: float,
    *,
    by: float = PARAMETER_ERROR,
    t_max: float = PUMP_T_MAX_S,
) -> list[SensitivityRow]:
    """Replay the schedule open-loop on plants with M, m, l, b_VF, c off by +/-by.

    Parameters
    ----------
    plant : PlantParams
        The nominal plant the schedule was worked out on.
    schedule : Schedule
        The switching table.
    zone : Zone
        The hand-off zone.
    force_limit : float
        Largest force (N).
    by, t_max : float
        The parameter error, and the longest pump-up (s).

    Returns
    -------
    list of SensitivityRow
        Per perturbed plant: reached, time to the zone, cart excursion, on the track.
    """
    rows = []
    for name, f, p in perturbed_plants(plant, by):
        r = replay(p, schedule, zone, force_limit, t_max=t_max, hold_s=0.0)
        rows.append(SensitivityRow(name, f, r.reached, r.handoff_time, r.max_abs_s_pump, r.on_track))
    return rows
