"""Scaling: a design's control law as signal blocks in machine volts.

Every signal on the machine is a voltage ``volts_per_unit * quantity``. Sensors give s, theta,
s_dot (table A.2). Other signals come from blocks the allocator will put on amplifiers:

- ``sum``:           v = sum_j c_j v_j
- ``integrate``:     dv/dt = (1/T) sum_j c_j v_j           (T: the machine's time scale)
- ``differentiate``: (rolloff s + 1) v = T_d s sum_j c_j v_j
- ``lag``:           (tau s + 1) v = sum_j c_j v_j

The control voltage is the block ``u_c``: u_c = F/K_U = -(1/K_U) K x, so the coefficient on a
state's voltage is -K_i / (K_sensor_i K_U); conventions.md's wired gain K_i/(K_sensor_i K_U) is
its negative.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .design import Design
from .machine import MachineProfile

SENSOR_UNITS = {"s": "m", "theta": "rad", "s_dot": "m/s"}
SENSOR_LABELS = {"s": "cart position pot", "theta": "pendulum angle pot", "s_dot": "motor tachometer"}


@dataclass(frozen=True)
class Term:
    signal: str
    coeff: float
    design: float | None = None  # the design's value when coeff was changed (pot resolution)

    @property
    def wanted(self) -> float:
        return self.coeff if self.design is None else self.design


@dataclass(frozen=True)
class Block:
    name: str  # the signal it produces
    kind: str  # sum | integrate | differentiate | lag
    terms: tuple[Term, ...]
    volts_per_unit: float
    unit: str
    purpose: str
    T_d_s: float | None = None
    rolloff_s: float | None = None
    tau_s: float | None = None


@dataclass(frozen=True)
class Realization:
    """The control law as blocks (in dependency-free order) over the sensor voltages."""

    design_name: str
    sensors: dict[str, float]  # sensor id -> volts per unit
    blocks: tuple[Block, ...]
    K_U: float
    below_resolution: str
    notes: tuple[str, ...] = ()

    def block(self, name: str) -> Block:
        return next(b for b in self.blocks if b.name == name)


def realize(design: Design, machine: MachineProfile) -> Realization:
    """Scale the design's controller into machine volts (gains through sensor constants and K_U)."""
    spec = design.spec
    ks = {"s": spec.sensors.s, "theta": spec.sensors.theta, "s_dot": spec.sensors.s_dot}
    KU = spec.actuator.K_U
    T = machine.time_scale_s
    e = spec.estimator.kind
    blocks: list[Block] = []
    scale: dict[str, float] = dict(ks)  # volts per unit of each state signal on the machine
    units = {"theta_dot": "rad/s", "int_s": "m s", "int_theta": "rad s", "actuator": "N"}
    notes: list[str] = []
    states = design.states
    sc = spec.actuator.state_scale
    if e == "kalman":
        return _kalman(design, machine, ks, KU, T)
    if "theta_dot" in states:
        if e == "none":
            raise spec.error("estimator.kind", "theta_dot is not measured on the bench: choose "
                             "\"differentiator\" or \"kalman\" to patch this design")
        roll = design.estimator.rolloff_s
        scale["theta_dot"] = spec.theta_dot_scale()
        blocks.append(Block("theta_dot", "differentiate", (Term("theta", 1.0),), scale["theta_dot"], "rad/s",
                            "theta_dot from theta (practical differentiator)",
                            T_d_s=scale["theta_dot"] / ks["theta"], rolloff_s=roll))
    for name, src in (("int_s", "s"), ("int_theta", "theta")):
        if name in states:
            scale[name] = ks[src]  # volts per (unit s): integrating the sensor voltage with gain 1
            blocks.append(Block(name, "integrate", (Term(src, T),), scale[name],
                                units[name], f"integral of {src}"))
            leak = getattr(spec.integrators, f"{name}_leak")
            if leak:
                notes.append(f"{name}: the design's leak of {leak:g} 1/s is not patched (a pure integrator)")
    if "actuator" in states:
        # model of the actuator driven by u_c: x_a' = -x_a/tau + u/(tau sc); voltage sc/K_U per unit
        scale["actuator"] = sc / KU
        tau = spec.actuator.tau
        if spec.actuator.model != "lag":
            raise spec.error("actuator.model", "an actuator state with a zero can only be patched with a "
                             "Kalman estimator")
        blocks.append(Block("actuator", "lag", (Term("u_c", 1.0),), scale["actuator"], "N",
                            "actuator state from a first-order lag model driven by u_c", tau_s=tau))
    terms = tuple(Term(s, -float(design.K[0, i]) / (scale[s] * KU)) for i, s in enumerate(states))
    blocks.append(Block("u_c", "sum", terms, 1.0, "V", "control voltage to the servo amplifier"))
    return Realization(spec.name, ks, tuple(blocks), KU, spec.patch.below_resolution, tuple(notes))


def _kalman(design: Design, machine: MachineProfile, ks, KU, T) -> Realization:
    """Kalman estimator states on integrators: xhat' = A xhat + B u + L (y - C xhat), in volts."""
    spec = design.spec
    model = design.model
    est = model.estimated
    Ae, Be, Ce = model.submodel(est)
    L = design.estimator.L
    sc = spec.actuator.state_scale
    sv = {"s": ks["s"], "theta": ks["theta"], "s_dot": ks["s_dot"], "theta_dot": spec.theta_dot_scale(),
          "actuator": sc / KU}
    units = {"s": "m", "theta": "rad", "s_dot": "m/s", "theta_dot": "rad/s", "actuator": "N"}
    S = np.diag([sv[s] for s in est])
    Sy = np.diag([ks[m] for m in model.measured])
    Av = S @ (Ae - L @ Ce) @ np.linalg.inv(S)
    Bv = S @ Be[:, 0] * KU
    Lv = S @ L @ np.linalg.inv(Sy)
    blocks: list[Block] = []
    for i, s in enumerate(est):
        terms = [Term(f"xhat_{t}", T * Av[i, j]) for j, t in enumerate(est) if Av[i, j] != 0]
        terms += [Term(m, T * Lv[i, j]) for j, m in enumerate(model.measured) if Lv[i, j] != 0]
        if Bv[i] != 0:
            terms.append(Term("u_c", T * Bv[i]))
        blocks.append(Block(f"xhat_{s}", "integrate", tuple(terms), sv[s], units[s], f"Kalman estimate of {s}"))
    scale = {f"xhat_{s}": sv[s] for s in est}
    for name, src in (("int_s", "s"), ("int_theta", "theta")):
        if name in model.states:
            scale[name] = ks[src]
            blocks.append(Block(name, "integrate", (Term(src, T),), ks[src], "", f"integral of {src}"))
    sig = {s: (f"xhat_{s}" if s in est else s) for s in model.states}
    terms = tuple(Term(sig[s], -float(design.K[0, i]) / (scale[sig[s]] * KU)) for i, s in enumerate(model.states))
    blocks.append(Block("u_c", "sum", terms, 1.0, "V", "control voltage to the servo amplifier"))
    return Realization(spec.name, dict(ks), tuple(blocks), KU, spec.patch.below_resolution)
