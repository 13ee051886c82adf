"""The hand-off zone: the region of state space where the linear controller takes over (thesis 3.5).

The thesis asks for a "zone of control" in which the linear controller is effective, judged by a
cost on the non-homogeneous states. Here the zone is a level set of a quadratic form
``x^T P x < r`` (optionally intersected with a box), with the angle wrapped to (-pi, pi] so that
"upright" is the same after any number of turns. ``r`` is estimated by sampling: the largest level
containing no sampled start from which the controller fails to recover.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_continuous_lyapunov

from patchgen.plant.equations import PlantParams, linear_matrices
from patchgen.plant.step import rk4_step

STATE_COUNT = 4
# the zone's level sits this far below the first failing start: sampling finds the boundary only
# to within the gaps between its samples, so a 10 % margin keeps the zone inside it
ZONE_SHRINK = 0.9
SAMPLED_ANGLE_RAD = 0.5  # the sampled box's angle half-width (about 29 deg): well past the
#                          linear design's small angles, so the boundary lies inside the box
PROBED_ZONE_SAMPLES = 300  # starts tried one by one (each a simulated recovery): seconds, not minutes
BATCH_ZONE_SAMPLES = 2000  # starts of the vectorised model check: cheap, so a denser sample


def wrap_angle(theta: np.ndarray | float) -> np.ndarray | float:
    """Angle wrapped to [-pi, pi): 0 is upright after any number of turns."""
    return (np.asarray(theta) + np.pi) % (2.0 * np.pi) - np.pi


def wrapped(x: np.ndarray) -> np.ndarray:
    """The state (4 or 4xN) with its angle wrapped about upright."""
    y = np.array(x, dtype=float, copy=True)
    y[1] = wrap_angle(y[1])
    return y


@dataclass(frozen=True)
class Zone:
    """Hand-off zone: ``x^T P x < r`` (angle wrapped), and inside ``half_widths`` if given."""

    P: np.ndarray
    r: float
    half_widths: tuple[float, float, float, float] | None = None
    source: str = ""
    samples: int = 0
    failures: int = 0

    def value(self, x: np.ndarray) -> np.ndarray | float:
        """The quadratic form for a state (4,) or a batch (4, N)."""
        y = wrapped(x)
        if y.ndim == 1:
            return float(y @ self.P @ y)
        return np.einsum("in,ij,jn->n", y, self.P, y)

    def contains(self, x: np.ndarray) -> bool | np.ndarray:
        """Whether a state (4,) is in the zone, or which of a batch (4, N) are."""
        inside = np.asarray(self.value(x)) < self.r
        if self.half_widths is not None:
            y = wrapped(x)
            h = np.asarray(self.half_widths, dtype=float)
            box = np.all(np.abs(y) < (h if y.ndim == 1 else h[:, None]), axis=0)
            inside = inside & box
        return bool(inside) if np.ndim(inside) == 0 else inside

    @staticmethod
    def box(half_widths: tuple[float, float, float, float], source: str = "box") -> Zone:
        """A zone given by bounds only (e.g. |theta| < 10 deg and the rest)."""
        h = np.asarray(half_widths, dtype=float)
        return Zone(P=np.diag(1.0 / h**2), r=float(STATE_COUNT), half_widths=tuple(map(float, h)),
                    source=source)


def lyapunov_matrix(
    plant: PlantParams, K: np.ndarray, force_limit: float, weights: np.ndarray | None = None
) -> np.ndarray:
    """P with (A-BK)^T P + P (A-BK) = -(Q_L + K^T K / F_max^2): the closed loop's cost-to-go for
    states weighted by Q_L = diag(weights) (default 1/spread^2) and force by the force limit,
    so that directions that saturate the actuator count as far from upright.

    Parameters
    ----------
    plant : PlantParams
        The plant linearised about upright.
    K : array_like
        State-feedback gain; its first four entries (s, theta, s_dot, theta_dot) are used.
    force_limit : float
        Largest force (N).
    weights : array_like, optional
        The diagonal of Q_L.

    Returns
    -------
    numpy.ndarray
        The symmetric 4 x 4 matrix P.
    """
    A, B = linear_matrices(plant)
    w = default_spread(plant) ** -2.0 if weights is None else np.asarray(weights, dtype=float)
    return closed_loop_cost(A, B, K, force_limit, w)


def closed_loop_cost(A: np.ndarray, B: np.ndarray, K: np.ndarray, input_limit: float,
                     weights: np.ndarray) -> np.ndarray:
    """P with (A-BK)^T P + P (A-BK) = -(diag(weights) + K^T K / input_limit^2), for any plant's
    linear model about upright (the cart's force, the rotary pendulum's voltage).

    Parameters
    ----------
    A, B : numpy.ndarray
        The linear model, 4 x 4 and 4 x 1.
    K : array_like
        State-feedback gain; its first four entries are used.
    input_limit : float
        The input's largest magnitude (N or V): an input that saturates counts as far from upright.
    weights : array_like
        The diagonal of the states' weight.

    Returns
    -------
    numpy.ndarray
        The symmetric 4 x 4 matrix P.
    """
    k = np.asarray(K, dtype=float).ravel()[:STATE_COUNT]
    Acl = A - B @ k[None, :]
    P = solve_continuous_lyapunov(Acl.T, -(np.diag(np.asarray(weights, dtype=float)) + np.outer(k, k) / input_limit**2))
    return 0.5 * (P + P.T)


def default_spread(plant: PlantParams) -> np.ndarray:
    """Half-widths of the sampling box: half the track, SAMPLED_ANGLE_RAD, and the speeds these
    imply at the pendulum's natural frequency."""
    half_track = plant.d / 2.0
    omega = np.sqrt(plant.g / plant.swing_length())
    theta = SAMPLED_ANGLE_RAD
    return np.array([half_track, theta, half_track * omega, theta * omega])


