"""The rotary (Furuta) pendulum's equations: parameters, nonlinear and linear models, the events
that end a run.

States in SI units: alpha (rad, the arm), theta (rad, the pendulum, 0 = upright), alpha_dot and
theta_dot (rad/s). Input: the motor's armature voltage V_m (V); a positive voltage turns the arm in
+alpha, and theta is positive when the pendulum's tip leans the way +alpha moves the arm's tip.

The equations of motion are Cazzolato & Prime's, "On the dynamics of the Furuta pendulum", J.
Control Sci. Eng. 2011, article 528341 (doi:10.1155/2011/528341), for links whose principal axes
lie along and across them and a slender pendulum (no inertia about its own long axis), with their
hanging angle theta_2 = pi - theta here; the QUBE-Servo 2 workbook's rotary pendulum model is the
same with the pendulum's own inertia left out of the arm's equation. The arm (mass m_r, centre of
mass at l_r from the motor's axis, inertia J_r about it) and the pendulum (mass m_p, centre of
mass at l_p from its pivot, inertia J_p about it) are rigid bodies. With

    J_0 = J_r + m_r l_r^2 + m_p L_r^2    the arm and the pendulum's mass at its tip, about the axis
    J_2 = J_p + m_p l_p^2                the pendulum about its pivot
    K = m_p L_r l_p,  G = m_p g l_p

the kinetic energy is T = (J_0 + J_2 sin^2 theta) alpha'^2 / 2 + K cos(theta) alpha' theta'
+ J_2 theta'^2 / 2 and the potential V = G cos(theta); Lagrange's equations give

    M(theta) q'' + c(q, q') + dV/dq = Q,   q = (alpha, theta)
    M = [[J_0 + J_2 sin^2 theta, K cos theta], [K cos theta, J_2]]
    c = (2 J_2 sin theta cos theta alpha' theta' - K sin theta theta'^2, -J_2 sin theta cos theta alpha'^2)
    dV/dq = (0, -G sin theta)
    Q = (tau - D_r alpha', -D_p theta'),   tau = k_t (V_m - k_m alpha') / R_m

The motor's armature inductance is neglected: its current follows the voltage at once (a
QUBE-Servo 2's L_m / R_m is about 0.14 ms, far below the pendulum's time scales). Each term is
written once below; the linear model is those terms differentiated at an equilibrium.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from patchgen.plant.rotary_pendulum import ANGLE, POSITION, STATE_NAMES

ROTARY_STATES = STATE_NAMES  # alpha, theta, alpha_dot, theta_dot (patchgen.plant.rotary_pendulum)
_ARM, _PENDULUM = STATE_NAMES.index(POSITION), STATE_NAMES.index(ANGLE)
ROD_INERTIA = 1.0 / 12.0  # a uniform rod's inertia about its centre, across it, per m L^2
# sin(theta_0) above which linear_matrices refuses theta_0 as no equilibrium (pi's double: 1.2e-16)
EQUILIBRIUM_TOL = 1e-12


@dataclass(frozen=True)
class RotaryParams:
    """The rotary pendulum's physical parameters (patchgen.plant.rotary_pendulum.PARAMETERS), SI
    units. Centres of mass and inertias left as None are a uniform rod's, from the link's mass and
    length: so a sweep that scales a mass or a length scales them with it.

    Attributes
    ----------
    m_r, L_r : float
        The arm's mass (kg) and length from the motor's axis to the pendulum's pivot (m).
    m_p, L_p : float
        The pendulum's mass (kg) and length from its pivot to its tip (m).
    D_r, D_p : float
        Viscous damping at the motor's axis and at the pendulum's pivot (N m s/rad).
    R_m, k_t, k_m : float
        The motor's armature resistance (ohm), torque constant (N m/A) and back-EMF constant (V s/rad).
    g : float
        Gravity (m/s^2).
    l_r, J_r : float or None
        The motor's axis to the arm's centre of mass (m; None: L_r / 2) and the arm's inertia about
        its centre of mass (kg m^2; None: m_r L_r^2 / 12).
    l_p, J_p : float or None
        The pendulum's pivot to its centre of mass (m; None: L_p / 2) and its inertia about its
        centre of mass, across it (kg m^2; None: m_p L_p^2 / 12).
    alpha_limit : float
        The arm angle either way past which the pendulum encoder's cable winds up (rad; inf: none).
    """

    m_r: float
    L_r: float
    m_p: float
    L_p: float
    D_r: float
    D_p: float
    R_m: float
    k_t: float
    k_m: float
    g: float = 9.81
    l_r: float | None = None
    J_r: float | None = None
    l_p: float | None = None
    J_p: float | None = None
    alpha_limit: float = math.inf

    def arm_com(self) -> float:
        """The motor's axis to the arm's centre of mass (m)."""
        return self.L_r / 2.0 if self.l_r is None else self.l_r

    def arm_inertia(self) -> float:
        """The arm's inertia about its centre of mass (kg m^2)."""
        return ROD_INERTIA * self.m_r * self.L_r * self.L_r if self.J_r is None else self.J_r

    def pendulum_com(self) -> float:
        """The pendulum's pivot to its centre of mass (m)."""
        return self.L_p / 2.0 if self.l_p is None else self.l_p

    def pendulum_inertia(self) -> float:
        """The pendulum's inertia about its centre of mass, across it (kg m^2)."""
        return ROD_INERTIA * self.m_p * self.L_p * self.L_p if self.J_p is None else self.J_p

    def torque_per_volt(self) -> float:
        """k_t / R_m: the motor's torque per volt at standstill (N m/V)."""
        return self.k_t / self.R_m

    def back_emf_damping(self) -> float:
        """k_t k_m / R_m: the damping the back-EMF puts on the arm (N m s/rad)."""
        return self.k_t * self.k_m / self.R_m

    def scaled(self, **factors: float) -> RotaryParams:
        """A copy with named parameters multiplied by the given factors (for sweeps).

        Parameters
        ----------
        **factors : float
            Parameter name -> factor, e.g. ``m_p=1.1`` for a pendulum 10 % heavier. A rod's
            centre of mass or inertia left as None follows its mass and length; one given is
            not scaled unless named; one named that was left as None is the rod's, scaled.

        Returns
        -------
        RotaryParams
            The perturbed plant; this one is unchanged.
        """
        rod = {"l_r": self.arm_com, "J_r": self.arm_inertia, "l_p": self.pendulum_com, "J_p": self.pendulum_inertia}
        return replace(self, **{k: (getattr(self, k) if getattr(self, k) is not None else rod[k]()) * f
                                for k, f in factors.items()})


