"""Scaling: a design's control law as signal blocks in machine volts.

Every signal on the machine is a voltage ``volts_per_unit * quantity``. Sensors give s, theta,
s_dot (table A.2). Other signals come from blocks the allocator will put on amplifiers:

- ``sum``:           v = sum_j c_j v_j
- ``integrate``:     dv/dt = (1/T) sum_j c_j v_j           (T: the machine's time scale, its
                     slowest integrator mode's; patchgen.patch.time_scales may move a block to a
                     faster mode, rescaling its coefficients, and names the mode)
- ``differentiate``: (rolloff s + 1) v = T_d s sum_j c_j v_j
- ``lag``:           (tau s + 1) v = sum_j c_j v_j  (built as an integrator with its own output
                     fed back through a pot when the coefficients allow: see lag_block)

The control voltage is the block ``u_c``: u_c = F/K_U = -(1/K_U) K x, so the coefficient on a
state's voltage is -K_i / (K_sensor_i K_U); conventions.md's wired gain K_i/(K_sensor_i K_U) is
its negative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from patchgen.design.lqg import Design
from patchgen.plant.plant_model import CART, PlantModel
from patchgen.profiles.machine import MachineProfile


@dataclass(frozen=True)
class Term:
    """One coefficient of a block: the signal it scales and by how much (and the design's value when rounded)."""

    signal: str
    coeff: float
    design: float | None = None  # the design's value when coeff was changed (pot resolution)

    @property
    def wanted(self) -> float:
        return self.coeff if self.design is None else self.design


@dataclass(frozen=True)
class Block:
    """A signal the machine must produce: a sum, integral, derivative or lag of terms, in volts."""

    name: str  # the signal it produces
    kind: str  # sum | integrate | differentiate | lag
    terms: tuple[Term, ...]
    volts_per_unit: float
    unit: str
    purpose: str
    T_d_s: float | None = None
    rolloff_s: float | None = None
    tau_s: float | None = None
    mode: str | None = None  # an integrate block's integrator mode (patchgen.patch.time_scales)
    settles: bool = False  # an integrate block that starts settled on its input, as a differentiator does
    # (a lag closed through a difference: it runs while the pendulum is held, so it has no IC of its own)
    partial_scale: float = 1.0  # a partial sum of its terms (patchgen.patch.allocation's pre-summer) carries
    # them times this, and the block takes it 1 / this times: below 1 to keep the partial sum inside the reference


@dataclass(frozen=True)
class Realization:
    """The control law as blocks (in dependency-free order) over the sensor voltages."""

    design_name: str
    sensors: dict[str, float]  # sensor id -> volts per unit
    blocks: tuple[Block, ...]
    K_U: float
    below_resolution: str
    notes: tuple[str, ...] = ()
    labels: dict[str, str] = field(default_factory=dict)  # sensor id -> what reads it, where the spec says
    inverter_gains: dict[str, float] = field(default_factory=dict)  # sensor id -> the gain its inverter (where
    # the allocation needs one) takes it at, its consumers taking the inverter 1 / gain times (signal-to-noise)
    plant: PlantModel = CART  # whose sensors and states the law reads

    def label(self, sensor: str) -> str:
        """What reads a sensor, as the sheet names it: the spec's word, else the plant's reference bench's
        instrument (the thesis's pots and tachometer for the cart)."""
        return self.labels.get(sensor, self.plant.sensor_labels[sensor])

    def unit(self, signal: str) -> str:
        """The SI unit of a state or sensor signal."""
        return self.plant.state_units()[signal]

    def block(self, name: str) -> Block:
        return next(b for b in self.blocks if b.name == name)


def realize(design: Design, machine: MachineProfile) -> Realization:
    """Scale the design's controller into machine volts (gains through sensor constants and K_U)."""
    spec = design.spec
    ks = spec.sensors.constants()
    KU = spec.actuator.K_U
    T = machine.time_scale_s
    e = spec.estimator.kind
    blocks: list[Block] = []
    scale: dict[str, float] = dict(ks)  # volts per unit of each state signal on the machine
    states = design.states
    units = spec.plant_model.state_units()
    sc = spec.actuator.state_scale
    if e == "kalman":
        return _kalman(design, machine, ks, KU, T)
    if e == "reduced_observer":
        return _reduced_observer(design, ks, KU, T, max(machine.input_weights) * machine.pot_max,
                                 integrator_reach(machine))
    for rate in (r for r in spec.sensors.derived() if r in states):
        if e == "none":
            raise spec.error("estimator.kind", f"{rate} is not measured on the bench: choose "
                             "\"differentiator\", \"filtered_differentiator\", \"reduced_observer\" or "
                             "\"kalman\" to patch this design")
        roll, pos = design.estimator.rolloff_s, spec.plant_model.position_of[rate]
        scale[rate] = spec.rate_scale(rate)
        blocks.append(Block(rate, "differentiate", (Term(pos, 1.0),), scale[rate], units[rate],
                            f"{rate} from {pos} (practical differentiator)" if e == "differentiator" else
                            f"{rate} from {pos} (differentiator, roll-off {roll:g} s chosen from the noise)",
                            T_d_s=scale[rate] / ks[pos], rolloff_s=roll))
    ints, int_scale, notes = _integral_blocks(design, ks, T)
    blocks += ints
    scale.update(int_scale)
    if "actuator" in states:
        # model of the actuator driven by u_c: x_a' = -x_a/tau + u/(tau sc); voltage sc/K_U per unit
        scale["actuator"] = sc / KU
        tau = spec.actuator.tau
        if spec.actuator.model != "lag":
            raise spec.error("actuator.model", "an actuator state with a zero can only be patched with a "
                             "Kalman estimator")
        blocks.append(lag_block("actuator", (Term("u_c", 1.0),), scale["actuator"], units["actuator"],
                                "actuator state from a first-order lag model driven by u_c", tau, T,
                                integrator_reach(machine)))
    terms = tuple(Term(s, -float(design.K[0, i]) / (scale[s] * KU)) for i, s in enumerate(states))
    blocks.append(Block("u_c", "sum", terms, 1.0, "V", "control voltage to the servo amplifier"))
    return Realization(spec.name, ks, tuple(blocks), KU, spec.patch.below_resolution, tuple(notes),
                       dict(spec.sensors.labels), plant=spec.plant_model)


def integrator_reach(machine: MachineProfile) -> float:
    """The largest coefficient, at the machine's time scale, an integrator carries on one input on
    some mode: the top gain on the fastest mode, scaled back to the slowest (patchgen.patch.time_scales
    moves a block there). The top gain itself on a machine with one mode."""
    top = max(machine.input_weights) * machine.pot_max
    fastest = max(m.k0_per_s for m in machine.integrator_modes)
    return top if len(machine.integrator_modes) == 1 else top * fastest * machine.time_scale_s


def lag_block(name: str, terms: tuple[Term, ...], volts_per_unit: float, unit: str, purpose: str, tau: float,
              T: float, top: float) -> Block:
    """A first-order lag (tau s + 1) v = sum c_j v_j, built from the machine's own parts where it can.

    As an integrator with its own output fed back through a pot: dv/dt = (1/T) (sum (T/tau) c_j v_j
    - (T/tau) v), so the time constant is a dial setting (T/tau on a weighted input) and no external
    part is needed. That takes every coefficient times T/tau within ``top`` (the largest weighted
    input, on the fastest integrator mode: :func:`integrator_reach`); otherwise the block stays a
    lag (a summer with an external capacitor tau/R_f across its feedback resistor,
    patchgen.patch.parts).
    """
    k = T / tau
    if k <= top and all(abs(t.coeff) * k <= top for t in terms):
        scaled = tuple(Term(t.signal, t.coeff * k, None if t.design is None else t.design * k) for t in terms)
        return Block(name, "integrate", scaled + (Term(name, -k),), volts_per_unit, unit,
                     f"{purpose}; a lag of {tau:g} s: an integrator with its output fed back through a pot")
    return Block(name, "lag", terms, volts_per_unit, unit, purpose, tau_s=tau)


def _integral_blocks(design: Design, ks: dict[str, float], T: float):
    """The integral states as integrators of the sensor voltages (gain 1: volts per unit s equal the
    sensor's), their scales, and a note for each design leak the pure integrator leaves out."""
    blocks, scale, notes = [], {}, []
    plant = design.spec.plant_model
    for name, src in (("int_s", plant.position), ("int_theta", plant.angle)):
        if name in design.states:
            scale[name] = ks[src]
            blocks.append(Block(name, "integrate", (Term(src, T),), ks[src], plant.state_units()[name],
                                f"integral of {src}"))
            leak = getattr(design.spec.integrators, f"{name}_leak")
            if leak:
                notes.append(f"{name}: the design's leak of {leak:g} 1/s is not patched (a pure integrator)")
    return blocks, scale, notes


def _kalman(design: Design, machine: MachineProfile, ks, KU, T) -> Realization:
    """Kalman estimator states on integrators: xhat' = A xhat + B u + L (y - C xhat), in volts."""
    spec = design.spec
    model = design.model
    est = model.estimated
    Ae, Be, Ce = model.submodel(est)
    L = design.estimator.L
    sc = spec.actuator.state_scale
    sv = {**ks, **{r: spec.rate_scale(r) for r in spec.sensors.derived()}, "actuator": sc / KU}
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
        blocks.append(Block(f"xhat_{s}", "integrate", tuple(terms), sv[s], spec.plant_model.state_units()[s],
                            f"Kalman estimate of {s}"))
    scale = {f"xhat_{s}": sv[s] for s in est}
    ints, int_scale, notes = _integral_blocks(design, ks, T)
    blocks += ints
    scale.update(int_scale)
    sig = {s: (f"xhat_{s}" if s in est else s) for s in model.states}
    terms = tuple(Term(sig[s], -float(design.K[0, i]) / (scale[sig[s]] * KU)) for i, s in enumerate(model.states))
    blocks.append(Block("u_c", "sum", terms, 1.0, "V", "control voltage to the servo amplifier"))
    return Realization(spec.name, dict(ks), tuple(blocks), KU, spec.patch.below_resolution, tuple(notes),
                       dict(spec.sensors.labels), plant=spec.plant_model)


def _reduced_observer(design: Design, ks: dict[str, float], KU: float, T: float,
                      top: float, reach: float) -> Realization:
    """Reduced observer (patchgen.design.observer) on lag amplifiers: z_i' = -p z_i + sum F_ij z_j + G_i y
    + H_i u, each a lag of time constant 1/p (its own feedback needs no pot).

    Scaling: each z's voltage is scaled so its largest input coefficient is exactly ``top`` (the
    largest a weighted input gives without a pot; the biggest voltage the inputs allow). The
    observer gain Lr is folded into the u_c summer's sensor terms (w_hat = z + Lr y) unless a
    folded coefficient would exceed ``top``; then w_hat gets its own summer, scaled so its input
    and output coefficients are balanced (geometric mean)."""
    spec = design.spec
    model = design.model
    obs = design.estimator.observer
    w = list(obs.unmeasured)
    y = list(model.measured)
    tau = 1.0 / obs.pole
    alpha: dict[str, float] = {}
    for i in reversed(range(len(w))):
        rates = [abs(obs.F[i, j]) / alpha[w[j]] for j in range(i + 1, len(w))]
        rates += [abs(obs.G[i, k]) / ks[m] for k, m in enumerate(y)]
        rates.append(abs(obs.H[i]) * KU)
        alpha[w[i]] = top / (tau * max(rates))
    blocks: list[Block] = []
    for i, s in enumerate(w):
        terms: list[Term] = []
        for j in range(i + 1, len(w)):
            if obs.F[i, j] != 0:
                terms.append(Term(f"z_{w[j]}", _exact(tau * obs.F[i, j] * alpha[s] / alpha[w[j]], top)))
        for k, m in enumerate(y):
            if obs.G[i, k] != 0:
                terms.append(Term(m, _exact(tau * obs.G[i, k] * alpha[s] / ks[m], top)))
        if obs.H[i] != 0:
            terms.append(Term("u_c", _exact(tau * obs.H[i] * alpha[s] * KU, top)))
        blocks.append(lag_block(f"z_{s}", tuple(terms), alpha[s], spec.plant_model.state_units()[s],
                                f"reduced observer: {s} estimate minus its sensor part (pole {obs.pole:g} rad/s)",
                                tau, T, reach))
    scale = {f"z_{s}": alpha[s] for s in w}
    ints, int_scale, notes = _integral_blocks(design, ks, T)
    blocks += ints
    scale.update(int_scale)
    Ky = design.K[0, [model.index(m) for m in y]]
    Kw = design.K[0, [model.index(s) for s in w]]
    folded = Ky + Kw @ obs.Lr
    fold = [s for i, s in enumerate(w)
            if all(abs(folded[k]) / (ks[m] * KU) <= top for k, m in enumerate(y))]
    ysum = Ky + sum((Kw[i] * obs.Lr[i] for i, s in enumerate(w) if s in fold), np.zeros(len(y)))
    uterms = [Term(m, -float(ysum[k]) / (ks[m] * KU)) for k, m in enumerate(y)]
    for i, s in enumerate(w):
        if s in fold:
            uterms.append(Term(f"z_{s}", -float(Kw[i]) / (alpha[s] * KU)))
            continue
        # w_hat = z + Lr y on its own summer, scale beta: inputs beta/alpha, Lr beta/k; out K/(beta K_U)
        ins = max([1.0 / alpha[s]] + [abs(obs.Lr[i, k]) / ks[m] for k, m in enumerate(y)])
        beta = math.sqrt(abs(Kw[i]) / (KU * ins))
        hterms = [Term(f"z_{s}", beta / alpha[s])]
        hterms += [Term(m, float(obs.Lr[i, k]) * beta / ks[m]) for k, m in enumerate(y) if obs.Lr[i, k] != 0]
        blocks.append(Block(f"what_{s}", "sum", tuple(hterms), beta, spec.plant_model.state_units()[s],
                            f"reduced observer's estimate of {s} (z plus its sensor part)"))
        uterms.append(Term(f"what_{s}", -float(Kw[i]) / (beta * KU)))
    uterms += [Term(n, -design.gain(n) / (scale[n] * KU)) for n in model.states if n.startswith("int_")]
    blocks.append(Block("u_c", "sum", tuple(uterms), 1.0, "V", "control voltage to the servo amplifier"))
    return Realization(spec.name, dict(ks), tuple(blocks), KU, spec.patch.below_resolution, tuple(notes),
                       dict(spec.sensors.labels), plant=spec.plant_model)


def _exact(c: float, top: float) -> float:
    """A coefficient the scaling made +/-top, exactly (so the allocator patches it without a pot)."""
    return math.copysign(top, c) if math.isclose(abs(c), top, rel_tol=1e-9) else c
