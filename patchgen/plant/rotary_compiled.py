"""The rotary pendulum's equations compiled with numba, for loops that will run many plants side
by side: patchgen.plant.rotary_equations.nonlinear_rhs term for term, in the same order, so that
the two agree to rounding (tests/plant/test_rotary.py).

A plant is a vector of ROTARY_VECTOR's figures, its rods' centres of mass and inertias resolved
(``rotary_vector``).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from patchgen.plant.rotary_equations import RotaryParams

# cached on disk; IEEE arithmetic, no Python exceptions for x / 0 (as patchgen.plant.compiled's)
_JIT = {"cache": True, "error_model": "numpy"}

ROTARY_VECTOR = ("m_r", "L_r", "l_r", "J_r", "m_p", "l_p", "J_p", "g", "D_r", "D_p", "R_m", "k_t", "k_m")
# the RotaryParams figure behind each entry: a method where a rod's default may stand in
_RESOLVED = {"l_r": RotaryParams.arm_com, "J_r": RotaryParams.arm_inertia, "l_p": RotaryParams.pendulum_com,
             "J_p": RotaryParams.pendulum_inertia}


def rotary_vector(plant: RotaryParams) -> np.ndarray:
    """A RotaryParams as the compiled loops take it (ROTARY_VECTOR, rods resolved)."""
    return np.array([_RESOLVED[k](plant) if k in _RESOLVED else getattr(plant, k) for k in ROTARY_VECTOR],
                    dtype=np.float64)


@nb.njit(**_JIT)
def rotary_rhs(p, th, ad, thd, V_m):
    """(dalpha, dtheta, dalpha_dot, dtheta_dot) at theta ``th`` and rates ``ad``, ``thd`` under the
    motor voltage ``V_m`` (p: ROTARY_VECTOR); the arm's angle enters nothing."""
    m_r, L_r, l_r, J_r, m_p, l_p, J_p, g = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    D_r, D_p, R_m, k_t, k_m = p[8], p[9], p[10], p[11], p[12]
    J_0 = J_r + m_r * l_r * l_r + m_p * L_r * L_r
    J_2 = J_p + m_p * l_p * l_p
    K = m_p * L_r * l_p
    G = m_p * g * l_p
    sin, cos = math.sin(th), math.cos(th)
    m11, m12, m22 = J_0 + J_2 * sin * sin, K * cos, J_2  # the mass matrix
    v1 = 2.0 * J_2 * sin * cos * ad * thd - K * sin * thd * thd  # Coriolis and centripetal terms
    v2 = -J_2 * sin * cos * ad * ad
    g2 = -G * sin  # the potential's gradient (none on the arm)
    tau = k_t * (V_m - k_m * ad) / R_m
    f1 = (tau - D_r * ad) - v1
    f2 = (-D_p * thd) - v2 - g2
    det = m11 * m22 - m12 * m12
    return ad, thd, (m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det
