"""The bench in a SPICE deck: the plant (the cart-pendulum or the rotary pendulum), its actuator and
the scenario's pushes and steps, as behavioural sources charging 1 F capacitors. The plant's node
voltages are its states in SI units (1 V = 1 m, 1 rad, 1 m/s, 1 rad/s); the force node's is the
plant's input: the force on the cart in N, or a rotary arm's motor voltage."""

from __future__ import annotations

from collections.abc import Sequence

from patchgen.inputs.drive_fields import motor_of
from patchgen.inputs.scenario import Disturbance
from patchgen.plant.behavioural import accelerations
from patchgen.plant.drive import DCMotor
from patchgen.plant.equations import PLANT_STATES, PlantParams
from patchgen.plant.plant_model import PLANT_MODELS, PlantModel
from patchgen.plant.rotary_behavioural import rotary_accelerations
from patchgen.plant.rotary_equations import RotaryParams
from patchgen.profiles.bench import BenchProfile
from patchgen.spice.elements import SMOOTHING, DeckLines, clamp, dead_zone, num, state_integrator

# Plant state nodes, in PLANT_STATES order (x_s, x_theta, x_sdot, x_thetadot); their voltages are
# the states in SI units.
STATE_NODES = {k: "x_" + k.replace("_", "") for k in PLANT_STATES}
ALL_STATE_NODES = {k: "x_" + k.replace("_", "") for pm in PLANT_MODELS.values() for k in pm.state_names}


def state_nodes(pm: PlantModel) -> dict[str, str]:
    """A plant's state nodes, by state (the cart's are STATE_NODES)."""
    return {k: ALL_STATE_NODES[k] for k in pm.state_names}
FORCE_NODE = "f_cart"
S_REF_NODE = "s_ref"  # the cart-position reference a step disturbance moves
EDGE_S = 1e-6  # s: the rise and fall of a push or step in the deck (the simulator's are sharp)
CONTROL_NODE = "u_c"


def actuator(d: DeckLines, plant: PlantParams | RotaryParams, bench: BenchProfile, ideal: bool) -> None:
    """The plant's input from u_c: the ideal gain K_U, or the bench's actuator (dead zone, lag or
    lag with a zero, limit) and, when a cart's track has them, its limit switches (a rotary arm's
    input is its motor's voltage, the motor itself the plant's)."""
    act = bench.actuator
    unit = PLANT_MODELS[bench.plant].input_unit
    uc = f"v({CONTROL_NODE})"
    motor = motor_of(act)
    if motor is not None:
        _motor(d, plant, bench, motor, ideal)
        return
    if ideal:
        d.comment(f"Actuator: ideal gain K_U = {act.K_U} {unit}/V")
        d.add(f"B_force {FORCE_NODE} 0 V = {num(act.K_U)}*{uc}")
        return
    d.comment(f"Actuator ({bench.id}): {act.model}, K_U {act.K_U} {unit}/V, tau {act.tau} s, dead zone "
              f"+/-{act.dead_zone_V} V, limit {act.force_limit_N} {unit}")
    if act.dead_zone_V > 0:
        d.add(f"B_deadzone a_dz 0 V = {dead_zone(uc, act.dead_zone_V)}")
    else:
        d.add(f"B_deadzone a_dz 0 V = {uc}")
    if act.model == "gain" or act.tau == 0.0:
        raw = f"{num(act.K_U)}*v(a_dz)"
    elif act.model == "lag":
        state_integrator(d, "a_lag", f"({num(act.K_U)}*v(a_dz) - v(a_lag))/{num(act.tau)}", 0.0)
        raw = "v(a_lag)"
    else:  # lag_zero: K_U s/(tau s + 1) = (K_U/tau) (1 - 1/(tau s + 1))
        state_integrator(d, "a_lag", f"(v(a_dz) - v(a_lag))/{num(act.tau)}", 0.0)
        raw = f"{num(act.K_U / act.tau)}*(v(a_dz) - v(a_lag))"
    d.add(f"B_force_raw a_raw 0 V = {raw}")
    d.add(f"B_force {FORCE_NODE} 0 V = {_switched(d, plant, bench, clamp('v(a_raw)', act.force_limit_N))}")


def _switched(d: DeckLines, plant: PlantParams, bench: BenchProfile, force: str) -> str:
    """The force with the limit switches cutting it at +/- d/2, when the track has them (a rotary
    arm's cable cuts nothing: the run ends there, patchgen.spice.verdict)."""
    if not isinstance(plant, PlantParams):
        return force
    cut = bench.track.cut_at(plant.d)
    if cut is None:
        return force
    half, w = num(cut), num(SMOOTHING * cut)
    s = f"v({STATE_NODES['s']})"
    d.comment(f"Limit switches at +/- d/2 = {plant.d / 2} m cut motor power" if cut == plant.d / 2 else
              f"The watchdog cuts motor power at +/- {cut} m")
    return f"({force})*0.25*(1+tanh(({half}-{s})/{w}))*(1+tanh(({half}+{s})/{w}))"


