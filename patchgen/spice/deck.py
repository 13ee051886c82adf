"""The patch at the electrical level: a SPICE deck of the patched machine and the bench, run in ngspice.

patchgen's own simulator treats each amplifier as an ideal element. This module writes the patched
circuit as a circuit simulator sees it: every amplifier an inverting op-amp macromodel with finite
open-loop gain, output resistance and a feedback bound that keeps its output within the
saturation voltage; the machine's
input resistors (x1, x10), feedback resistors and capacitors; every pot a resistive divider loaded
by the input resistor it feeds; integrator drift as an offset voltage and a bias current. The
cart-pendulum (eq. 2.16-2.19, nonlinear) and the actuator are behavioural sources charging 1 F
capacitors, so the whole loop runs in ngspice. An independent simulator that agrees with patchgen's
own is the strongest check that a patch sheet is right.

ngspice runs in batch mode as a subprocess (``ngspice -b deck.cir``); its ``wrdata`` table is read
back. Volts on the machine; the plant's node voltages are its states in SI units (1 V = 1 m, 1 rad,
1 m/s, 1 rad/s, 1 N).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from patchgen.bench.circuit import sensor_constants
from patchgen.inputs.scenario import Disturbance
from patchgen.patch.netlist import Amplifier, Netlist, Pot
from patchgen.patch.reading import Stage, read
from patchgen.plant.equations import PLANT_STATES, PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.spice.elements import (
    SMOOTHING,
    bound,
    clamp,
    dead_zone,
    num,
    pot_wiper_position,
    spice_name,
)

DECK_NAME = "patch.cir"
DATA_NAME = "patch.data"
NOISE_NAME = "patch.noise"
INSTALL_HINT = ("install ngspice (Debian/Ubuntu: apt-get install ngspice) and make sure `ngspice` "
                "is on the PATH")

# Plant state nodes, in PLANT_STATES order; their voltages are the states in SI units.
STATE_NODES = {"s": "x_s", "theta": "x_theta", "s_dot": "x_sdot", "theta_dot": "x_thetadot"}
FORCE_NODE = "f_cart"
S_REF_NODE = "s_ref"  # the cart-position reference a step disturbance moves
EDGE_S = 1e-6  # s: the rise and fall of a push or step in the deck (the simulator's are sharp)
CONTROL_NODE = "u_c"


@dataclass(frozen=True)
class SpiceSettings:
    """What a scenario asks of the circuit run: duration, output step, initial plant state, switches.

    ``x0`` is [s, theta, s_dot, theta_dot] in SI units. ``actuator`` "bench" uses the bench
    profile's actuator (lag, dead zone, force limit, limit switches); "ideal" is F = K_U u_c.
    ``max_step_s`` bounds ngspice's time step (default: the output step). ``disturbances`` are
    the scenario's pushes (on the cart or the pendulum tip) and cart-position steps, as sources.
    """

    duration_s: float
    step_s: float
    x0: tuple[float, float, float, float]
    noise: bool = False
    drift: bool = False
    actuator: Literal["bench", "ideal"] = "bench"
    max_step_s: float | None = None
    seed: int = 1
    reltol: float = 1e-5
    disturbances: tuple[Disturbance, ...] = ()



# ----------------------------------------------------------------------------------------------
# Deck



@dataclass
class _Deck:
    rng: np.random.Generator
    lines: list[str] = field(default_factory=list)
    noise: list[tuple[str, float, np.ndarray]] = field(default_factory=list)
    ics: dict[str, float] = field(default_factory=dict)

    def add(self, *lines: str) -> None:
        self.lines.extend(lines)

    def comment(self, text: str) -> None:
        self.lines.append(f"* {text}")


def _source_node(net: Netlist, source: str) -> str:
    if any(s.id == source for s in net.sensors):
        return f"sens_{spice_name(source)}"
    return _amp_out(net.amp(source))


def _amp_out(amp: Amplifier) -> str:
    return f"{spice_name(amp.id)}_out"


def _noise_source(d: _Deck, name: str, plus: str, minus: str, rms: float, bandwidth_Hz: float,
                  duration_s: float) -> None:
    """White noise of the given rms, sampled at twice its bandwidth and joined linearly, as a
    voltage source ``name`` (an E element) in series between ``minus`` and ``plus``. The samples
    come from the deck's seeded generator (ngspice's TRNOISE cannot be seeded reproducibly in
    batch mode) and are played from the noise table by one XSPICE filesource (a PWL source of
    this length is quadratically slow)."""
    dt = 0.5 / bandwidth_Hz
    n = int(math.ceil(duration_s / dt)) + 1
    d.noise.append((f"nz_{len(d.noise)}", dt, d.rng.normal(0.0, rms, n)))
    d.add(f"{name} {plus} {minus} {d.noise[-1][0]} 0 1")


def _noise_table(d: _Deck, duration_s: float) -> tuple[str, float]:
    """The noise samples of every source on one time grid (the finest), and that grid's step."""
    dt = min(step for _, step, _ in d.noise)
    t = np.arange(int(math.ceil(duration_s / dt)) + 1) * dt
    cols = [np.interp(t, np.arange(len(v)) * step, v) for _, step, v in d.noise]
    rows = [f"{ti:.9g} " + " ".join(f"{c[k]:.6g}" for c in cols) for k, ti in enumerate(t)]
    return "\n".join(rows) + "\n", dt


