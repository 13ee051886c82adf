"""The cart-pendulum plant: physical parameters, nonlinear (eq. 2.16-2.19) and linear (eq. 2.28) models.

States in SI units: s (m), theta (rad, 0 = upright), s_dot (m/s), theta_dot (rad/s).
Input: the force F_U on the cart (N).

The pendulum is a rigid body: mass m, centre of mass at l from the pivot, moment of inertia J
about it (the thesis's point mass is J = 0). With I = J + m l^2 about the pivot, the equations of
motion are (M + m) s'' + m l cos(theta) theta'' - m l sin(theta) theta'^2 = F - b_VF s' and
I theta'' + m l cos(theta) s'' - m g l sin(theta) = -c theta', with Coulomb friction F_C sign(s')
on the cart beside the viscous b_VF s' when the plant has it. They are written with the swing
length L = I / (m l) = l + J / (m l) and r = l / L, so that J = 0 (L = l, r = 1) takes exactly the
thesis's floating-point operations.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from patchgen.plant.cart_pendulum import STATE_NAMES

PLANT_STATES = STATE_NAMES  # s, theta, s_dot, theta_dot (patchgen.plant.cart_pendulum)


@dataclass(frozen=True)
class PlantParams:
    """The plant's physical parameters (thesis table B.1), SI units.

    Attributes
    ----------
    M, m : float
        Cart and pendulum masses (kg).
    l : float
        Effective pendulum length (m).
    g : float
        Gravity (m/s^2).
    b_VF : float
        Cart friction (N s/m).
    c : float
        Pendulum pivot friction (N m s).
    d : float
        Track length between the limit switches (m).
    J : float
        The pendulum's moment of inertia about its centre of mass (kg m^2); 0 for a point mass.
    F_C : float
        The cart's Coulomb friction (N), opposing its motion; 0 for viscous friction alone. Not in
        the linear model (it has no slope at rest): the nonlinear equations and the bench have it.
    """

    M: float
    m: float
    l: float
    g: float
    b_VF: float
    c: float
    d: float
    J: float = 0.0
    F_C: float = 0.0

    def swing_length(self) -> float:
        """L = I / (m l) = l + J / (m l): the length of the point mass that swings as this pendulum."""
        return self.l + self.J / (self.m * self.l)

    def scaled(self, **factors: float) -> PlantParams:
        """A copy with named parameters multiplied by the given factors (for sweeps).

        Parameters
        ----------
        **factors : float
            Parameter name -> factor, e.g. ``M=1.1`` for a cart 10 % heavier.

        Returns
        -------
        PlantParams
            The perturbed plant; this one is unchanged.
        """
        return replace(self, **{k: getattr(self, k) * f for k, f in factors.items()})


def push_shares(p: PlantParams, arm_m: float) -> tuple[float, float]:
    """Where a horizontal push on the pendulum at ``arm_m`` from the pivot acts, as the
    simulator applies pushes: (the share that acts as a push on the cart, the share that acts at
    l). Its generalised forces are F on s and F arm cos(theta) on theta; a push at l has F and
    F l cos(theta), one on the cart F and 0: so F at arm is (1 - arm/l) F on the cart and
    (arm/l) F at l, exactly, at any angle."""
    k = arm_m / p.l
    return 1.0 - k, k


def linear_matrices(p: PlantParams) -> tuple[np.ndarray, np.ndarray]:
    """The plant linearised about upright (eq. 2.28): x' = A x + B F_U.

    Parameters
    ----------
    p : PlantParams
        The plant.

    Returns
    -------
    A : ndarray, shape (4, 4)
        State matrix over s, theta, s_dot, theta_dot.
    B : ndarray, shape (4, 1)
        Input matrix for the cart force F_U (N).
    """
    M, m, l, g, b, c = p.M, p.m, p.l, p.g, p.b_VF, p.c
    L = p.swing_length()
    r = l / L
    den = M + m * (1.0 - r)  # M for a point mass
    A = np.array(
        [
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
            [0.0, -m * g * r / den, -b / den, c / (den * L)],
            [0.0, (den + m * r) * g / (den * L), b / (den * L), -(den + m * r) * c / (den * m * l * L)],
        ]
    )
    B = np.array([[0.0], [0.0], [1.0 / den], [-1.0 / (den * L)]])
    return A, B


def nonlinear_rhs(p: PlantParams, x: np.ndarray, force: float | np.ndarray) -> np.ndarray:
    """dx/dt of the nonlinear plant (eq. 2.16-2.19).

    Eq. 2.18-2.19 print x_2^2 in the centripetal term; the derivation (eq. 2.14) has
    x_4^2 (theta_dot squared), which is what is used here.

    Parameters
    ----------
    p : PlantParams
        The plant.
    x : ndarray, shape (4,) or (4, N)
        State [s, theta, s_dot, theta_dot] (SI), or N states side by side.
    force : float or ndarray, shape (N,)
        Force on the cart (N).

    Returns
    -------
    ndarray
        dx/dt, shaped like ``x``.
    """
    M, m, l, g, b, c = p.M, p.m, p.l, p.g, p.b_VF, p.c
    L = p.swing_length()
    r = l / L
    _, th, sd, thd = x[0], x[1], x[2], x[3]
    sin, cos = np.sin(th), np.cos(th)
    den = (M + m) - m * cos * cos * r
    bracket = -b * sd + m * l * thd * thd * sin + (c / L) * thd * cos - m * g * sin * cos * r + force
    if p.F_C:  # Coulomb friction against the cart's motion (none at rest)
        bracket = bracket - p.F_C * np.sign(sd)
    sdd = bracket / den
    thdd = -c / (m * l * L) * thd + g / L * sin - cos * sdd / L
    return np.array([sd, thd, sdd, thdd])
