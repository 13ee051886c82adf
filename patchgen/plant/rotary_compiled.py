"""The rotary pendulum's equations compiled with numba, for loops that run many plants side by
side (patchgen.bench.kernel's lanes): patchgen.plant.rotary_equations.nonlinear_rhs term for term,
in the same order, so that the two agree to rounding (tests/plant/test_rotary.py); and the form the
kernel's lanes take, per-plant constants (``rotary_coefficients``) read by ``rotary_accel`` with a
torque on the arm and a force at the pendulum's tip beside the motor's voltage.

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

ROTARY_VECTOR = ("m_r", "L_r", "l_r", "J_r", "m_p", "l_p", "J_p", "g", "D_r", "D_p", "R_m", "k_t", "k_m", "L_p",
                 "alpha_limit")
P_ARM_LIMIT = ROTARY_VECTOR.index("alpha_limit")  # where the cable winds up (rad): a run's end
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


N_ROTARY_COEF = 9  # per-plant constants rotary_accel reads (rotary_coefficients)


@nb.njit(inline="always", **_JIT)
def rotary_coefficients(p, out):
    """The per-run constants of the equations from p (ROTARY_VECTOR), into out: J_0, J_2, K, G, the
    arm's damping with the back-EMF's, the pendulum's damping, the torque per volt, and the arm's
    and the pendulum's lengths (the levers of a force at the pendulum's tip)."""
    m_r, L_r, l_r, J_r, m_p, l_p, J_p, g = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    D_r, D_p, R_m, k_t, k_m = p[8], p[9], p[10], p[11], p[12]
    out[0] = J_r + m_r * l_r * l_r + m_p * L_r * L_r
    out[1] = J_p + m_p * l_p * l_p
    out[2] = m_p * L_r * l_p
    out[3] = m_p * g * l_p
    out[4] = D_r + k_t * k_m / R_m
    out[5] = D_p
    out[6] = k_t / R_m
    out[7] = L_r
    out[8] = p[13]


@nb.njit(inline="always", **_JIT)
def rotary_accel(q, i, sn, cs, ad, thd, V_m, torque, tip):
    """(alpha_ddot, theta_ddot) with coefficients q[:, i] at sin and cos of theta and the rates
    ``ad``, ``thd``, under the motor voltage V_m, a torque on the arm about the motor's axis (N m)
    and a horizontal force at the pendulum's tip along the arm tip's path (N): generalised forces
    tip L_r on alpha and tip L_p cos(theta) on theta."""
    J_0, J_2, K, G = q[0, i], q[1, i], q[2, i], q[3, i]
    m11, m12 = J_0 + J_2 * sn * sn, K * cs
    f1 = q[6, i] * V_m - q[4, i] * ad + torque + tip * q[7, i] - (2.0 * J_2 * sn * cs * ad * thd - K * sn * thd * thd)
    f2 = -q[5, i] * thd + J_2 * sn * cs * ad * ad + G * sn + tip * q[8, i] * cs
    det = m11 * J_2 - m12 * m12
    return (J_2 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det
