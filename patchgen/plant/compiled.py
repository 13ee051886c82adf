"""The plant's equations compiled with numba, for loops that run many plants side by side
(patchgen.bench.kernel's lanes, patchgen.swingup.schedule's batches): eq. 2.16-2.19 as
patchgen.plant.equations.nonlinear_rhs, with a horizontal force at the pendulum tip, and a sine
and cosine by arithmetic so that such loops vectorise.

A plant is a vector of PLANT_VECTOR's parameters; ``plant_coefficients`` turns it into the
N_COEF per-plant constants ``plant_accel`` reads (one column per plant).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

# cached on disk; IEEE arithmetic, no Python exceptions for x / 0 (as patchgen.bench.kernel's)
_JIT = {"cache": True, "error_model": "numpy"}

PLANT_VECTOR = ("M", "m", "l", "g", "b_VF", "c", "half_track", "J", "F_C")  # a plant as the compiled loops take it
P_HALF_TRACK = PLANT_VECTOR.index("half_track")  # where the limit switches are (d/2)
P_J = PLANT_VECTOR.index("J")
P_F_C = PLANT_VECTOR.index("F_C")
VECTOR_PARAMETERS = ("M", "m", "l", "g", "b_VF", "c", "d", "J", "F_C")  # the PlantParams field behind each entry


def plant_vector(plant) -> np.ndarray:
    """A PlantParams as the compiled loops take it (PLANT_VECTOR: d as the track's half length)."""
    return np.array([plant.d / 2 if k == "d" else getattr(plant, k) for k in VECTOR_PARAMETERS], dtype=np.float64)

_TWO_OVER_PI = 2.0 / math.pi
_PIO2_A = math.ldexp(math.floor(math.ldexp(math.pi / 2, 30)), -30)  # 31 bits: k * _PIO2_A exact
_PIO2_B = math.pi / 2 - _PIO2_A  # the rest of the double nearest pi/2 (an exact difference)
_PIO2_C = 6.123233995736766e-17  # pi/2 minus that double
# Taylor coefficients, highest order first: sin r = r + r z (S1 + z S2 + ...), cos r = 1 + z (C1 + ...)
_SIN = tuple((-1) ** k / math.factorial(2 * k + 1) for k in range(8, 0, -1))
_COS = tuple((-1) ** k / math.factorial(2 * k) for k in range(9, 0, -1))


@nb.njit(inline="always", **_JIT)
def sincos(x):
    """(sin x, cos x) by arithmetic alone, so that a loop over lanes vectorises (libm's are
    scalar calls): reduction by pi/2 in three parts, then Taylor series on |r| <= pi/4, where the
    first omitted terms are below 1e-19. Within a few ulp of libm for |x| < 1e5."""
    k = math.floor(x * _TWO_OVER_PI + 0.5)
    r = ((x - k * _PIO2_A) - k * _PIO2_B) - k * _PIO2_C
    z = r * r
    ps = 0.0
    for a in _SIN:
        ps = ps * z + a
    pc = 0.0
    for a in _COS:
        pc = pc * z + a
    s = r + r * z * ps
    c = 1.0 + z * pc
    q = np.int64(k)  # the quadrant, by selects (a return per quadrant stops vectorisation)
    swap = (q & 1) != 0
    sn = c if swap else s
    cs = s if swap else c
    return (-sn if q & 2 else sn), (-cs if (q + 1) & 2 else cs)


N_COEF = 12  # per-plant constants of eq. 2.16-2.19 (plant_coefficients)


@nb.njit(inline="always", **_JIT)
def plant_coefficients(p, out):
    """The per-run constants of eq. 2.16-2.19 from p (PLANT_VECTOR), into out: with the swing
    length L = l + J/(m l) and r = l/L as patchgen.plant.equations has them (J = 0: the thesis's)."""
    M, m, l, g, b, c = p[0], p[1], p[2], p[3], p[4], p[5]
    L = l + p[P_J] / (m * l)
    r = l / L
    out[0], out[1], out[2], out[3], out[4] = M + m, m * r, m * l, c / L, m * g * r
    out[5], out[6], out[7], out[8], out[9] = b, -c / (m * l * L), g / L, 1.0 / (m * L), 1.0 / L
    out[10] = 1.0 - r
    out[11] = p[P_F_C]


@nb.njit(inline="always", **_JIT)
def plant_accel(q, i, sn, cs, sd, thd, force, tip):
    """(s_ddot, theta_ddot) of eq. 2.16-2.19 with coefficients q[:, i], plus a horizontal force at
    distance l on the pendulum: generalised forces tip on s and tip * l * cos(theta) on theta."""
    den = q[0, i] - q[1, i] * cs * cs
    coulomb = q[11, i] * (1.0 if sd > 0.0 else (-1.0 if sd < 0.0 else 0.0))  # against the cart's motion
    bracket = -q[5, i] * sd + q[2, i] * thd * thd * sn + q[3, i] * thd * cs - q[4, i] * sn * cs + force - coulomb
    sdd = (bracket + (tip * sn * sn + tip * q[10, i] * cs * cs)) / den  # q[10] = 1 - r: 0 for a point mass
    return sdd, q[6, i] * thd + q[7, i] * sn + tip * cs * q[8, i] - cs * sdd * q[9, i]


@nb.njit(**_JIT)
def plant_rhs(p, th, sd, thd, force, tip_force):
    """(ds, dtheta, ds_dot, dtheta_dot) as the kernel computes them (p: PLANT_VECTOR)."""
    q = np.empty((N_COEF, 1))
    plant_coefficients(p, q[:, 0])
    sn, cs = sincos(th)
    sdd, thdd = plant_accel(q, 0, sn, cs, sd, thd, force, tip_force)
    return sd, thd, sdd, thdd