def _motor(d: DeckLines, plant: PlantParams, bench: BenchProfile, motor: DCMotor, ideal: bool) -> None:
    """A DC motor driven by voltage (patchgen.plant.drive): the amplifier's limit on K_U u_c (none
    when ideal), the back-EMF's b s_dot taken from it, through the electrical lag when it has one;
    the rotor's mass is on the cart (cart_pendulum's plant)."""
    act = bench.actuator
    uc, sd = f"v({CONTROL_NODE})", f"v({STATE_NODES['s_dot']})"
    emf, lag = motor.back_emf_damping(), 0.0 if ideal else motor.electrical_lag()
    d.comment(f"Actuator ({bench.id}): dc_motor, K_U {act.K_U:.6g} N/V, back-EMF {emf:.6g} N s/m, electrical lag "
              f"{lag:g} s" + ("" if ideal else f", dead zone +/-{act.dead_zone_V} V, amplifier limit "
                                              f"+/-{act.V_limit} V"))
    if ideal:
        command = f"{num(act.K_U)}*{uc}"
    else:
        d.add(f"B_deadzone a_dz 0 V = {dead_zone(uc, act.dead_zone_V) if act.dead_zone_V > 0 else uc}")
        command = clamp(f"{num(act.K_U)}*v(a_dz)", act.force_limit_N)
    net = f"{command}-{num(emf)}*{sd}"
    if lag > 0:
        state_integrator(d, "a_lag", f"(({net}) - v(a_lag))/{num(lag)}", 0.0)
        net = "v(a_lag)"
    d.add(f"B_force {FORCE_NODE} 0 V = {net if ideal else _switched(d, plant, bench, net)}")


def disturbances(d: DeckLines, pushes: Sequence[Disturbance], arm_lever: float = 1.0) -> dict[str, str]:
    """A source per push or step of the scenario (a rectangle or a step with EDGE_S edges, as the
    simulator applies them); returns the push on the position (the cart's force; a rotary arm's
    torque, a push at its end times ``arm_lever``, L_r), the tip push and the reference expressions
    ('' for none) and writes the reference node when there is a step."""
    parts: dict[str, list[str]] = {"cart": [], "tip": [], "step": []}
    for i, x in enumerate(pushes):
        node, t0 = f"dist_{i}", x.time_s
        if x.kind == "step":
            points = [(0.0, 0.0), (t0, 0.0), (t0 + EDGE_S, x.step_size())]
            parts["step"].append(f"v({node})")
        else:
            t1 = t0 + x.duration_s
            f = x.force_N * (arm_lever if x.at == "arm" else 1.0)
            points = [(0.0, 0.0), (t0, 0.0), (t0 + EDGE_S, f), (t1, f), (t1 + EDGE_S, 0.0)]
            parts["tip" if x.at == "pendulum_tip" else "cart"].append(f"v({node})")
        points = [pt for k, pt in enumerate(points) if k == 0 or pt[0] > points[k - 1][0]]  # a push at t = 0
        d.comment(f"Disturbance {i}: {x.kind} at {t0} s")
        d.add(f"V_{node} {node} 0 PWL(" + " ".join(f"{num(t)} {num(v)}" for t, v in points) + ")")
    if parts["step"]:
        d.add(f"B_sref {S_REF_NODE} 0 V = " + "+".join(parts["step"]))
    return {k: "+".join(v) for k, v in parts.items()}


def cart_pendulum(d: DeckLines, plant: PlantParams, x0: Sequence[float], push: dict[str, str]) -> None:
    """Eq. 2.16-2.19 with theta_dot^2 in the centripetal term (as patchgen.plant.equations.nonlinear_rhs),
    with the pushes of the scenario on the cart and, at distance l, on the pendulum tip
    (generalised forces F_tip on s and F_tip l cos(theta) on theta, as the simulator's)."""
    th, sd, thd = (f"v({STATE_NODES[k]})" for k in PLANT_STATES[1:])
    d.comment(f"Cart-pendulum, eq. 2.16-2.19: M {plant.M} kg, m {plant.m} kg, l {plant.l} m, "
              f"b_VF {plant.b_VF} kg/s, c {plant.c} kg m^2/s")
    force = f"v({FORCE_NODE})" + (f" + {push['cart']}" if push["cart"] else "")
    sdd, thdd = accelerations(plant, num, th, sd, thd, force, push["tip"], "v(x_sdd)")
    d.add(f"B_sdd x_sdd 0 V = {sdd}", f"B_thdd x_thdd 0 V = {thdd}")
    x0 = dict(zip(PLANT_STATES, x0))
    state_integrator(d, STATE_NODES["s"], sd, x0["s"])
    state_integrator(d, STATE_NODES["theta"], thd, x0["theta"])
    state_integrator(d, STATE_NODES["s_dot"], "v(x_sdd)", x0["s_dot"])
    state_integrator(d, STATE_NODES["theta_dot"], "v(x_thdd)", x0["theta_dot"])


def rotary_pendulum(d: DeckLines, plant: RotaryParams, x0: Sequence[float], push: dict[str, str]) -> None:
    """The rotary pendulum's equations (patchgen.plant.rotary_behavioural), the motor's voltage on
    the force node, the pushes' torque on the arm and force at the pendulum's tip."""
    nodes = state_nodes(PLANT_MODELS["rotary-pendulum"])
    names = tuple(nodes)
    th, ad, thd = (f"v({nodes[k]})" for k in names[1:])
    d.comment(f"Rotary pendulum (Cazzolato and Prime): arm {plant.m_r} kg, {plant.L_r} m; pendulum {plant.m_p} kg, "
              f"{plant.L_p} m; motor {plant.R_m} ohm, k_t {plant.k_t}, k_m {plant.k_m}")
    add, thdd = rotary_accelerations(plant, num, th, ad, thd, f"v({FORCE_NODE})", push["cart"], push["tip"])
    d.add(f"B_add x_add 0 V = {add}", f"B_thdd x_thdd 0 V = {thdd}")
    start = dict(zip(names, x0))
    state_integrator(d, nodes[names[0]], ad, start[names[0]])
    state_integrator(d, nodes[names[1]], thd, start[names[1]])
    state_integrator(d, nodes[names[2]], "v(x_add)", start[names[2]])
    state_integrator(d, nodes[names[3]], "v(x_thdd)", start[names[3]])
