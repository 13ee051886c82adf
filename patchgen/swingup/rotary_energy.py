"""Energy-based swing-up of the rotary (Furuta) pendulum, with a hand-off near upright.

The law is Astrom and Furuta's energy control (K. J. Astrom, K. Furuta, "Swinging up a pendulum
by energy control", Automatica 36 (2000) 287-295), written for patchgen.plant.rotary_equations'
signs and for an arm that turns. With the arm's acceleration alpha'' as the input, the pendulum's
own equation J_2 theta'' = -K cos(theta) alpha'' + J_2 sin cos alpha'^2 + G sin theta - D_p theta'
gives, for its energy with the arm still, E = J_2 theta'^2 / 2 + G (cos theta - 1),

    dE/dt = -K cos(theta) theta' alpha'' + J_2 sin cos alpha'^2 theta' - D_p theta'^2.

The middle term is the arm's centrifugal pull on the pendulum, towards horizontal: with the arm
turning at a few rad/s it is a quarter of the pendulum's weight on a QUBE, and a law that pumps E
alone stalls tens of degrees short of upright. Counting it as a potential, the energy in the frame
that turns with the arm, E_r = E - J_2 sin^2(theta) alpha'^2 / 2, has

    dE_r/dt = -alpha'' (K cos(theta) theta' + J_2 sin^2(theta) alpha') - D_p theta'^2,

so the input alone moves it, and E_r is E upright. With a = L_r alpha'' the pivot's acceleration
(m/s^2) and m_p l_p = K / L_r, the pump is a = sat_{n g}(k (E_r - E_0) sign(m_p l_p cos(theta)
theta' + J_2 sin^2(theta) alpha' / L_r)) (Astrom and Furuta's eq. 5 when the arm is still), aimed
ENERGY_MARGIN G above E_0 for the damping. The motor's voltage realises a from the arm's equation
with the pendulum's reaction in it (voltage_for). tests/swingup/test_rotary_energy.py checks the
law's sign by running it flipped.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from patchgen.plant.rotary_equations import RotaryParams, inertias, linear_matrices, nonlinear_rhs
from patchgen.swingup.handoff import Zone

UPRIGHT_ENERGY_J = 0.0  # E_0: upright at rest, the energy the law drives toward
PUMP_GAIN = 1000.0  # k, (m/s^2)/J: the law saturates until |E_r - E_0| < n g / k (~0.65 G on a QUBE)
# The law aims ENERGY_MARGIN G above E_0 (a choice, found by simulation on the QUBE with a free-
# swinging pendulum): the pendulum's damping and the arm's centring take a little back on the last
# swing. Aimed at 0.03 G the pendulum stalls 13 deg short of upright; at 0.1 G it arrives within
# 20 deg at 4.5 rad/s with the arm near its centre; at 0.2 G the arm comes in at 7 rad/s, outside
# the patch's zone of control (patchgen.swingup.rotary_zone)
ENERGY_MARGIN = 0.1
ACCEL_LIMIT_G = 1.0  # n: the pivot's acceleration limit in g; a QUBE's 10 V stall torque gives ~1.1 g
CENTRING_GAIN = 20.0  # 1/s^2: alpha'' = -20 alpha pulls the arm home (4.5 rad/s), slower than the
#                      pendulum's swing (10.7 rad/s on a QUBE), so that it does not fight the pump;
#                      Quanser's swing-up labs likewise keep a weak arm-homing term (a choice)
CENTRING_DAMPING = 4.0  # 1/s: damps the pull (zeta 0.45 with 20 1/s^2): the arm stays within 1.4 rad
LQR_Q = (5.0, 1.0, 1.0, 1.0)  # state weights on alpha, theta, alpha_dot, theta_dot (a choice)
LQR_R = 1.0  # weight on V_m^2 (a choice)
CATCH_ANGLE_RAD = math.radians(20.0)  # hand off within 20 deg of upright (and inside a zone, if given)
SAMPLE_S = 1e-3  # the controller's sample period, zero-order hold between samples
SUBSTEPS = 4  # RK4 steps per sample (0.25 ms): within 1e-9 of solve_ivp at rtol 1e-8 over a pump-up, 4x faster
NUDGE_RAD = 0.05  # the default start: hanging, tipped by 0.05 rad (~3 deg), at rest
HOLD_ANGLE_RAD = math.radians(5.0)  # "held upright": |theta| below this
HOLD_CHECK_S = 30.0  # ... for the run's last 30 s


def wrap(theta):
    """Angle wrapped to [-pi, pi): 0 upright after any number of turns."""
    return (np.asarray(theta) + np.pi) % (2.0 * np.pi) - np.pi


def pendulum_energy(p: RotaryParams, theta, theta_dot):
    """E = J_2 theta'^2 / 2 + G (cos theta - 1) (J): the pendulum about its pivot with the arm
    still; 0 upright at rest, -2G hanging at rest."""
    c = inertias(p)
    return 0.5 * c.J_2 * theta_dot * theta_dot + c.G * (np.cos(theta) - 1.0)


def turning_frame_energy(p: RotaryParams, x):
    """E_r = E - J_2 sin^2(theta) alpha'^2 / 2 (J): the pendulum's energy in the frame turning with
    the arm, its centrifugal potential counted; E at upright whatever the arm does (module docstring)."""
    c = inertias(p)
    s = np.sin(x[1])
    return pendulum_energy(p, x[1], x[3]) - 0.5 * c.J_2 * s * s * x[2] * x[2]


def pump_direction(p: RotaryParams, x) -> float:
    """m_p l_p cos(theta) theta' + J_2 sin^2(theta) alpha' / L_r (kg m/s): dE_r/dt is minus this
    times the pivot's acceleration (module docstring)."""
    c = inertias(p)
    s = math.sin(x[1])
    return c.K / p.L_r * math.cos(x[1]) * x[3] + c.J_2 * s * s * x[2] / p.L_r


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
    """Astrom and Furuta's law on E_r: the pendulum pivot's desired acceleration a (m/s^2), the
    pump saturated at n g, plus the arm-centring term outside the saturation (inside it, the
    saturated pump would hide it: a bang-bang acceleration from rest walks the arm one way)."""
    alpha, alpha_dot = x[0], x[2]
    target = UPRIGHT_ENERGY_J + gains.margin * inertias(p).G
    pump = gains.sign * gains.k * (turning_frame_energy(p, x) - target) * np.sign(pump_direction(p, x))
    limit = gains.n * p.g
    centre = -p.L_r * (gains.centring * alpha + gains.centring_damping * alpha_dot)
    return float(np.clip(pump, -limit, limit) + centre)