def estimate_zone(
    controller_recovers: Callable[[np.ndarray], bool],
    P: np.ndarray,
    spread: np.ndarray,
    *,
    n_samples: int = PROBED_ZONE_SAMPLES,
    seed: int = 0,
    shrink: float = ZONE_SHRINK,
    source: str = "sampled",
) -> Zone:
    """Estimate r for ``x^T P x < r``: sample starts in the box +/-spread, try them in order of
    increasing x^T P x, and stop at the first one the controller does not recover from. The zone
    is also cut to the sampled box: nothing outside it was tried.

    Parameters
    ----------
    controller_recovers : callable
        Whether the controller recovers from a start (4,).
    P : numpy.ndarray
        The quadratic form of the zone.
    spread : array_like
        Half-widths of the sampled box.
    n_samples, seed : int
        How many starts, and the seed they are drawn with.
    shrink : float
        The level kept, as a fraction of the first failing start's.
    source : str
        What the zone was found with (shown with it).

    Returns
    -------
    Zone
        The zone, with the number of starts tried and whether one failed.
    """
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1.0, 1.0, size=(STATE_COUNT, n_samples)) * np.asarray(spread, dtype=float)[:, None]
    V = np.einsum("in,ij,jn->n", X, P, X)
    box = tuple(float(h) for h in spread)
    order = np.argsort(V)
    tried = 0
    for k in order:
        tried += 1
        if not controller_recovers(X[:, k]):
            return Zone(P=P, r=float(shrink * V[k]), half_widths=box, source=source, samples=tried,
                        failures=1)
    return Zone(P=P, r=float(V[order[-1]]), half_widths=box, source=source, samples=tried, failures=0)