def _sensors(d: _Deck, net: Netlist, bench: BenchProfile, machine: MachineProfile,
             settings: SpiceSettings) -> None:
    """Sensor voltage = bench sensor constant x state, limited (smoothly) at the machine reference:
    the sensors cannot drive the patch beyond it, and a fallen pendulum (theta of many radians)
    would otherwise put hundreds of volts on the differentiator and stall ngspice's time step.
    Inside the reference the limit changes nothing (its rounding is below 1e-9 V up to 80 % of it)."""
    d.comment(f"Sensors: volts = bench sensor constant x state, limited at +/-{machine.reference_V} V")
    for s, k in zip(net.sensors, sensor_constants(net, bench)):
        if s.id not in STATE_NODES:
            raise ValueError(f"sensor {s.id!r} is not a plant state")
        node = f"sens_{spice_name(s.id)}"
        rms = bench.sensors.noise_V_rms.get(s.id, 0.0) if settings.noise else 0.0
        clean = f"{node}_clean" if rms > 0 else node
        state = f"v({STATE_NODES[s.id]})"
        if s.id == "s" and any(x.kind == "step" for x in settings.disturbances):
            state = f"({state}-v({S_REF_NODE}))"  # a step moves the reference the s sensor is read against
        volts = clamp(f"{num(k)}*{state}", machine.reference_V)
        d.add(f"B_sens_{spice_name(s.id)} {clean} 0 V = {volts}")
        if rms > 0:
            _noise_source(d, f"E_sens_{spice_name(s.id)}_noise", node, clean, rms,
                          bench.sensors.noise_bandwidth_Hz, settings.duration_s)


def _pot(d: _Deck, net: Netlist, machine: MachineProfile, pot: Pot, load_ohm: float | None) -> str:
    """A pot as two resistors; returns its wiper node. ``load_ohm`` None: no resistive load."""
    rp = machine.components.pot_resistance_ohm
    a = (pot_wiper_position(pot.setting, rp, load_ohm) if load_ohm is not None
         else min(max(pot.setting, 0.0), 1.0))
    top, wiper = _source_node(net, pot.source), f"pot_{spice_name(pot.id)}_w"
    # A wiper at an end would make a zero resistor: keep a milliohm so the matrix stays regular.
    r_upper, r_lower = max((1.0 - a) * rp, 1e-3), max(a * rp, 1e-3)
    load_txt = f"load {num(load_ohm)} ohm" if load_ohm is not None else "no resistive load"
    d.comment(f"{pot.id}: setting {pot.setting} (loaded), wiper at {a:.6f} of {num(rp)} ohm, {load_txt}")
    d.add(f"R_{spice_name(pot.id)}_up {top} {wiper} {num(r_upper)}",
          f"R_{spice_name(pot.id)}_lo {wiper} 0 {num(r_lower)}")
    return wiper