@dataclass(frozen=True)
class Inertias:
    """The four constants the equations of motion are made of (module docstring)."""

    J_0: float  # kg m^2: the arm and the pendulum's mass at its tip, about the motor's axis
    J_2: float  # kg m^2: the pendulum about its pivot
    K: float  # kg m^2: m_p L_r l_p, the arm-pendulum coupling
    G: float  # N m: m_p g l_p, the pendulum's weight times its pivot's distance to its centre of mass


def inertias(p: RotaryParams) -> Inertias:
    """J_0, J_2, K and G of the plant (module docstring)."""
    l_r, l_p = p.arm_com(), p.pendulum_com()
    return Inertias(J_0=p.arm_inertia() + p.m_r * l_r * l_r + p.m_p * p.L_r * p.L_r,
                    J_2=p.pendulum_inertia() + p.m_p * l_p * l_p, K=p.m_p * p.L_r * l_p, G=p.m_p * p.g * l_p)


def mass_matrix(c: Inertias, theta):
    """M(theta)'s entries (M_11, M_12, M_22); M_21 = M_12 (M_22 is a constant)."""
    sin, cos = np.sin(theta), np.cos(theta)
    return c.J_0 + c.J_2 * sin * sin, c.K * cos, c.J_2


def velocity_terms(c: Inertias, theta, alpha_dot, theta_dot):
    """c(q, q'): the Coriolis and centripetal terms, each a product of two rates (so none in the
    linear model about rest)."""
    sin, cos = np.sin(theta), np.cos(theta)
    return (2.0 * c.J_2 * sin * cos * alpha_dot * theta_dot - c.K * sin * theta_dot * theta_dot,
            -c.J_2 * sin * cos * alpha_dot * alpha_dot)


def potential_gradient(c: Inertias, theta):
    """dV/dq with V = G cos(theta): (0, -G sin theta)."""
    return 0.0, -c.G * np.sin(theta)


