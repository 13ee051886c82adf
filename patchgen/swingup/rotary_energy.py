"""Energy-based swing-up of the rotary (Furuta) pendulum, with a hand-off to LQR near upright.

The law is Astrom and Furuta's energy control (K. J. Astrom, K. Furuta, "Swinging up a pendulum
by energy control", Automatica 36 (2000) 287-295), written for patchgen.plant.rotary_equations'
signs. With the arm's acceleration alpha'' as the input, the pendulum's own equation gives

    dE/dt = theta' (J_2 theta'' - G sin theta) = -K cos(theta) theta' alpha'' + J_2 sin cos alpha'^2 theta'
            - D_p theta'^2,

so, with a = L_r alpha'' the pivot's acceleration (m/s^2) and m_p l_p = K / L_r, the pumping
term is dE/dt = -m_p l_p cos(theta) theta' a, Astrom and Furuta's (their eq. 5). Energy rises
when a has the opposite sign to theta' cos(theta); hence a = sat_{n g}(k (E - E_0) sign(theta'
cos theta)) with E < E_0 = 0 below upright (aimed ENERGY_MARGIN G higher, see there).
tests/swingup/test_rotary_energy.py checks this sign by running the law flipped.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from patchgen.plant.rotary_equations import RotaryParams, inertias, linear_matrices, nonlinear_rhs

UPRIGHT_ENERGY_J = 0.0  # E_0: upright at rest, the energy the law drives toward
PUMP_GAIN = 1000.0  # k, (m/s^2)/J: saturates the law until |E - E_0| < n g / k (~1 % of 2G on a QUBE)
# The law aims ENERGY_MARGIN G above E_0 (a choice, found by simulation): E is the pendulum's energy
# with the arm still, and on the way up the arm's motion (the J_2 sin cos alpha'^2 term) and the
# pendulum's damping take some back; aimed at E_0 itself, the QUBE stalls about 50 deg short
ENERGY_MARGIN = 0.5
ACCEL_LIMIT_G = 1.0  # n: the pivot's acceleration limit in g; a QUBE's 10 V stall torque gives ~1.1 g
CENTRING_GAIN = 20.0  # 1/s^2 (as m/s^2 of pivot per m of arm tip): a weak pull of alpha back to 0,
#                      so the arm does not walk toward the cable's wind-up while pumping (a choice)
CENTRING_DAMPING = 4.0  # 1/s: damps the centring pull (a choice; with 20 1/s^2, |alpha| < 2.8 rad on a QUBE)
LQR_Q = (5.0, 1.0, 1.0, 1.0)  # state weights on alpha, theta, alpha_dot, theta_dot (a choice)
LQR_R = 1.0  # weight on V_m^2 (a choice)
CATCH_ANGLE_RAD = math.radians(20.0)  # hand to LQR within 20 deg of upright
SAMPLE_S = 1e-3  # the controller's sample period, zero-order hold between samples
MAX_STEP_S = 2.5e-4  # solve_ivp's largest step inside a sample
RTOL, ATOL = 1e-8, 1e-10  # solve_ivp's tolerances
NUDGE_RAD = 0.05  # the default start: hanging, tipped by 0.05 rad (~3 deg), at rest
HOLD_ANGLE_RAD = math.radians(5.0)  # "held upright": |theta| below this
HOLD_CHECK_S = 30.0  # ... for the run's last 30 s


def wrap(theta):
    """Angle wrapped to [-pi, pi): 0 upright after any number of turns."""
    return (np.asarray(theta) + np.pi) % (2.0 * np.pi) - np.pi


def pendulum_energy(p: RotaryParams, theta, theta_dot):
    """E = J_2 theta'^2 / 2 + G (cos theta - 1) (J): the pendulum about its pivot with the arm
    still; 0 upright at rest, -2G hanging at rest."""
    l_p = p.pendulum_com()
    J_2 = p.pendulum_inertia() + p.m_p * l_p * l_p
    G = p.m_p * p.g * l_p
    return 0.5 * J_2 * theta_dot * theta_dot + G * (np.cos(theta) - 1.0)


@dataclass(frozen=True)
class EnergyGains:
    """The energy law's gains (module constants by default)."""

    k: float = PUMP_GAIN  # (m/s^2)/J
    n: float = ACCEL_LIMIT_G  # the pivot's acceleration limit, in g
    centring: float = CENTRING_GAIN  # 1/s^2
    centring_damping: float = CENTRING_DAMPING  # 1/s
    sign: float = 1.0  # 1: as derived; -1: flipped (for the test that guards the sign)
    margin: float = ENERGY_MARGIN  # aim this many G above E_0