def _amplifier(d: _Deck, net: Netlist, amp: Amplifier, stage: Stage, machine: MachineProfile,
               settings: SpiceSettings) -> None:
    c, imp = machine.components, machine.imperfections
    n = spice_name(amp.id)
    sj, core, out = f"{n}_sj", f"{n}_core", _amp_out(amp)
    rms = imp.amplifier_noise_V_rms if settings.noise else 0.0
    fb = f"{n}_fb" if rms > 0 else out  # feedback is taken before an output-noise source
    drift = settings.drift and amp.role == "integrator"
    plus = f"{n}_plus" if drift else "0"
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
        _noise_source(d, f"E_{n}_noise", out, fb, rms, imp.noise_bandwidth_Hz, settings.duration_s)
    if drift:
        d.add(f"V_{n}_offset {plus} 0 DC {num(imp.integrator_offset_V)}",
              f"I_{n}_bias {sj} 0 DC {num(imp.integrator_bias_A)}")

    pots = {p.id: p for p in net.pots}
    if amp.role == "differentiator":
        T_d, roll = stage.T_d_s, stage.rolloff_s  # as patchgen.patch.reading resolves them
        for inp in amp.inputs:
            src = (_pot(d, net, machine, pots[inp.pot], None) if inp.pot else _source_node(net, inp.source))
            cap = inp.weight * T_d / c.feedback_resistor_ohm
            mid = f"{n}_{spice_name(inp.jack)}_m"
            d.comment(f"{inp.jack}: input capacitor {num(cap)} F (x{inp.weight}, T_d {T_d} s; profile C "
                      f"{num(c.differentiator_capacitor_F)} F) and series resistor for a {roll} s roll-off")
            d.add(f"C_{n}_{spice_name(inp.jack)} {src} {mid} {num(cap)}",
                  f"R_{n}_{spice_name(inp.jack)}_s {mid} {sj} {num(roll / cap)}")
        d.add(f"R_{n}_f {sj} {fb} {num(c.feedback_resistor_ohm)}")
        return

    for inp in amp.inputs:
        r_in = machine.components.input_resistor_ohm(inp.weight)
        src = (_pot(d, net, machine, pots[inp.pot], r_in) if inp.pot else _source_node(net, inp.source))
        d.add(f"R_{n}_{spice_name(inp.jack)} {src} {sj} {num(r_in)}")
    if amp.role in ("summer", "inverter"):
        d.add(f"R_{n}_f {sj} {fb} {num(c.feedback_resistor_ohm)}")
    elif amp.role == "integrator":
        d.add(f"C_{n}_f {sj} {fb} {num(c.integrator_capacitor_F)}")
        _capacitor_ic(d, sj, fb, amp, imp.integrator_offset_V if drift else 0.0)
    elif amp.role == "lag":
        tau = stage.tau_s
        d.add(f"R_{n}_f {sj} {fb} {num(c.feedback_resistor_ohm)}",
              f"C_{n}_f {sj} {fb} {num(tau / c.feedback_resistor_ohm)}")
        _capacitor_ic(d, sj, fb, amp, 0.0)
    else:  # pragma: no cover - the schema admits no other role
        raise ValueError(f"unknown amplifier role {amp.role!r}")


def _capacitor_ic(d: _Deck, sj: str, out: str, amp: Amplifier, sj_V: float) -> None:
    """Initial condition of a feedback capacitor: both its ends are held during the operating
    point (the output at ic_V, the summing junction where the amplifier keeps it), as the IC mode
    charges the capacitor; holding only the output would let the open-loop amplifier saturate."""
    d.ics[out] = float(amp.ic_V or 0.0)
    d.ics[sj] = float(sj_V)


def _state_integrator(d: _Deck, node: str, rate_expr: str, x0: float) -> None:
    """dx/dt = rate: a behavioural current into a 1 F capacitor (node voltage = x)."""
    d.add(f"B_{node} 0 {node} I = {rate_expr}", f"C_{node} {node} 0 1")
    d.ics[node] = float(x0)


def _actuator(d: _Deck, plant: PlantParams, bench: BenchProfile, settings: SpiceSettings) -> None:
    act = bench.actuator
    uc = f"v({CONTROL_NODE})"
    if settings.actuator == "ideal":
        d.comment(f"Actuator: ideal gain K_U = {act.K_U} N/V")
        d.add(f"B_force {FORCE_NODE} 0 V = {num(act.K_U)}*{uc}")
        return
    d.comment(f"Actuator ({bench.id}): {act.model}, K_U {act.K_U} N/V, tau {act.tau} s, dead zone "
              f"+/-{act.dead_zone_V} V, force limit {act.force_limit_N} N")
    if act.dead_zone_V > 0:
        d.add(f"B_deadzone a_dz 0 V = {dead_zone(uc, act.dead_zone_V)}")
    else:
        d.add(f"B_deadzone a_dz 0 V = {uc}")
    if act.model == "gain" or act.tau == 0.0:
        raw = f"{num(act.K_U)}*v(a_dz)"
    elif act.model == "lag":
        _state_integrator(d, "a_lag", f"({num(act.K_U)}*v(a_dz) - v(a_lag))/{num(act.tau)}", 0.0)
        raw = "v(a_lag)"
    else:  # lag_zero: K_U s/(tau s + 1) = (K_U/tau) (1 - 1/(tau s + 1))
        _state_integrator(d, "a_lag", f"(v(a_dz) - v(a_lag))/{num(act.tau)}", 0.0)
        raw = f"{num(act.K_U / act.tau)}*(v(a_dz) - v(a_lag))"
    d.add(f"B_force_raw a_raw 0 V = {raw}")
    force = clamp("v(a_raw)", act.force_limit_N)
    if bench.track.limit_switches:
        half, w = num(plant.d / 2), num(SMOOTHING * plant.d / 2)
        s = f"v({STATE_NODES['s']})"
        d.comment(f"Limit switches at +/- d/2 = {plant.d / 2} m cut motor power")
        force = f"({force})*0.25*(1+tanh(({half}-{s})/{w}))*(1+tanh(({half}+{s})/{w}))"
    d.add(f"B_force {FORCE_NODE} 0 V = {force}")



