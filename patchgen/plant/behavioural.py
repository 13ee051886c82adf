"""The cart-pendulum's accelerations as expressions for SPICE's behavioural sources (B elements):
eq. 2.16-2.19 with theta_dot^2 in the centripetal term, as patchgen.plant.equations.nonlinear_rhs,
and a horizontal push at the pendulum's tip (distance l: generalised forces F_tip on s and
F_tip l cos(theta) on theta, as patchgen.plant.compiled.plant_accel). The deck
(patchgen.spice.plant) names the nodes; the three forms are checked against each other by
tests/plant/test_equations_agree.py."""

from __future__ import annotations

from collections.abc import Callable

from patchgen.plant.equations import PlantParams


def accelerations(plant: PlantParams, number: Callable[[float], str], th: str, sd: str, thd: str, force: str,
                  tip: str, sdd: str) -> tuple[str, str]:
    """(s_ddot, theta_ddot) as expressions.

    Parameters
    ----------
    plant : PlantParams
        The plant; its figures written with ``number``.
    number : callable
        A float as the deck writes it.
    th, sd, thd : str
        Expressions of theta, s_dot and theta_dot.
    force : str
        The force on the cart (the actuator's and any push on the cart).
    tip : str
        The push at the tip, or "" for none.
    sdd : str
        The expression theta_ddot reads s_ddot from (the node the first expression drives).
    """
    M, m, l, g, b, c = (number(v) for v in (plant.M, plant.m, plant.l, plant.g, plant.b_VF, plant.c))
    tip_s = f" + ({tip})*sin({th})*sin({th})" if tip else ""
    tip_th = f" + ({tip})*cos({th})/({m}*{l})" if tip else ""
    s_ddot = (f"(-{b}*{sd} + {m}*{l}*{thd}*{thd}*sin({th}) + ({c}/{l})*{thd}*cos({th})"
              f" - {m}*{g}*sin({th})*cos({th}) + {force}{tip_s}) / (({M}+{m}) - {m}*cos({th})*cos({th}))")
    theta_ddot = f"-({c}/({m}*{l}*{l}))*{thd} + ({g}/{l})*sin({th}){tip_th} - cos({th})*{sdd}/{l}"
    return s_ddot, theta_ddot
