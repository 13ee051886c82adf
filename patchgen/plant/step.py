"""Fixed-step RK4 for the nonlinear plant with a force held over the step.

Switching logic (supervisor, energy law, schedules) is sampled at the step rate, like a digital
sequencer would be; a fixed step keeps runs deterministic and lets a batch of states (4xN) advance
together.
"""

from __future__ import annotations

import numpy as np

from patchgen.plant.equations import PlantParams, nonlinear_rhs


def rk4_step(plant: PlantParams, x: np.ndarray, force: float | np.ndarray, h: float) -> np.ndarray:
    """One RK4 step of eq. 2.16-2.19 with the force held constant over the step.

    Parameters
    ----------
    plant : PlantParams
        The plant.
    x : ndarray, shape (4,) or (4, N)
        State [s, theta, s_dot, theta_dot] (SI), or N states advanced together.
    force : float or ndarray, shape (N,)
        Force on the cart over the step (N).
    h : float
        Step (s).

    Returns
    -------
    ndarray
        The state after the step, shaped like ``x``.
    """
    k1 = nonlinear_rhs(plant, x, force)
    k2 = nonlinear_rhs(plant, x + 0.5 * h * k1, force)
    k3 = nonlinear_rhs(plant, x + 0.5 * h * k2, force)
    k4 = nonlinear_rhs(plant, x + h * k3, force)
    return x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