def _disturbances(d: _Deck, settings: SpiceSettings) -> dict[str, str]:
    """A source per push or step of the scenario (a rectangle or a step with EDGE_S edges, as the
    simulator applies them); returns the cart push, tip push and reference expressions ('' for
    none) and writes the reference node when there is a step."""
    parts: dict[str, list[str]] = {"cart": [], "tip": [], "step": []}
    for i, x in enumerate(settings.disturbances):
        node, t0 = f"dist_{i}", x.time_s
        if x.kind == "step":
            points = [(0.0, 0.0), (t0, 0.0), (t0 + EDGE_S, x.size_m)]
            parts["step"].append(f"v({node})")
        else:
            t1 = t0 + x.duration_s
            points = [(0.0, 0.0), (t0, 0.0), (t0 + EDGE_S, x.force_N), (t1, x.force_N), (t1 + EDGE_S, 0.0)]
            parts["tip" if x.at == "pendulum_tip" else "cart"].append(f"v({node})")
        points = [pt for k, pt in enumerate(points) if k == 0 or pt[0] > points[k - 1][0]]  # a push at t = 0
        d.comment(f"Disturbance {i}: {x.kind} at {t0} s")
        d.add(f"V_{node} {node} 0 PWL(" + " ".join(f"{num(t)} {num(v)}" for t, v in points) + ")")
    if parts["step"]:
        d.add(f"B_sref {S_REF_NODE} 0 V = " + "+".join(parts["step"]))
    return {k: "+".join(v) for k, v in parts.items()}


def _plant(d: _Deck, plant: PlantParams, settings: SpiceSettings, push: dict[str, str]) -> None:
    """Eq. 2.16-2.19 with theta_dot^2 in the centripetal term (as patchgen.plant.equations.nonlinear_rhs),
    with the pushes of the scenario on the cart and, at distance l, on the pendulum tip
    (generalised forces F_tip on s and F_tip l cos(theta) on theta, as the simulator's)."""
    M, m, l, g, b, c = (num(v) for v in (plant.M, plant.m, plant.l, plant.g, plant.b_VF, plant.c))
    th, sd, thd = (f"v({STATE_NODES[k]})" for k in ("theta", "s_dot", "theta_dot"))
    d.comment(f"Cart-pendulum, eq. 2.16-2.19: M {plant.M} kg, m {plant.m} kg, l {plant.l} m, "
              f"b_VF {plant.b_VF} kg/s, c {plant.c} kg m^2/s")
    cart = f" + {push['cart']}" if push["cart"] else ""
    tip_s = f" + ({push['tip']})*sin({th})*sin({th})" if push["tip"] else ""
    tip_th = f" + ({push['tip']})*cos({th})/({m}*{l})" if push["tip"] else ""
    d.add(f"B_sdd x_sdd 0 V = (-{b}*{sd} + {m}*{l}*{thd}*{thd}*sin({th}) + ({c}/{l})*{thd}*cos({th})"
          f" - {m}*{g}*sin({th})*cos({th}) + v({FORCE_NODE}){cart}{tip_s}) / (({M}+{m}) - {m}*cos({th})*cos({th}))",
          f"B_thdd x_thdd 0 V = -({c}/({m}*{l}*{l}))*{thd} + ({g}/{l})*sin({th}){tip_th} - cos({th})*v(x_sdd)/{l}")
    x0 = dict(zip(PLANT_STATES, settings.x0))
    _state_integrator(d, STATE_NODES["s"], sd, x0["s"])
    _state_integrator(d, STATE_NODES["theta"], thd, x0["theta"])
    _state_integrator(d, STATE_NODES["s_dot"], "v(x_sdd)", x0["s_dot"])
    _state_integrator(d, STATE_NODES["theta_dot"], "v(x_thdd)", x0["theta_dot"])


