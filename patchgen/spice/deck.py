"""The patch at the electrical level: a SPICE deck of the patched machine and the bench.

patchgen's own simulator treats each amplifier as an ideal element. This module writes the patched
circuit, read once by patchgen.patch.reading, as a circuit simulator sees it: every amplifier an
inverting op-amp macromodel with finite open-loop gain, output resistance and a feedback bound that
keeps its output within the saturation voltage (no gain-bandwidth or slew limit: OPAMP_MODEL); the
machine's input resistor for each weight its profile declares, feedback resistors and capacitors,
the external parts the netlist lists (patchgen.patch.parts); every pot a resistive divider loaded by
the input resistor it feeds; noise, random forces on the plant and drift as patchgen's simulator
takes them
(patchgen.bench.noise_drift), drift as an offset voltage and a bias current. The sensors' constants
are the bench's (patchgen.bench.circuit.sensor_constants), as in the simulator. The cart-pendulum
and the actuator are behavioural sources (patchgen.spice.plant), so the whole loop runs in ngspice
(patchgen.spice.run). An independent simulator that agrees with patchgen's own is the strongest
check that a patch sheet is right.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from patchgen.bench.circuit import sensor_constants
from patchgen.bench.noise_drift import NoiseAndDrift
from patchgen.inputs.drive_fields import motor_of
from patchgen.inputs.scenario import Disturbance
from patchgen.patch.netlist import Amplifier, Netlist, Pot
from patchgen.patch.parts import parts_for
from patchgen.patch.reading import Reading, Stage, read
from patchgen.plant.drive import with_rotor
from patchgen.plant.equations import PlantParams
from patchgen.plant.plant_model import CART, PLANT_MODELS, PlantModel
from patchgen.plant.rotary_equations import RotaryParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.spice.elements import DeckLines, bound, clamp, num, pot_wiper_position, spice_name, state_integrator
from patchgen.spice.noise import noise_source, play_noise, random_forces
from patchgen.spice.plant import (
    CONTROL_NODE,
    FORCE_NODE,
    S_REF_NODE,
    STATE_NODES,
    actuator,
    cart_pendulum,
    disturbances,
    rotary_pendulum,
    state_nodes,
)

# What each amplifier's macromodel includes and leaves out (printed by patchgen spice)
OPAMP_MODEL = ("finite open-loop DC gain, output resistance, a soft bound at the saturation voltage, the input "
               "and feedback resistors and capacitors, loaded pots, drift as offset and bias; omitted: gain-"
               "bandwidth and slew rate (the loop's motions are a few hertz, the differentiator's roll-off at most "
               "a few hundred hertz: far below an op-amp's bandwidth), input capacitance and common-mode effects")
DECK_NAME = "patch.cir"
DATA_NAME = "patch.data"
INSTALL_HINT = ("install ngspice (Debian/Ubuntu: apt-get install ngspice) and make sure `ngspice` "
                "is on the PATH")
__all__ = ["CONTROL_NODE", "FORCE_NODE", "OPAMP_MODEL", "STATE_NODES", "SpiceDeck", "SpiceSettings", "output_vectors",
           "spice_deck"]


@dataclass(frozen=True)
class SpiceSettings:
    """What a scenario asks of the circuit run: duration, output step, initial plant state, switches.

    ``x0`` is the plant's state (the cart's [s, theta, s_dot, theta_dot]) in SI units.
    ``noise_and_drift`` gives the noise levels and drift rate, as patchgen's simulator takes them
    (patchgen.bench.noise_drift; default none). ``actuator`` "bench" uses the bench profile's
    actuator (lag, dead zone, force limit, limit switches); "ideal" is F = K_U u_c. ``max_step_s``
    bounds ngspice's time step (default: the output step). ``disturbances`` are the scenario's
    pushes (on the cart, a rotary arm's end or the pendulum tip) and position steps, as sources.
    ``noise_step_s`` is the step of the simulator the noisy run is judged against: no noise source
    carries a band above its Nyquist frequency (0: each its own band,
    patchgen.spice.noise.noise_source).
    """

    duration_s: float
    step_s: float
    x0: tuple[float, ...]
    noise_and_drift: NoiseAndDrift = NoiseAndDrift()
    actuator: Literal["bench", "ideal"] = "bench"
    max_step_s: float | None = None
    seed: int = 1
    reltol: float = 1e-5
    disturbances: tuple[Disturbance, ...] = ()
    noise_step_s: float = 0.0


def _source_node(reading: Reading, source: str) -> str:
    """The node carrying a source's voltage: a sensor's output or an amplifier's."""
    return f"sens_{spice_name(source)}" if source in reading.sensors else _amp_out(source)


def _amp_out(amp_id: str) -> str:
    return f"{spice_name(amp_id)}_out"


def _sensors(d: DeckLines, net: Netlist, bench: BenchProfile, machine: MachineProfile,
             settings: SpiceSettings) -> None:
    """Sensor voltage = bench sensor constant x state, limited (smoothly) at the machine reference:
    the sensors cannot drive the patch beyond it, and a fallen pendulum (theta of many radians)
    would otherwise put hundreds of volts on the differentiator and stall ngspice's time step.
    Inside the reference the limit changes nothing (its rounding is below 1e-9 V up to 80 % of it)."""
    d.comment(f"Sensors: volts = bench sensor constant x state, limited at +/-{machine.reference_V} V")
    levels = settings.noise_and_drift
    filters = bench.sensors.filters()
    pm = PLANT_MODELS[bench.plant]
    nodes = state_nodes(pm)
    if bench.sensors.quanta():  # a staircase stalls ngspice's time step at every count
        d.comment("Encoder counts left out: the deck reads the states continuously (the simulator has the counts)")
    for s, k in zip(net.sensors, sensor_constants(net, bench)):
        if s.id not in nodes:
            raise ValueError(f"sensor {s.id!r} is not a plant state")
        node = f"sens_{spice_name(s.id)}"
        rms = levels.sensor_V_rms.get(s.id, 0.0)
        clean = f"{node}_clean" if rms > 0 else node
        state = f"v({nodes[s.id]})"
        if s.id in filters:
            state = _velocity_filter(d, pm, s.id, filters[s.id], settings.x0)
        if s.id == pm.position and any(x.kind == "step" for x in settings.disturbances):
            state = f"({state}-v({S_REF_NODE}))"  # a step moves the reference the s sensor is read against
        volts = clamp(f"{num(k)}*{state}", machine.reference_V)
        d.add(f"B_sens_{spice_name(s.id)} {clean} 0 V = {volts}")
        if rms > 0:
            noise_source(d, f"E_sens_{spice_name(s.id)}_noise", node, clean, rms,
                          levels.sensor_bandwidth_Hz, settings.duration_s, settings.noise_step_s)


def _velocity_filter(d: DeckLines, pm: PlantModel, rate: str, f, x0) -> str:
    """A velocity as the bench reads it: the rate of its position's reading through
    wn^2 / (s^2 + 2 zeta wn s + wn^2), two states settled on the run's start. Returns the
    expression of the filtered rate."""
    position = pm.position_of[rate]
    x = f"v({state_nodes(pm)[position]})"
    start = dict(zip(pm.state_names, x0))
    y, yd = f"vf_{spice_name(rate)}", f"vfd_{spice_name(rate)}"
    d.comment(f"{rate} from a filter of {position}'s reading: wn {f.wn_rad_s:g} rad/s, zeta {f.zeta:g}")
    state_integrator(d, y, f"v({yd})", start[position])
    state_integrator(d, yd, f"{num(f.wn_rad_s ** 2)}*({x}-v({y}))-{num(2 * f.zeta * f.wn_rad_s)}*v({yd})",
                     start[rate])
    return f"v({yd})"


def _pot(d: DeckLines, reading: Reading, machine: MachineProfile, pot: Pot, load_ohm: float | None) -> str:
    """A pot as two resistors; returns its wiper node. ``load_ohm`` None: no resistive load."""
    rp = machine.components.pot_resistance_ohm
    a = (pot_wiper_position(pot.setting, rp, load_ohm) if load_ohm is not None
         else min(max(pot.setting, 0.0), 1.0))
    top, wiper = _source_node(reading, pot.source), f"pot_{spice_name(pot.id)}_w"
    # A wiper at an end would make a zero resistor: keep a milliohm so the matrix stays regular.
    r_upper, r_lower = max((1.0 - a) * rp, 1e-3), max(a * rp, 1e-3)
    load_txt = f"load {num(load_ohm)} ohm" if load_ohm is not None else "no resistive load"
    d.comment(f"{pot.id}: setting {pot.setting} (loaded), wiper at {a:.6f} of {num(rp)} ohm, {load_txt}")
    d.add(f"R_{spice_name(pot.id)}_up {top} {wiper} {num(r_upper)}",
          f"R_{spice_name(pot.id)}_lo {wiper} 0 {num(r_lower)}")
    return wiper


def _amplifier(d: DeckLines, net: Netlist, reading: Reading, amp: Amplifier, machine: MachineProfile,
               settings: SpiceSettings) -> None:
    """One amplifier: the op-amp macromodel, its output noise and drift sources, its input
    resistors (through loaded pots) or capacitors, and its feedback element."""
    c, imp, levels = machine.components, machine.imperfections, settings.noise_and_drift
    stage = reading.amplifiers[amp.id]
    n = spice_name(amp.id)
    sj, core, out = f"{n}_sj", f"{n}_core", _amp_out(amp.id)
    rms = levels.amplifier_V_rms
    fb = f"{n}_fb" if rms > 0 else out  # feedback is taken before an output-noise source
    cap = _feedback_capacitor(stage, machine)
    rate = levels.drift_at(1.0 / stage.T_s if stage.role == "integrator" else None, machine)
    offset, bias = _drift_sources(stage, machine, cap, rate)
    plus = f"{n}_plus" if offset else "0"
    d.comment(f"{amp.id}: {amp.role}, carries {amp.carries.polarity:+d} x {amp.carries.volts_per_unit} "
              f"V/unit x {amp.carries.quantity}")
    # Op-amp macromodel: finite open-loop gain (the non-inverting input grounded, or at the offset
    # voltage), output resistance, and a feedback bound that holds the output at the saturation
    # voltage (see _bound).
    vsat, gain = imp.saturation_V, c.opamp_open_loop_gain
    d.add(f"E_{n} {core} 0 {plus} {sj} {num(gain)}",
          f"R_{n}_o {core} {fb} {num(max(c.opamp_output_resistance_ohm, 1e-3))}",
          f"B_{n}_bound {fb} {sj} I = {bound(f'v({fb})', vsat, c.feedback_resistor_ohm)}")
    if rms > 0:
        noise_source(d, f"E_{n}_noise", out, fb, rms, levels.amplifier_bandwidth_Hz, settings.duration_s,
                     settings.noise_step_s)
    if offset:
        d.add(f"V_{n}_offset {plus} 0 DC {num(offset)}")
    if bias:
        d.add(f"I_{n}_bias {sj} 0 DC {num(bias)}")

    pots = {p.id: p for p in net.pots}
    parts = [p for p in (net.parts or parts_for(net, machine)) if p.amplifier == amp.id]
    if amp.role == "differentiator":
        T_d, roll = stage.T_d_s, stage.rolloff_s  # as patchgen.patch.reading resolves them
        for inp in amp.inputs:
            src = (_pot(d, reading, machine, pots[inp.pot], None) if inp.pot else _source_node(reading, inp.source))
            cap, res = (next(p for p in parts if p.jack == inp.jack and p.kind == k) for k in ("capacitor", "resistor"))
            mid = f"{n}_{spice_name(inp.jack)}_m"
            d.comment(f"{inp.jack}: input capacitor {cap.id} (x{inp.weight}, T_d {T_d} s) and series resistor "
                      f"{res.id} for a {roll} s roll-off (the netlist's parts)")
            d.add(f"C_{n}_{spice_name(inp.jack)} {src} {mid} {num(cap.value)}",
                  f"R_{n}_{spice_name(inp.jack)}_s {mid} {sj} {num(res.value)}")
        d.add(f"R_{n}_f {sj} {fb} {num(c.feedback_resistor_ohm)}")
        return

    for inp in amp.inputs:
        r_in = machine.components.input_resistor_ohm(inp.weight)
        src = (_pot(d, reading, machine, pots[inp.pot], r_in) if inp.pot else _source_node(reading, inp.source))
        d.add(f"R_{n}_{spice_name(inp.jack)} {src} {sj} {num(r_in)}")
    if amp.role in ("summer", "inverter"):
        d.add(f"R_{n}_f {sj} {fb} {num(c.feedback_resistor_ohm)}")
    elif amp.role == "integrator":
        d.add(f"C_{n}_f {sj} {fb} {num(cap)}")
        _capacitor_ic(d, sj, fb, amp, offset)
    elif amp.role == "lag":  # a summer with the parts list's capacitor across its feedback resistor
        d.add(f"R_{n}_f {sj} {fb} {num(c.feedback_resistor_ohm)}", f"C_{n}_f {sj} {fb} {num(cap)}")
        _capacitor_ic(d, sj, fb, amp, offset)
    else:  # pragma: no cover - the schema admits no other role
        raise ValueError(f"unknown amplifier role {amp.role!r}")


def _feedback_capacitor(stage: Stage, machine: MachineProfile) -> float | None:
    """The feedback capacitor of an integrator or lag, from the time constant the reading resolved
    (as patchgen's simulator takes it): an integrator's time scale over its x1 input resistor, a
    lag's tau over the feedback resistor. None for the other roles."""
    if stage.role == "integrator":
        return stage.T_s / machine.components.input_resistor_ohm(1)
    if stage.role == "lag":  # the external capacitor of patchgen.patch.parts: tau / R_f
        return stage.tau_s / machine.components.feedback_resistor_ohm
    return None


def _drift_sources(stage: Stage, machine: MachineProfile, cap: float | None,
                   rate_V_per_s: float) -> tuple[float, float]:
    """Offset voltage and bias current that drift an integrating amplifier as patchgen's simulator
    drifts it, at the run's rate through its feedback capacitor ``cap`` (C): an integrator has the
    profile's offset e and bias i scaled so that e/(R C) + i/C is that rate; a lag, and an
    integrator whose profile has no drift, a bias current alone. Other amplifiers do not drift."""
    imp = machine.imperfections
    if not rate_V_per_s or cap is None:
        return 0.0, 0.0
    if stage.role == "integrator":
        own = (imp.integrator_offset_V / (machine.components.input_resistor_ohm(1) * cap)
               + imp.integrator_bias_A / cap)
        if own > 0:
            k = rate_V_per_s / own
            return imp.integrator_offset_V * k, imp.integrator_bias_A * k
    return 0.0, rate_V_per_s * cap


def _capacitor_ic(d: DeckLines, sj: str, out: str, amp: Amplifier, sj_V: float) -> None:
    """Initial condition of a feedback capacitor: both its ends are held during the operating
    point (the output at ic_V, the summing junction where the amplifier keeps it), as the IC mode
    charges the capacitor; holding only the output would let the open-loop amplifier saturate."""
    d.ics[out] = float(amp.ic_V or 0.0)
    d.ics[sj] = float(sj_V)


def output_vectors(net: Netlist, pm: PlantModel = CART) -> list[tuple[str, str]]:
    """(signal name, ngspice vector) written by ``wrdata``, in column order: the plant states, u_c,
    the force (the plant's input) and every amplifier's output (netlist order)."""
    vecs = [(k, f"v({node})") for k, node in state_nodes(pm).items()]
    vecs += [("u_c", f"v({CONTROL_NODE})"), ("force", f"v({FORCE_NODE})")]
    vecs += [(a.id, f"v({_amp_out(a.id)})") for a in net.amplifiers]
    return vecs


@dataclass(frozen=True)
class SpiceDeck:
    """An ngspice deck and the files it reads (the noise table, when noise is on), by name.

    ``output_step_s``: the step at which ngspice writes its solution (interpolated as it runs),
    or None when it writes every time point it took.
    """

    text: str
    files: dict[str, str] = field(default_factory=dict)
    output_step_s: float | None = None

    def write(self, directory: str | Path) -> Path:
        """Write the deck (patch.cir) and its files into ``directory``; return the deck's path."""
        out = Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        chunk = 1 << 20  # characters at a time: the noise table is tens of megabytes, not to be held
        for name, body in self.files.items():  # again as its encoding
            with open(out / name, "w") as f:
                for i in range(0, len(body), chunk):
                    f.write(body[i:i + chunk])
        (out / DECK_NAME).write_text(self.text)
        return out / DECK_NAME

    def __str__(self) -> str:
        return self.text


def spice_deck(net: Netlist, plant: PlantParams | RotaryParams, bench: BenchProfile, machine: MachineProfile,
               settings: SpiceSettings) -> SpiceDeck:
    """The patched circuit and the bench as an ngspice deck.

    Its .control block runs the transient and writes time, the plant states, u_c, the force and
    every amplifier output to patch.data: at every time point ngspice takes or, when noise is on,
    at the output step. Same inputs and seed, same bytes.

    Parameters
    ----------
    net : Netlist
        The patch, as wired.
    plant : PlantParams or RotaryParams
        The cart-pendulum or the rotary pendulum (the bench's plant).
    bench, machine : BenchProfile, MachineProfile
        The sensors, actuator and track; the machine's components and imperfections.
    settings : SpiceSettings
        Duration, output step, initial state, noise and drift, actuator, disturbances.

    Returns
    -------
    SpiceDeck
        The deck, its noise table when noise is on, and the step it writes at
        (``output_step_s``; None: ngspice's own time points).
    """
    if machine.id != net.machine:
        raise ValueError(f"netlist is for machine {net.machine!r}, profile is {machine.id!r}")
    reading = read(net, machine.imperfections.differentiator_rolloff_s)  # checks the wiring, too
    d = DeckLines(np.random.default_rng(settings.seed))
    d.add(f"patchgen: {net.design} on {machine.name}, bench {bench.name}")
    d.comment("Written by patchgen (patchgen.spice.deck). Volts on the machine; plant nodes carry SI states.")
    levels = settings.noise_and_drift
    d.comment(f"Noise {'on' if levels.noisy else 'off'}, drift {'on' if levels.drift_V_per_s else 'off'}, "
              f"actuator {settings.actuator}")
    _sensors(d, net, bench, machine, settings)
    for amp in net.amplifiers:
        _amplifier(d, net, reading, amp, machine, settings)
    d.comment(f"Control voltage u_c = output of {reading.output}")
    d.add(f"V_uc {CONTROL_NODE} {_source_node(reading, reading.output)} DC 0")
    actuator(d, plant, bench, settings.actuator == "ideal")
    lever = 1.0 if isinstance(plant, PlantParams) else plant.L_r  # a push at a rotary arm's end: its torque
    pushes = random_forces(d, disturbances(d, settings.disturbances, lever), levels, settings.duration_s,
                           settings.noise_step_s)
    if isinstance(plant, PlantParams):
        cart_pendulum(d, with_rotor(plant, motor_of(bench.actuator)), settings.x0, pushes)
    else:
        rotary_pendulum(d, plant, settings.x0, pushes)

    max_step = settings.max_step_s or settings.step_s
    files, dt = play_noise(d, settings.seed, settings.duration_s)
    max_step = min(max_step, dt)  # the filesource sets no breakpoints: do not step over samples
    d.add(".ic " + " ".join(f"v({node})={num(v)}" for node, v in sorted(d.ics.items())))
    d.add(f".options method=gear reltol={num(settings.reltol)} abstol=1e-12 vntol=1e-9 "
          f"chgtol=1e-16 itl4=100")
    vecs = " ".join(v for _, v in output_vectors(net, PLANT_MODELS[bench.plant]))
    output_step = None
    if d.noise:  # noise makes ngspice take some 7000 points per second of run: it keeps only the
        # vectors written and writes them at the output step (its solution, interpolated as it
        # runs); without noise its own points are few, and they are the ones compared
        output_step = settings.step_s
        d.add(f".save {vecs}", ".options interp")
    d.add(".control",
          "set wr_singlescale",
          "set wr_vecnames",
          "option numdgt=10",
          f"tran {num(settings.step_s)} {num(settings.duration_s)} 0 {num(max_step)}",
          f"wrdata {DATA_NAME} {vecs}",
          "quit",
          ".endc",
          ".end")
    return SpiceDeck("\n".join(d.lines) + "\n", files, output_step)