def voltage_for(p: RotaryParams, a: float, x: np.ndarray) -> float:
    """V_m that gives the pivot the acceleration a (m/s^2) at state x: the pendulum's equation gives
    theta'' for alpha'' = a / L_r, the arm's equation the torque for both (the pendulum's reaction
    included: on a QUBE it is a third of the arm's inertia), and the motor's the voltage."""
    c = inertias(p)
    _, th, ad, thd = x
    s, co = math.sin(th), math.cos(th)
    add = a / p.L_r
    thdd = (-c.K * co * add + c.J_2 * s * co * ad * ad + c.G * s - p.D_p * thd) / c.J_2
    tau = ((c.J_0 + c.J_2 * s * s) * add + c.K * co * thdd + 2.0 * c.J_2 * s * co * ad * thd
           - c.K * s * thd * thd + p.D_r * ad)
    return tau / p.torque_per_volt() + p.k_m * ad


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


# The switching table, read top down at every sample, first match wins. The manoeuvre
# (patchgen.swingup.rotary_manoeuvre) gives the patch its zone of control and ends the pump at the
# first match of the first row; simulate_swingup without a zone uses the angle alone and keeps no
# memory (a pendulum knocked out of the catch is pumped up again)
SWITCHING = (
    Rule(f"|theta| < {math.degrees(CATCH_ANGLE_RAD):.0f} deg (wrapped about upright) and the state inside the "
         "patch's zone of control (x^T P x < r, within its sampled box; found by simulating the patch on the bench)",
         "the patch's LQR: V_m = -K x (IC -> OP)"),
    Rule("otherwise", "energy pump: V_m for the pivot's acceleration a = sat_ng(k (E_r - E_0 - margin G) "
         "sign(m_p l_p cos(theta) theta' + J_2 sin^2(theta) alpha' / L_r)) - L_r (c alpha + c_d alpha'), "
         "E_r the pendulum's energy turning with the arm"),
)