def zone_from_batch(
    recovered: np.ndarray, X: np.ndarray, P: np.ndarray, *, shrink: float = ZONE_SHRINK, source: str = "sampled"
) -> Zone:
    """The zone from a batch already simulated: r below the smallest level of a failing start.

    Parameters
    ----------
    recovered : numpy.ndarray of bool
        Whether each start recovered.
    X : numpy.ndarray
        The starts (4, N).
    P : numpy.ndarray
        The quadratic form of the zone.
    shrink : float
        The level kept, as a fraction of the smallest failing start's.
    source : str
        What the zone was found with.

    Returns
    -------
    Zone
        The zone, cut to the box the starts span.
    """
    V = np.einsum("in,ij,jn->n", X, P, X)
    fails = V[~recovered]
    r = float(shrink * fails.min()) if fails.size else float(V.max())
    half_widths = tuple(float(h) for h in np.max(np.abs(X), axis=1))
    return Zone(P=P, r=r, half_widths=half_widths, source=source, samples=int(X.shape[1]),
                failures=int(fails.size))


@dataclass(frozen=True)
class RecoveryTest:
    """What "recovers" means: the cart stays on the track and the state settles within tolerances."""

    horizon_s: float = 6.0
    dt_s: float = 2e-3
    settle: tuple[float, float, float, float] = (0.05, 0.01, 0.05, 0.05)


def state_feedback_recovers_batch(
    plant: PlantParams,
    K: np.ndarray,
    force_limit: float,
    X0: np.ndarray,
    test: RecoveryTest = RecoveryTest(),
) -> np.ndarray:
    """Simulate u = sat(-K x) (angle wrapped) from each column of X0 on the nonlinear plant (RK4).

    Parameters
    ----------
    plant : PlantParams
        The nonlinear plant.
    K : array_like
        State-feedback gain (its first four entries).
    force_limit : float
        Largest force (N).
    X0 : numpy.ndarray
        Starts (4, N).
    test : RecoveryTest
        Horizon, step and the tolerances a recovered state settles within.

    Returns
    -------
    numpy.ndarray of bool
        Per start: on the track throughout and settled at the horizon.
    """
    k = np.asarray(K, dtype=float).ravel()[:STATE_COUNT]
    x = np.array(X0, dtype=float, copy=True)
    h = test.dt_s
    half_track = plant.d / 2.0
    on_track = np.ones(x.shape[1], dtype=bool)

    def force(y: np.ndarray) -> np.ndarray:
        return np.clip(-(k @ wrapped(y)), -force_limit, force_limit)

    for _ in range(int(round(test.horizon_s / h))):
        x = rk4_step(plant, x, force(x), h)
        on_track &= np.abs(x[0]) < half_track
    settled = np.all(np.abs(wrapped(x)) < np.asarray(test.settle)[:, None], axis=0)
    return on_track & settled


def lqr_zone(
    plant: PlantParams,
    K: np.ndarray,
    force_limit: float,
    *,
    P: np.ndarray | None = None,
    n_samples: int = BATCH_ZONE_SAMPLES,
    seed: int = 0,
    shrink: float = ZONE_SHRINK,
    test: RecoveryTest = RecoveryTest(),
) -> Zone:
    """Default zone from a linear design: a Lyapunov level set of A-BK, its level found by
    simulating u = -K x (force-limited) on the nonlinear plant from sampled starts.

    Parameters
    ----------
    plant, K, force_limit
        As for state_feedback_recovers_batch.
    P : numpy.ndarray, optional
        The quadratic form (default: lyapunov_matrix of the design).
    n_samples, seed : int
        How many starts, and the seed they are drawn with.
    shrink : float
        The level kept, as a fraction of the smallest failing start's.
    test : RecoveryTest
        What counts as recovered.

    Returns
    -------
    Zone
        The hand-off zone of the linear design.
    """
    P = lyapunov_matrix(plant, K, force_limit) if P is None else np.asarray(P, dtype=float)
    rng = np.random.default_rng(seed)
    spread = default_spread(plant)
    X = rng.uniform(-1.0, 1.0, size=(STATE_COUNT, n_samples)) * spread[:, None]
    ok = state_feedback_recovers_batch(plant, K, force_limit, X, test)
    return zone_from_batch(ok, X, P, shrink=shrink, source="lqr-lyapunov")