def output_vectors(net: Netlist) -> list[tuple[str, str]]:
    """(signal name, ngspice vector) written by ``wrdata``, in column order."""
    vecs = [(k, f"v({STATE_NODES[k]})") for k in PLANT_STATES]
    vecs += [("u_c", f"v({CONTROL_NODE})"), ("force", f"v({FORCE_NODE})")]
    vecs += [(a.id, f"v({_amp_out(a)})") for a in net.amplifiers]
    return vecs


@dataclass(frozen=True)
class SpiceDeck:
    """An ngspice deck and the files it reads (the noise table, when noise is on), by name."""

    text: str
    files: dict[str, str] = field(default_factory=dict)

    def write(self, directory: str | Path) -> Path:
        """Write the deck (patch.cir) and its files into ``directory``; return the deck's path."""
        out = Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        for name, body in self.files.items():
            (out / name).write_text(body)
        (out / DECK_NAME).write_text(self.text)
        return out / DECK_NAME

    def __str__(self) -> str:
        return self.text


def spice_deck(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
               settings: SpiceSettings) -> SpiceDeck:
    """The patched circuit and the bench as an ngspice deck, with a .control block that runs the
    transient and writes time, the plant states, u_c, the force and every amplifier output to
    patch.data. Same inputs and seed, same bytes."""
    if machine.id != net.machine:
        raise ValueError(f"netlist is for machine {net.machine!r}, profile is {machine.id!r}")
    reading = read(net, machine.imperfections.differentiator_rolloff_s)  # checks the wiring, too
    d = _Deck(np.random.default_rng(settings.seed))
    d.add(f"patchgen: {net.design} on {machine.name}, bench {bench.name}")
    d.comment("Written by patchgen (patchgen.spice.deck). Volts on the machine; plant nodes carry SI states.")
    d.comment(f"Noise {'on' if settings.noise else 'off'}, drift {'on' if settings.drift else 'off'}, "
              f"actuator {settings.actuator}")
    _sensors(d, net, bench, machine, settings)
    for amp in net.amplifiers:
        _amplifier(d, net, amp, reading.amplifiers[amp.id], machine, settings)
    d.comment(f"Control voltage u_c = output of {net.output.source}")
    d.add(f"V_uc {CONTROL_NODE} {_source_node(net, net.output.source)} DC 0")
    _actuator(d, plant, bench, settings)
    _plant(d, plant, settings, _disturbances(d, settings))

    max_step = settings.max_step_s or settings.step_s
    files: dict[str, str] = {}
    if d.noise:
        table, dt = _noise_table(d, settings.duration_s)
        files[NOISE_NAME] = table
        max_step = min(max_step, dt)  # the filesource sets no breakpoints: do not step over samples
        nodes = " ".join(name for name, _, _ in d.noise)
        ones = " ".join("1" for _ in d.noise)
        zeros = " ".join("0" for _ in d.noise)
        d.comment(f"Noise samples (seed {settings.seed}), one column per source, from {NOISE_NAME}")
        d.add(f"A_noise [{nodes}] noise_table",
              f'.model noise_table filesource (file="{NOISE_NAME}" amploffset=[{zeros}] '
              f"amplscale=[{ones}] timeoffset=0 timescale=1 timerelative=false amplstep=false)")
        d.add(*(f"R_{name} {name} 0 1e6" for name, _, _ in d.noise))
    d.add(".ic " + " ".join(f"v({node})={num(v)}" for node, v in sorted(d.ics.items())))
    d.add(f".options method=gear reltol={num(settings.reltol)} abstol=1e-12 vntol=1e-9 "
          f"chgtol=1e-16 itl4=100")
    vecs = " ".join(v for _, v in output_vectors(net))
    d.add(".control",
          "set wr_singlescale",
          "set wr_vecnames",
          "option numdgt=10",
          f"tran {num(settings.step_s)} {num(settings.duration_s)} 0 {num(max_step)}",
          f"wrdata {DATA_NAME} {vecs}",
          "quit",
          ".endc",
          ".end")
    return SpiceDeck("\n".join(d.lines) + "\n", files)
