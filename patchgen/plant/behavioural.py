"""The cart-pendulum's accelerations as expressions for SPICE's behavioural sources (B elements):
eq. 2.16-2.19 with theta_dot^2 in the centripetal term and the pendulum's own inertia J (its swing
length L = l + J/(m l), r = l/L), as patchgen.plant.equations.nonlinear_rhs, and a horizontal push
on the pendulum at distance l (generalised forces F_tip on s and F_tip l cos(theta) on theta, as
patchgen.plant.compiled.plant_accel). A point mass (J = 0) gives the thesis's expressions. The deck
(patchgen.spice.plant) names the nodes; the three forms are checked against each other by
tests/plant/test_equations_agree.py."""

from __future__ import annotations

from collections.abc import Callable

from patchgen.plant.equations import PlantParams

# m/s: SPICE's Coulomb friction is F_C tanh(s_dot / this), a sign smooth enough for its variable step
COULOMB_SMOOTHING_M_S = 1e-4


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
    L_, r_ = plant.swing_length(), plant.l / plant.swing_length()
    M, m, l, g, b, c, L = (number(v) for v in (plant.M, plant.m, plant.l, plant.g, plant.b_VF, plant.c, L_))
    m_r = number(plant.m * r_)  # m for a point mass (r = 1)
    tip_s = f" + ({tip})*sin({th})*sin({th})" if tip else ""
    if tip and plant.J:  # the push's share a rigid pendulum leaves the cart: tip (1 - r) cos^2
        tip_s += f" + ({tip})*{number(1.0 - r_)}*cos({th})*cos({th})"
    tip_th = f" + ({tip})*cos({th})/({m}*{L})" if tip else ""
    coulomb = f" - {number(plant.F_C)}*tanh({sd}/{number(COULOMB_SMOOTHING_M_S)})" if plant.F_C else ""
    s_ddot = (f"(-{b}*{sd}{coulomb} + {m}*{l}*{thd}*{thd}*sin({th}) + ({c}/{L})*{thd}*cos({th})"
              f" - {m_r}*{g}*sin({th})*cos({th}) + {force}{tip_s}) / (({M}+{m}) - {m_r}*cos({th})*cos({th}))")
    theta_ddot = f"-({c}/({m}*{l}*{L}))*{thd} + ({g}/{L})*sin({th}){tip_th} - cos({th})*{sdd}/{L}"
    return s_ddot, theta_ddot
