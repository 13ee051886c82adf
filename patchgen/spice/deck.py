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
import re
import shutil
import subprocess
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Protocol

import numpy as np

from patchgen.patch.netlist import Amplifier, Netlist, Pot
from patchgen.plant.equations import PLANT_STATES, PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

DECK_NAME = "patch.cir"
DATA_NAME = "patch.data"
NOISE_NAME = "patch.noise"
INSTALL_HINT = ("install ngspice (Debian/Ubuntu: apt-get install ngspice) and make sure `ngspice` "
                "is on the PATH")

# Plant state nodes, in PLANT_STATES order; their voltages are the states in SI units.
STATE_NODES = {"s": "x_s", "theta": "x_theta", "s_dot": "x_sdot", "theta_dot": "x_thetadot"}
FORCE_NODE = "f_cart"
CONTROL_NODE = "u_c"
# The actuator's dead zone, force limit and the track's limit switches are written with max/abs
# and their corners rounded (softplus) over this fraction of their size, so Newton's iteration sees
# continuous derivatives. (ngspice 39's B-source limit() silently evaluates to 0: not used.) With
# the feedback-bound amplifiers hard corners also run; the rounding is a cheap precaution.
SMOOTHING = 0.01
# Amplifier saturation: a feedback bound of this many times the feedback conductance, with its
# corner rounded over this fraction of the saturation voltage.
BOUND_STIFFNESS = 1.0e3
BOUND_SMOOTHING = 1.0e-3


class NgspiceMissing(RuntimeError):
    """ngspice is not on the PATH: the deck can be written but not run."""

    exit_status = 3

    def __init__(self) -> None:
        super().__init__(f"ngspice not found on the PATH: {INSTALL_HINT}")


class NgspiceError(RuntimeError):
    """ngspice ran but failed (non-zero exit, an error in its output, or no data written)."""

    exit_status = 4