def pivot_acceleration(p: RotaryParams, x: np.ndarray, gains: EnergyGains = EnergyGains()) -> float:
    """Astrom and Furuta's law: the pendulum pivot's desired acceleration a (m/s^2), saturated at
    n g, plus the weak arm-centring term outside the saturation (inside it, the saturated pump
    would hide it: a bang-bang acceleration from rest walks the arm one way)."""
    alpha, theta, alpha_dot, theta_dot = x
    E = pendulum_energy(p, theta, theta_dot)
    target = UPRIGHT_ENERGY_J + gains.margin * p.m_p * p.g * p.pendulum_com()
    pump = gains.sign * gains.k * (E - target) * np.sign(theta_dot * np.cos(theta))
    limit = gains.n * p.g
    centre = -p.L_r * (gains.centring * alpha + gains.centring_damping * alpha_dot)
    return float(np.clip(pump, -limit, limit) + centre)


def voltage_for(p: RotaryParams, a: float, alpha_dot: float) -> float:
    """V_m for the pivot acceleration a: the arm's torque balance J_0 alpha'' = tau - D_r alpha'
    inverted with alpha'' = a / L_r, the pendulum's reaction left out (J_0 from inertias: the
    arm and the pendulum's mass at its tip), plus the back-EMF k_m alpha'."""
    tau = inertias(p).J_0 * a / p.L_r + p.D_r * alpha_dot
    return tau / p.torque_per_volt() + p.k_m * alpha_dot


def lqr_gain(p: RotaryParams, Q=LQR_Q, R: float = LQR_R) -> np.ndarray:
    """K of u = -K x from control.lqr on the plant linearised upright, shape (4,)."""
    import control  # loaded only where a hand-off gain is asked for, as patchgen's API does

    A, B = linear_matrices(p)
    K, _, _ = control.lqr(A, B, np.diag(Q), np.array([[R]]))
    return np.asarray(K, dtype=float).ravel()


@dataclass(frozen=True)
class Rule:
    """One row of the switching table: when ``condition`` holds, ``law`` drives the motor."""

    condition: str
    law: str


# The switching table, read top down, first match wins (no memory: a pendulum knocked out of the
# catch zone is pumped up again)
SWITCHING = (
    Rule(f"|theta| < {math.degrees(CATCH_ANGLE_RAD):.0f} deg (wrapped about upright)", "LQR: V_m = -K x"),
    Rule("otherwise", "energy: V_m from a = sat_ng(k (E - E_0 - margin G) sign(theta' cos theta)) + centring"),
)


def controller(p: RotaryParams, K: np.ndarray, v_limit: float, catch: float = CATCH_ANGLE_RAD,
               gains: EnergyGains = EnergyGains(), handoff: bool = True) -> Callable[[np.ndarray], tuple[float, bool]]:
    """The SWITCHING table as a function: state -> (V_m clipped to v_limit, LQR in charge)."""

    def law(x: np.ndarray) -> tuple[float, bool]:
        th = float(wrap(x[1]))
        if handoff and abs(th) < catch:
            v = -float(K @ np.array([x[0], th, x[2], x[3]]))
            return float(np.clip(v, -v_limit, v_limit)), True
        a = pivot_acceleration(p, x, gains)
        return float(np.clip(voltage_for(p, a, x[2]), -v_limit, v_limit)), False

    return law