def controller(p: RotaryParams, K: np.ndarray, v_limit: float, catch: float = CATCH_ANGLE_RAD,
               gains: EnergyGains = EnergyGains(), handoff: bool = True,
               zone: Zone | None = None) -> Callable[[np.ndarray], tuple[float, bool]]:
    """The SWITCHING table as a function: state -> (V_m clipped to v_limit, LQR in charge); with
    ``zone`` None the catch is the angle alone."""

    def law(x: np.ndarray) -> tuple[float, bool]:
        th = float(wrap(x[1]))
        if handoff and abs(th) < catch and (zone is None or zone.contains(x)):
            v = -float(K @ np.array([x[0], th, x[2], x[3]]))
            return float(np.clip(v, -v_limit, v_limit)), True
        a = pivot_acceleration(p, x, gains)
        return float(np.clip(voltage_for(p, a, x), -v_limit, v_limit)), False

    return law


def held_step(p: RotaryParams, x: np.ndarray, v: float, h: float) -> np.ndarray:
    """One RK4 step of the nonlinear plant with the voltage held."""
    k1 = nonlinear_rhs(x, v, p)
    k2 = nonlinear_rhs(x + 0.5 * h * k1, v, p)
    k3 = nonlinear_rhs(x + 0.5 * h * k2, v, p)
    k4 = nonlinear_rhs(x + h * k3, v, p)
    return x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


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
                     stop_at_handoff: bool = False, zone: Zone | None = None) -> SwingUpRun:
    """Run the switched controller on the nonlinear plant: SUBSTEPS RK4 steps across each sample
    period with the voltage held (zero-order hold), the controller evaluated at each sample.

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
    zone : Zone, optional
        The catching controller's zone of control: the hand-off also needs the state inside it.

    Returns
    -------
    SwingUpRun
    """
    K = lqr_gain(p) if K is None else np.asarray(K, dtype=float).ravel()
    law = controller(p, K, v_limit, gains=gains, handoff=handoff, zone=zone)
    n = int(round(t_end / sample))
    h = sample / SUBSTEPS
    t = np.arange(n + 1) * sample
    xs = np.empty((n + 1, 4))
    Vs, lq = np.zeros(n + 1), np.zeros(n + 1, dtype=bool)
    xs[0] = hanging() if x0 is None else x0
    for i in range(n):
        Vs[i], lq[i] = law(xs[i])
        if stop_at_handoff and lq[i]:
            t, xs, Vs, lq, n = t[:i + 1], xs[:i + 1], Vs[:i + 1], lq[:i + 1], i
            break
        y = xs[i]
        for _ in range(SUBSTEPS):
            y = held_step(p, y, Vs[i], h)
        xs[i + 1] = y
    else:
        Vs[n], lq[n] = law(xs[n])
    on = np.flatnonzero(lq)
    tail = t >= t_end - hold_check
    stopped = t[-1] < t_end - 0.5 * sample  # ended at the hand-off: this run held nothing
    return SwingUpRun(t=t, x=xs, V=Vs, lqr=lq, energy=pendulum_energy(p, xs[:, 1], xs[:, 3]),
                      handoff_time=float(t[on[0]]) if on.size else None,
                      held=not stopped and bool(np.all(np.abs(wrap(xs[tail, 1])) < HOLD_ANGLE_RAD)),
                      max_abs_alpha=float(np.max(np.abs(xs[:, 0]))), max_abs_V=float(np.max(np.abs(Vs))))