def potential_hessian(c: Inertias, theta: float) -> np.ndarray:
    """d^2V/dq^2 = [[0, 0], [0, -G cos theta]]: potential_gradient differentiated."""
    return np.array([[0.0, 0.0], [0.0, -c.G * np.cos(theta)]])


def generalised_forces(p: RotaryParams, alpha_dot, theta_dot, V_m):
    """Q: the motor's torque k_t (V_m - k_m alpha') / R_m less the arm's damping, and the
    pendulum's damping."""
    tau = p.k_t * (V_m - p.k_m * alpha_dot) / p.R_m
    return tau - p.D_r * alpha_dot, -p.D_p * theta_dot


def force_jacobians(p: RotaryParams) -> tuple[np.ndarray, np.ndarray]:
    """(dQ/dq', dQ/dV_m): generalised_forces differentiated (Q is linear in both)."""
    return (np.array([[-(p.D_r + p.back_emf_damping()), 0.0], [0.0, -p.D_p]]),
            np.array([[p.torque_per_volt()], [0.0]]))


def nonlinear_rhs(x: np.ndarray, V_m: float | np.ndarray, p: RotaryParams) -> np.ndarray:
    """dx/dt of the nonlinear plant: M(theta) q'' = Q - c(q, q') - dV/dq, solved for q''.

    Parameters
    ----------
    x : ndarray, shape (4,) or (4, N)
        State [alpha, theta, alpha_dot, theta_dot] (SI), or N states side by side.
    V_m : float or ndarray, shape (N,)
        Motor voltage (V).
    p : RotaryParams
        The plant.

    Returns
    -------
    ndarray
        dx/dt, shaped like ``x``.
    """
    c = inertias(p)
    th, ad, thd = x[1], x[2], x[3]
    m11, m12, m22 = mass_matrix(c, th)
    v1, v2 = velocity_terms(c, th, ad, thd)
    g1, g2 = potential_gradient(c, th)
    q1, q2 = generalised_forces(p, ad, thd, V_m)
    f1, f2 = q1 - v1 - g1, q2 - v2 - g2
    det = m11 * m22 - m12 * m12
    add = (m22 * f1 - m12 * f2) / det
    thdd = (m11 * f2 - m12 * f1) / det
    return np.array([ad, thd, add, thdd])


def linear_matrices(p: RotaryParams, theta_0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The plant linearised about rest at theta_0: x' = A x + B V_m.

    At rest (q' = 0, q'' = 0) the velocity terms and M's slope drop out, leaving
    M(theta_0) dq'' = -d^2V/dq^2 dq + dQ/dq' dq' + dQ/dV_m dV_m.

    Parameters
    ----------
    p : RotaryParams
        The plant.
    theta_0 : float
        The equilibrium: 0 upright (the balance point), pi hanging; sin(theta_0) must be 0.

    Returns
    -------
    A : ndarray, shape (4, 4)
        State matrix over alpha, theta, alpha_dot, theta_dot.
    B : ndarray, shape (4, 1)
        Input matrix for the motor voltage V_m (V).
    """
    if abs(np.sin(theta_0)) > EQUILIBRIUM_TOL:
        raise ValueError(f"theta_0 = {theta_0} is no equilibrium: the pendulum rests upright (0) or hanging (pi)")
    c = inertias(p)
    m11, m12, m22 = mass_matrix(c, theta_0)
    M = np.array([[m11, m12], [m12, m22]])
    dQ_drate, dQ_dV = force_jacobians(p)
    A = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [np.linalg.solve(M, -potential_hessian(c, theta_0)), np.linalg.solve(M, dQ_drate)]])
    B = np.vstack([np.zeros((2, 1)), np.linalg.solve(M, dQ_dV)])
    return A, B


def fallen(x: np.ndarray, fall_angle: float):
    """Whether the pendulum has fallen: |theta| past ``fall_angle`` (rad) from upright, the angle a
    run's scenario states. True or False, or one per state for x of shape (4, N)."""
    return np.abs(x[_PENDULUM]) > fall_angle


def wound_up(x: np.ndarray, arm_limit: float):
    """Whether the arm has turned far enough to wind up the pendulum encoder's cable: |alpha| past
    ``arm_limit`` (rad; RotaryParams.alpha_limit). One per state for x of shape (4, N)."""
    return np.abs(x[_ARM]) > arm_limit