@dataclass(frozen=True)
class SpiceSettings:
    """What a scenario asks of the circuit run: duration, output step, initial plant state, switches.

    ``x0`` is [s, theta, s_dot, theta_dot] in SI units. ``actuator`` "bench" uses the bench
    profile's actuator (lag, dead zone, force limit, limit switches); "ideal" is F = K_U u_c.
    ``max_step_s`` bounds ngspice's time step (default: the output step).
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


@dataclass
class SpiceResult:
    """Time histories from ngspice: ``t`` (s) and ``signals`` by name.

    Names: the plant states (``s``, ``theta``, ``s_dot``, ``theta_dot``; SI units), ``u_c`` (V),
    ``force`` (N) and every amplifier id (its output, V).
    """

    t: np.ndarray
    signals: dict[str, np.ndarray]
    run_time_s: float = 0.0
    log: str = ""


class Trajectory(Protocol):
    """Anything with a time vector and named signals (SpiceResult, patchgen's simulation result)."""

    t: np.ndarray
    signals: Mapping[str, np.ndarray]


# ----------------------------------------------------------------------------------------------
# Pots


def pot_wiper_position(setting: float, pot_ohm: float, load_ohm: float) -> float:
    """Wiper position a (0..1) whose LOADED ratio equals ``setting``.

    Pots are set in POT SET mode with the load connected, so the dial setting k is the ratio
    v_wiper/v_top with the load R_L (the amplifier's input resistor, to a virtual ground) across
    the lower part a*R_p. Solving k = (a R_p || R_L) / ((1 - a) R_p + a R_p || R_L) for a gives
    k R_p a^2 + (R_L - k R_p) a - k R_L = 0; the root is written in its cancellation-free form.
    """
    if not 0.0 <= setting <= 1.0:
        raise ValueError(f"pot setting {setting} outside 0..1")
    if setting == 0.0:
        return 0.0
    k, rp, rl = setting, pot_ohm, load_ohm
    b = rl - k * rp
    disc = math.sqrt(b * b + 4.0 * k * k * rp * rl)
    a = 2.0 * k * rl / (b + disc) if b >= 0 else (disc - b) / (2.0 * k * rp)
    return min(max(a, 0.0), 1.0)


def loaded_ratio(position: float, pot_ohm: float, load_ohm: float) -> float:
    """v_wiper/v_top of a pot at wiper position a with a load R_L on the wiper (to ground)."""
    lower = position * pot_ohm
    if lower == 0.0:
        return 0.0
    par = lower * load_ohm / (lower + load_ohm)
    return par / ((1.0 - position) * pot_ohm + par)


# ----------------------------------------------------------------------------------------------
# Deck


def _node(name: str) -> str:
    """A SPICE-safe lower-case node or element suffix."""
    return re.sub(r"[^a-z0-9_]", "_", name.lower())


def _num(x: float) -> str:
    """Full-precision number text for the deck (deterministic)."""
    return repr(float(x))


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


def _input_resistor(machine: MachineProfile, weight: int) -> float:
    c = machine.components
    return {1: c.input_resistor_x1_ohm, 10: c.input_resistor_x10_ohm}[weight]


def _source_node(net: Netlist, source: str) -> str:
    if any(s.id == source for s in net.sensors):
        return f"sens_{_node(source)}"
    return _amp_out(net.amp(source))


def _amp_out(amp: Amplifier) -> str:
    return f"{_node(amp.id)}_out"


def _sensor_constant(bench: BenchProfile, sensor_id: str) -> float:
    return float(getattr(bench.sensors, sensor_id))


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
    for s in net.sensors:
        if s.id not in STATE_NODES:
            raise ValueError(f"sensor {s.id!r} is not a plant state")
        k = _sensor_constant(bench, s.id)
        node = f"sens_{_node(s.id)}"
        rms = bench.sensors.noise_V_rms.get(s.id, 0.0) if settings.noise else 0.0
        clean = f"{node}_clean" if rms > 0 else node
        volts = _clamp(f"{_num(k)}*v({STATE_NODES[s.id]})", machine.reference_V)
        d.add(f"B_sens_{_node(s.id)} {clean} 0 V = {volts}")
        if rms > 0:
            _noise_source(d, f"E_sens_{_node(s.id)}_noise", node, clean, rms,
                          bench.sensors.noise_bandwidth_Hz, settings.duration_s)


def _pot(d: _Deck, net: Netlist, machine: MachineProfile, pot: Pot, load_ohm: float | None) -> str:
    """A pot as two resistors; returns its wiper node. ``load_ohm`` None: no resistive load."""
    rp = machine.components.pot_resistance_ohm
    a = (pot_wiper_position(pot.setting, rp, load_ohm) if load_ohm is not None
         else min(max(pot.setting, 0.0), 1.0))
    top, wiper = _source_node(net, pot.source), f"pot_{_node(pot.id)}_w"
    # A wiper at an end would make a zero resistor: keep a milliohm so the matrix stays regular.
    r_upper, r_lower = max((1.0 - a) * rp, 1e-3), max(a * rp, 1e-3)
    load_txt = f"load {_num(load_ohm)} ohm" if load_ohm is not None else "no resistive load"
    d.comment(f"{pot.id}: setting {pot.setting} (loaded), wiper at {a:.6f} of {_num(rp)} ohm, {load_txt}")
    d.add(f"R_{_node(pot.id)}_up {top} {wiper} {_num(r_upper)}",
          f"R_{_node(pot.id)}_lo {wiper} 0 {_num(r_lower)}")
    return wiper


def _amplifier(d: _Deck, net: Netlist, amp: Amplifier, machine: MachineProfile,
               settings: SpiceSettings) -> None:
    c, imp = machine.components, machine.imperfections
    n = _node(amp.id)
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
    d.add(f"E_{n} {core} 0 {plus} {sj} {_num(gain)}",
          f"R_{n}_o {core} {fb} {_num(max(c.opamp_output_resistance_ohm, 1e-3))}",
          f"B_{n}_bound {fb} {sj} I = {_bound(f'v({fb})', vsat, c.feedback_resistor_ohm)}")
    if rms > 0:
        _noise_source(d, f"E_{n}_noise", out, fb, rms, imp.noise_bandwidth_Hz, settings.duration_s)
    if drift:
        d.add(f"V_{n}_offset {plus} 0 DC {_num(imp.integrator_offset_V)}",
              f"I_{n}_bias {sj} 0 DC {_num(imp.integrator_bias_A)}")

    pots = {p.id: p for p in net.pots}
    if amp.role == "differentiator":
        T_d = amp.T_d_s if amp.T_d_s is not None else c.feedback_resistor_ohm * c.differentiator_capacitor_F
        roll = amp.rolloff_s if amp.rolloff_s is not None else imp.differentiator_rolloff_s
        for inp in amp.inputs:
            src = (_pot(d, net, machine, pots[inp.pot], None) if inp.pot else _source_node(net, inp.source))
            cap = inp.weight * T_d / c.feedback_resistor_ohm
            mid = f"{n}_{_node(inp.jack)}_m"
            d.comment(f"{inp.jack}: input capacitor {_num(cap)} F (x{inp.weight}, T_d {T_d} s; profile C "
                      f"{_num(c.differentiator_capacitor_F)} F) and series resistor for a {roll} s roll-off")
            d.add(f"C_{n}_{_node(inp.jack)} {src} {mid} {_num(cap)}",
                  f"R_{n}_{_node(inp.jack)}_s {mid} {sj} {_num(roll / cap)}")
        d.add(f"R_{n}_f {sj} {fb} {_num(c.feedback_resistor_ohm)}")
        return

    for inp in amp.inputs:
        r_in = _input_resistor(machine, inp.weight)
        src = (_pot(d, net, machine, pots[inp.pot], r_in) if inp.pot else _source_node(net, inp.source))
        d.add(f"R_{n}_{_node(inp.jack)} {src} {sj} {_num(r_in)}")
    if amp.role in ("summer", "inverter"):
        d.add(f"R_{n}_f {sj} {fb} {_num(c.feedback_resistor_ohm)}")
    elif amp.role == "integrator":
        d.add(f"C_{n}_f {sj} {fb} {_num(c.integrator_capacitor_F)}")
        _capacitor_ic(d, sj, fb, amp, imp.integrator_offset_V if drift else 0.0)
    elif amp.role == "lag":
        tau = amp.tau_s if amp.tau_s is not None else machine.time_scale_s
        d.add(f"R_{n}_f {sj} {fb} {_num(c.feedback_resistor_ohm)}",
              f"C_{n}_f {sj} {fb} {_num(tau / c.feedback_resistor_ohm)}")
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
        d.add(f"B_force {FORCE_NODE} 0 V = {_num(act.K_U)}*{uc}")
        return
    d.comment(f"Actuator ({bench.id}): {act.model}, K_U {act.K_U} N/V, tau {act.tau} s, dead zone "
              f"+/-{act.dead_zone_V} V, force limit {act.force_limit_N} N")
    if act.dead_zone_V > 0:
        d.add(f"B_deadzone a_dz 0 V = {_dead_zone(uc, act.dead_zone_V)}")
    else:
        d.add(f"B_deadzone a_dz 0 V = {uc}")
    if act.model == "gain" or act.tau == 0.0:
        raw = f"{_num(act.K_U)}*v(a_dz)"
    elif act.model == "lag":
        _state_integrator(d, "a_lag", f"({_num(act.K_U)}*v(a_dz) - v(a_lag))/{_num(act.tau)}", 0.0)
        raw = "v(a_lag)"
    else:  # lag_zero: K_U s/(tau s + 1) = (K_U/tau) (1 - 1/(tau s + 1))
        _state_integrator(d, "a_lag", f"(v(a_dz) - v(a_lag))/{_num(act.tau)}", 0.0)
        raw = f"{_num(act.K_U / act.tau)}*(v(a_dz) - v(a_lag))"
    d.add(f"B_force_raw a_raw 0 V = {raw}")
    force = _clamp("v(a_raw)", act.force_limit_N)
    if bench.track.limit_switches:
        half, w = _num(plant.d / 2), _num(SMOOTHING * plant.d / 2)
        s = f"v({STATE_NODES['s']})"
        d.comment(f"Limit switches at +/- d/2 = {plant.d / 2} m cut motor power")
        force = f"({force})*0.25*(1+tanh(({half}-{s})/{w}))*(1+tanh(({half}+{s})/{w}))"
    d.add(f"B_force {FORCE_NODE} 0 V = {force}")


def _bound(out: str, vsat: float, r_feedback: float) -> str:
    """Current of a feedback limiter from the output into the summing junction: zero inside
    +/-vsat, a conductance BOUND_STIFFNESS times the feedback resistor's beyond it (corners rounded
    over BOUND_SMOOTHING of vsat). The amplifier stays in its linear region and the summing
    junction at virtual ground, so a saturated amplifier neither winds up nor stalls ngspice's
    Newton iteration (an output clipped inside the op-amp, e.g. by tanh, does both)."""
    w, v, g = BOUND_SMOOTHING * vsat, _num(vsat), _num(BOUND_STIFFNESS / r_feedback)
    return f"{g}*({_softplus(f'({out}-{v})', w)}-{_softplus(f'(-({out})-{v})', w)})"


def _softplus(x: str, width: float) -> str:
    """A smooth max(x, 0): max(x, 0) + w ln(1 + exp(-|x|/w)), exact beyond a few widths."""
    w = _num(width)
    return f"(max({x},0)+{w}*ln(1+exp(-abs({x})/{w})))"


def _dead_zone(x: str, half_width: float) -> str:
    """Smoothed dead zone: 0 inside +/-half_width, x -/+ half_width outside."""
    w, dz = SMOOTHING * half_width, _num(half_width)
    return f"{_softplus(f'({x}-{dz})', w)}-{_softplus(f'(-({x})-{dz})', w)}"


def _clamp(x: str, limit: float) -> str:
    """Smoothed limit to +/-limit."""
    w, lim = SMOOTHING * limit, _num(limit)
    return f"{x}-{_softplus(f'({x}-{lim})', w)}+{_softplus(f'(-({x})-{lim})', w)}"


def _plant(d: _Deck, plant: PlantParams, settings: SpiceSettings) -> None:
    """Eq. 2.16-2.19 with theta_dot^2 in the centripetal term (as patchgen.plant.equations.nonlinear_rhs)."""
    M, m, l, g, b, c = (_num(v) for v in (plant.M, plant.m, plant.l, plant.g, plant.b_VF, plant.c))
    th, sd, thd = (f"v({STATE_NODES[k]})" for k in ("theta", "s_dot", "theta_dot"))
    d.comment(f"Cart-pendulum, eq. 2.16-2.19: M {plant.M} kg, m {plant.m} kg, l {plant.l} m, "
              f"b_VF {plant.b_VF} kg/s, c {plant.c} kg m^2/s")
    d.add(f"B_sdd x_sdd 0 V = (-{b}*{sd} + {m}*{l}*{thd}*{thd}*sin({th}) + ({c}/{l})*{thd}*cos({th})"
          f" - {m}*{g}*sin({th})*cos({th}) + v({FORCE_NODE})) / (({M}+{m}) - {m}*cos({th})*cos({th}))",
          f"B_thdd x_thdd 0 V = -({c}/({m}*{l}*{l}))*{thd} + ({g}/{l})*sin({th}) - cos({th})*v(x_sdd)/{l}")
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
    d = _Deck(np.random.default_rng(settings.seed))
    d.add(f"patchgen: {net.design} on {machine.name}, bench {bench.name}")
    d.comment("Written by patchgen (patchgen.spice.deck). Volts on the machine; plant nodes carry SI states.")
    d.comment(f"Noise {'on' if settings.noise else 'off'}, drift {'on' if settings.drift else 'off'}, "
              f"actuator {settings.actuator}")
    _sensors(d, net, bench, machine, settings)
    for amp in net.amplifiers:
        _amplifier(d, net, amp, machine, settings)
    d.comment(f"Control voltage u_c = output of {net.output.source}")
    d.add(f"V_uc {CONTROL_NODE} {_source_node(net, net.output.source)} DC 0")
    _actuator(d, plant, bench, settings)
    _plant(d, plant, settings)

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
    d.add(".ic " + " ".join(f"v({node})={_num(v)}" for node, v in sorted(d.ics.items())))
    d.add(f".options method=gear reltol={_num(settings.reltol)} abstol=1e-12 vntol=1e-9 "
          f"chgtol=1e-16 itl4=100")
    vecs = " ".join(v for _, v in output_vectors(net))
    d.add(".control",
          "set wr_singlescale",
          "set wr_vecnames",
          "option numdgt=10",
          f"tran {_num(settings.step_s)} {_num(settings.duration_s)} 0 {_num(max_step)}",
          f"wrdata {DATA_NAME} {vecs}",
          "quit",
          ".endc",
          ".end")
    return SpiceDeck("\n".join(d.lines) + "\n", files)


# ----------------------------------------------------------------------------------------------
# Run


def ngspice_path() -> str:
    """Path of the ngspice executable; NgspiceMissing if it is not on the PATH."""
    path = shutil.which("ngspice")
    if path is None:
        raise NgspiceMissing()
    return path


def run_ngspice(deck: SpiceDeck | str, workdir: str | Path, timeout_s: float = 600.0) -> SpiceResult:
    """Write ``deck`` into workdir (patch.cir and its files), run ``ngspice -b`` there and read its
    wrdata table.

    The deck must write ``patch.data`` (as spice_deck's does). Raises NgspiceMissing without
    ngspice, NgspiceError if ngspice fails or reports an error.
    """
    exe = ngspice_path()
    work = Path(workdir)
    (deck if isinstance(deck, SpiceDeck) else SpiceDeck(deck)).write(work)
    data = work / DATA_NAME
    data.unlink(missing_ok=True)
    start = time.perf_counter()
    try:
        proc = subprocess.run([exe, "-b", DECK_NAME], cwd=work, capture_output=True, text=True,
                              timeout=timeout_s)
    except subprocess.TimeoutExpired:
        raise NgspiceError(f"ngspice did not finish within {timeout_s} s ({work / DECK_NAME})") from None
    elapsed = time.perf_counter() - start
    log = proc.stdout + proc.stderr
    (work / "ngspice.log").write_text(log)
    problems = [ln.strip() for ln in log.splitlines()
                if re.search(r"\berror\b|aborted|timestep too small|singular matrix|no convergence",
                             ln, re.IGNORECASE)]
    if proc.returncode != 0 or problems or not data.exists():
        first = problems[0] if problems else (log.strip().splitlines() or ["no output"])[-1]
        raise NgspiceError(f"ngspice failed on {work / DECK_NAME} (exit {proc.returncode}): {first}; "
                           f"full log in {work / 'ngspice.log'}")
    result = read_wrdata(data)
    result.run_time_s = elapsed
    result.log = log
    return result


def read_wrdata(path: str | Path, names: Sequence[tuple[str, str]] | None = None) -> SpiceResult:
    """Parse a wrdata table written with wr_singlescale and wr_vecnames.

    Columns are mapped back to signal names: v(x_s) -> s, v(u_c) -> u_c, v(a6_out) -> A6 (upper
    case amplifier ids as ngspice lower-cases node names; pass ``names`` to map exactly).
    """
    lines = Path(path).read_text().splitlines()
    header = lines[0].split()
    table = np.loadtxt(lines[1:], ndmin=2)
    if table.shape[1] != len(header):
        raise NgspiceError(f"{path}: {table.shape[1]} columns for {len(header)} names")
    by_vec = {(v.lower()): k for k, v in names} if names else {}
    state_of = {f"v({node})": k for k, node in STATE_NODES.items()}
    signals: dict[str, np.ndarray] = {}
    for i, col in enumerate(header[1:], start=1):
        key = col.lower()
        if key in by_vec:
            name = by_vec[key]
        elif key in state_of:
            name = state_of[key]
        elif key == f"v({CONTROL_NODE})":
            name = "u_c"
        elif key == f"v({FORCE_NODE})":
            name = "force"
        elif key.startswith("v(") and key.endswith("_out)"):
            name = key[2:-5].upper()
        else:
            name = key
        signals[name] = table[:, i]
    return SpiceResult(t=table[:, 0], signals=signals)


# ----------------------------------------------------------------------------------------------
# Compare


@dataclass(frozen=True)
class SignalAgreement:
    """Difference of one signal between two runs, relative to its peak in the reference run."""

    name: str
    peak: float
    rms_diff: float
    max_diff: float

    @property
    def rms_rel(self) -> float:
        return self.rms_diff / self.peak if self.peak > 0 else 0.0

    @property
    def max_rel(self) -> float:
        return self.max_diff / self.peak if self.peak > 0 else 0.0


@dataclass(frozen=True)
class Comparison:
    """ngspice against patchgen's own simulation on a common time grid."""

    t: np.ndarray
    spice: dict[str, np.ndarray]
    own: dict[str, np.ndarray]
    signals: dict[str, SignalAgreement]

    def agrees(self, tolerance: float = 0.01) -> bool:
        """True when every compared signal's peak difference is within ``tolerance`` of its peak."""
        return all(a.max_rel <= tolerance for a in self.signals.values())

    def lines(self) -> list[str]:
        return [f"{a.name}: peak {a.peak:.4g}, RMS difference {100 * a.rms_rel:.3f} % of peak, "
                f"largest difference {100 * a.max_rel:.3f} % of peak" for a in self.signals.values()]


def compare(spice_result: Trajectory, own_result: Trajectory, names: Sequence[str] = ("theta", "s"),
            n_points: int = 2001) -> Comparison:
    """Interpolate both runs on a common grid over their shared time span and measure the RMS and
    largest difference of each named signal, relative to its peak magnitude in ``own_result``."""
    t0 = max(spice_result.t[0], own_result.t[0])
    t1 = min(spice_result.t[-1], own_result.t[-1])
    t = np.linspace(t0, t1, n_points)
    spice, own, out = {}, {}, {}
    for name in names:
        a = np.interp(t, spice_result.t, spice_result.signals[name])
        b = np.interp(t, own_result.t, own_result.signals[name])
        diff = a - b
        spice[name], own[name] = a, b
        out[name] = SignalAgreement(name, float(np.max(np.abs(b))), float(np.sqrt(np.mean(diff ** 2))),
                                    float(np.max(np.abs(diff))))
    return Comparison(t, spice, own, out)


_UNITS = {"theta": ("deg", 180.0 / math.pi), "s": ("m", 1.0), "s_dot": ("m/s", 1.0),
          "theta_dot": ("deg/s", 180.0 / math.pi), "u_c": ("V", 1.0)}


def plot_comparison(cmp: Comparison, stem: str | Path, title: str = "",
                    own_label: str = "patchgen", svg: bool = False) -> list[Path]:
    """Overlay plot of each compared signal (ngspice dashed over patchgen's), as PNG (and SVG with
    ``svg``). The SVG is byte-for-byte deterministic (fixed hash salt, no date)."""
    from patchgen.render import plotting

    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    names = list(cmp.signals)
    height = 2.4 * len(names)
    fig, axes = plotting.stacked(7.0, height, len(names), top_in=0.6 if title else 0.35, left_in=0.85,
                                 hspace=0.35 * 2.4 / 1.9)
    cols = plotting.columns(fig, dpi=120)
    for ax, name in zip(axes, names):
        unit, scale = _UNITS.get(name, ("", 1.0))
        a = cmp.signals[name]
        ax.plot(*plotting.envelope(cmp.t, cmp.own[name] * scale, cols), color="tab:blue", lw=1.6, label=own_label)
        ax.plot(*plotting.envelope(cmp.t, cmp.spice[name] * scale, cols), color="tab:orange", lw=1.2, ls="--",
                label="ngspice")
        ax.set_ylabel(f"{name} ({unit})" if unit else name)
        ax.set_title(f"{name}: RMS diff {100 * a.rms_rel:.3f} %, max diff {100 * a.max_rel:.3f} % "
                     f"of peak", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time (s)")
    if title:
        fig.suptitle(title, fontsize=10)
    return plotting.save(fig, stem.with_suffix(".png"), stem.with_suffix(".svg") if svg else None, dpi=120)
