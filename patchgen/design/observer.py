"""The reduced-order observer: the unmeasured states (theta_dot, and the actuator state when the
design has one) from s, theta, s_dot and the commanded force, shaped to be cheap to patch.

Partition the design model into measured y = (s, theta, s_dot) and unmeasured w. The observer
(Luenberger's reduced form) carries z = w_hat - Lr y:

    z' = F z + G y + H u,   F = A_ww - Lr A_yw,  G = F Lr + A_wy - Lr A_yy,  H = B_w - Lr B_y,

and the control law uses w_hat = z + Lr y, so Lr's part of the law folds into the u_c summer's
coefficients on the sensors: u = -(K_y + K_w Lr) y - K_w z. Lr is chosen so that

- Lr has no column on s (s never enters the observer: G and H have no s terms either);
- F is triangular with both diagonal entries -pole (the errors decay at the chosen rate), so
  each z is one lag amplifier whose own feedback is its R||C time constant, with no pot;
- theta_dot's z takes no s_dot input (G[theta_dot, s_dot] = 0): the tachometer's ripple reaches
  theta_dot only through the actuator estimate, which it corrects (it sees the dead zone's
  missing force, which a lag model of u_c cannot).

Those conditions are linear in Lr except the last, which is quadratic along the one-parameter
family the others leave; its smallest real root is used.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from patchgen.design.controller import Controller, ReducedObserver, integrator_part
from patchgen.design.model import LinearModel

FIT_TOL = 1e-9  # relative: the structure's linear conditions hold to rounding, and a root is real
QUADRATIC_MIN = 1e-14  # below this leading coefficient the s_dot condition is linear in the free gain


class ObserverError(ValueError):
    """No observer gain meets the patchable structure at this pole."""


def unmeasured_states(model: LinearModel) -> tuple[str, ...]:
    """The estimated states the sensors do not measure (theta_dot, and the actuator's)."""
    return tuple(s for s in model.estimated if s not in model.measured)


def reduced_observer(model: LinearModel, pole: float) -> ReducedObserver:
    """The structured reduced observer of the design model with error decay rate ``pole`` (rad/s)."""
    y = list(model.measured)
    w = list(unmeasured_states(model))
    position = model.plant.position
    if model.plant.rate_of[position] not in y:
        raise ObserverError(f"the reduced observer is built for a measured {model.plant.rate_of[position]}: without "
                            "one, a differentiator or a Kalman filter finds it")
    iy = [model.index(s) for s in y]
    iw = [model.index(s) for s in w]
    A, B = model.A, model.B[:, 0]
    Ayy, Ayw = A[np.ix_(iy, iy)], A[np.ix_(iy, iw)]
    Awy, Aww = A[np.ix_(iw, iy)], A[np.ix_(iw, iw)]
    By, Bw = B[iy], B[iw]
    nw, ny = len(w), len(y)
    free = [(r, c) for r in range(nw) for c in range(ny) if y[c] != position]

    def lr_of(p):
        L = np.zeros((nw, ny))
        for k, (r, c) in enumerate(free):
            L[r, c] = p[k]
        return L

    def F_of(p):
        return Aww - lr_of(p) @ Ayw

    # linear conditions on F: diagonal = -pole, strictly lower part = 0
    want = [((r, r), -pole) for r in range(nw)] + [((r, c), 0.0) for r in range(nw) for c in range(r)]
    n = len(free)
    base = F_of(np.zeros(n))
    M = np.array([[F_of(np.eye(n)[k])[rc] - base[rc] for k in range(n)] for rc, _ in want])
    rhs = np.array([v - base[rc] for rc, v in want])
    p0 = np.linalg.lstsq(M, rhs, rcond=None)[0]
    null = sla.null_space(M)
    if null.shape[1] != 1 or not np.allclose(M @ p0, rhs, atol=FIT_TOL * max(1.0, pole)):
        raise ObserverError("the unmeasured states cannot be given the observer's structure")
    v = null[:, 0]
    rate = model.plant.rate_of[position]
    it, iv = w.index(model.plant.angle_rate), y.index(rate)

    def g(t):
        p = p0 + t * v
        L, F = lr_of(p), F_of(p)
        return (F @ L + Awy - L @ Ayy)[it, iv]

    # g is quadratic in t: fit through three points, take the real root nearest zero
    ts = np.array([-1.0, 0.0, 1.0])
    coef = np.polyfit(ts, [g(t) for t in ts], 2)
    if abs(coef[0]) > QUADRATIC_MIN:
        roots = [r.real for r in np.roots(coef) if abs(r.imag) < FIT_TOL * max(1.0, abs(r))]
    else:
        roots = [-coef[2] / coef[1]] if abs(coef[1]) > 0 else []
    if not roots:
        raise ObserverError(f"no real observer gain keeps {rate} out of {model.plant.angle_rate} at pole {pole:g} "
                            "rad/s")
    t = min(roots, key=abs)
    p = p0 + t * v
    L, F = lr_of(p), F_of(p)
    G = F @ L + Awy - L @ Ayy
    H = Bw - L @ By
    return ReducedObserver(tuple(w), L, F, G, H, pole)


def reduced_observer_controller(model: LinearModel, K: np.ndarray, obs: ReducedObserver) -> Controller:
    """The whole law with the reduced observer: states z (one per unmeasured state) then the
    integral states; u = -(K_y + K_w Lr) y - K_w z - K_i x_i."""
    Ky = K[:, [model.index(s) for s in model.measured]]
    Kw = K[:, [model.index(s) for s in obs.unmeasured]]
    ip = integrator_part(model, K)
    nw, ni = len(obs.unmeasured), len(ip.names)
    Cc = -np.hstack([Kw, ip.Ki])
    Dc = -(Ky + Kw @ obs.Lr)
    H = obs.H.reshape(-1, 1)
    Ac = np.zeros((nw + ni, nw + ni))
    Ac[:nw, :nw] = obs.F
    Ac[:nw] += H @ Cc
    Ac[nw:, nw:] = ip.Ai
    Bc = np.vstack([obs.G + H @ Dc, ip.Ei])
    return Controller(tuple(f"z_{s}" for s in obs.unmeasured) + ip.names, Ac, Bc, Cc, Dc)
