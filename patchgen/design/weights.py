"""The LQR weights a spec states, as the matrices the design takes: Q over the spec's states and R
on the plant's input, from named weights, a full matrix, Bryson's rule (thesis eq. 4.9 and 4.10) or
a weight per command volt (R_V)."""

from __future__ import annotations

import numpy as np

from patchgen.inputs.spec import DesignSpec


def q_matrix(spec: DesignSpec) -> np.ndarray:
    """The state weight Q over the spec's states (Bryson's rule when the spec asks for it).

    Parameters
    ----------
    spec : DesignSpec
        A checked spec.

    Returns
    -------
    ndarray, shape (n, n)
        Q in the order of ``spec.states()``: diagonal from named weights or 1/excursion^2
        (eq. 4.9), or the spec's full matrix.
    """
    states = spec.states()
    n = len(states)
    w = spec.weights
    if w.bryson is not None:
        Q = np.zeros((n, n))
        for name, sigma in w.bryson.items():
            if name == "u":
                continue
            Q[states.index(name), states.index(name)] = 1.0 / sigma**2
        return Q
    if isinstance(w.Q, dict):
        Q = np.zeros((n, n))
        for name, q in w.Q.items():
            Q[states.index(name), states.index(name)] = q
        return Q
    return np.array(w.Q, dtype=float)


def r_matrix(spec: DesignSpec) -> np.ndarray:
    """The control weight R as a 1 x 1 matrix (1/u_max^2 under Bryson's rule, eq. 4.10)."""
    w = spec.weights
    if w.bryson is not None:
        return np.array([[1.0 / w.bryson["u"] ** 2]])
    if w.R_V is not None:  # u = K_U u_c: a weight per volt squared is R_V / K_U^2 per newton squared
        return np.array([[float(w.R_V) / spec.actuator.K_U ** 2]])
    return np.array([[float(w.R)]])
