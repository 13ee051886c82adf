"""The rotary pendulum's accelerations as expressions for SPICE's behavioural sources (B elements):
patchgen.plant.rotary_equations.nonlinear_rhs's terms, with a torque on the arm and a force at the
pendulum's tip along the arm tip's path (generalised forces tip L_r on alpha and tip L_p cos(theta)
on theta, as patchgen.plant.rotary_compiled.rotary_accel). The deck (patchgen.spice.plant) names
the nodes; tests/plant/test_rotary.py holds the three forms to each other."""

from __future__ import annotations

from collections.abc import Callable

from patchgen.plant.rotary_equations import RotaryParams, inertias


def rotary_accelerations(plant: RotaryParams, number: Callable[[float], str], th: str, ad: str, thd: str,
                         volts: str, torque: str, tip: str) -> tuple[str, str]:
    """(alpha_ddot, theta_ddot) as expressions.

    Parameters
    ----------
    plant : RotaryParams
        The plant; its figures written with ``number``.
    number : callable
        A float as the deck writes it.
    th, ad, thd : str
        Expressions of theta, alpha_dot and theta_dot.
    volts : str
        The motor's voltage.
    torque, tip : str
        A torque on the arm (N m) and a force at the pendulum's tip (N), or "" for none.

    Returns
    -------
    tuple of str
        The arm's and the pendulum's angular accelerations, each solving M(theta) q'' = f.
    """
    c = inertias(plant)
    J_0, J_2, K, G = (number(v) for v in (c.J_0, c.J_2, c.K, c.G))
    damping = number(plant.D_r + plant.back_emf_damping())
    s, co = f"sin({th})", f"cos({th})"
    f1 = (f"({number(plant.torque_per_volt())}*({volts}) - {damping}*{ad}"
          f" - (2*{J_2}*{s}*{co}*{ad}*{thd} - {K}*{s}*{thd}*{thd})"
          + (f" + ({torque})" if torque else "") + (f" + ({tip})*{number(plant.L_r)}" if tip else "") + ")")
    f2 = (f"(-{number(plant.D_p)}*{thd} + {J_2}*{s}*{co}*{ad}*{ad} + {G}*{s}"
          + (f" + ({tip})*{number(plant.L_p)}*{co}" if tip else "") + ")")
    m11, m12 = f"({J_0} + {J_2}*{s}*{s})", f"({K}*{co})"
    det = f"({m11}*{J_2} - {m12}*{m12})"
    return f"({J_2}*{f1} - {m12}*{f2})/{det}", f"({m11}*{f2} - {m12}*{f1})/{det}"