@dataclass(frozen=True)
class SwingUpRun:
    """A simulated swing-up: histories at the controller's samples and what they show."""

    t: np.ndarray  # (N,) s
    x: np.ndarray  # (N, 4) alpha, theta (unwrapped), alpha_dot, theta_dot
    V: np.ndarray  # (N,) V, held from each sample to the next
    lqr: np.ndarray  # (N,) bool, LQR in charge
    energy: np.ndarray  # (N,) J
    handoff_time: float | None  # s, the first sample LQR took over; None if it never did
    held: bool  # |theta| < HOLD_ANGLE_RAD over the last hold_check seconds
    max_abs_alpha: float  # rad
    max_abs_V: float  # V


def hanging(nudge: float = NUDGE_RAD, nudge_rate: float = 0.0) -> np.ndarray:
    """The start: hanging (theta = pi) tipped by ``nudge`` (rad) at ``nudge_rate`` (rad/s), arm at 0."""
    return np.array([0.0, math.pi + nudge, 0.0, nudge_rate])


def simulate_swingup(p: RotaryParams, v_limit: float, x0: np.ndarray | None = None, t_end: float = 40.0,
                     K: np.ndarray | None = None, gains: EnergyGains = EnergyGains(), handoff: bool = True,
                     hold_check: float = HOLD_CHECK_S, sample: float = SAMPLE_S,
                     stop_at_handoff: bool = False) -> SwingUpRun:
    """Run the switched controller on the nonlinear plant: solve_ivp across each sample period
    with the voltage held (zero-order hold), the controller evaluated at each sample.

    Parameters
    ----------
    p : RotaryParams
        The plant.
    v_limit : float
        The motor's voltage limit either way (V).
    x0 : ndarray, optional
        Start state; default ``hanging()``.
    t_end : float
        Run length (s).
    K : ndarray, optional
        The hand-off's state feedback; default ``lqr_gain(p)``.
    gains : EnergyGains
        The energy law's gains and sign.
    handoff : bool
        False: the energy law alone, never LQR.
    hold_check : float
        The closing window (s) over which ``held`` is judged.
    sample : float
        Controller sample period (s).
    stop_at_handoff : bool
        End the run at the first sample the catch takes over (the state another controller, the
        patched circuit, is handed).

    Returns
    -------
    SwingUpRun
    """
    K = lqr_gain(p) if K is None else np.asarray(K, dtype=float).ravel()
    law = controller(p, K, v_limit, gains=gains, handoff=handoff)
    n = int(round(t_end / sample))
    t = np.arange(n + 1) * sample
    xs = np.empty((n + 1, 4))
    Vs, lq = np.zeros(n + 1), np.zeros(n + 1, dtype=bool)
    xs[0] = hanging() if x0 is None else x0
    for i in range(n):
        Vs[i], lq[i] = law(xs[i])
        if stop_at_handoff and lq[i]:
            t, xs, Vs, lq, n = t[:i + 1], xs[:i + 1], Vs[:i + 1], lq[:i + 1], i
            break
        sol = solve_ivp(lambda _t, y, v=Vs[i]: nonlinear_rhs(y, v, p), (t[i], t[i + 1]), xs[i],
                        rtol=RTOL, atol=ATOL, max_step=MAX_STEP_S)
        xs[i + 1] = sol.y[:, -1]
    else:
        Vs[n], lq[n] = law(xs[n])
    on = np.flatnonzero(lq)
    tail = t >= t_end - hold_check
    stopped = t[-1] < t_end - 0.5 * sample  # ended at the hand-off: this run held nothing
    return SwingUpRun(t=t, x=xs, V=Vs, lqr=lq, energy=pendulum_energy(p, xs[:, 1], xs[:, 3]),
                      handoff_time=float(t[on[0]]) if on.size else None,
                      held=not stopped and bool(np.all(np.abs(wrap(xs[tail, 1])) < HOLD_ANGLE_RAD)),
                      max_abs_alpha=float(np.max(np.abs(xs[:, 0]))), max_abs_V=float(np.max(np.abs(Vs))))
