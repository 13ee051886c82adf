"""The static check: the patch verified before it runs, as analog-computer practice does it.

Known voltages replace the sensors, the integrators sit in IC at chosen values, and every
amplifier's output is computed in advance; the technician reads each on the voltmeter, and a
mismatch points at the amplifier whose wiring or pot is wrong (patchgen.patch.fault_finding names
the likeliest fault).

The conditions:

- **IC**: every integrator in IC at its own test value (its IC jack at minus that value, from a
  spare pot of its own; with fewer spare pots than integrators, as many integrators at a time as
  pots are spare, the others' IC jacks grounded), the sensors' cords unplugged and their inputs
  grounded: each reading checks the pots and signs of the paths from the integrators.
- **one sensor at a time**: that sensor's input at a test voltage, taken from the reference
  through a spare pot (or a stated source when none is spare), the others grounded, the
  integrators in IC at 0: the pots, weights and signs of that sensor's paths.
- **as summers**: one sensor at a time at the test voltage (each that feeds such an amplifier), and
  every integrator and differentiator that
  the machine lets be patched as a summer (the GP-6's: resistor feedback in place of an integrator's
  capacitor; a differentiator's input through the input resistor in place of its capacitor and
  series resistor) patched so: each one's own input network (its pots, weights and signs, a lag's
  feedback pot included) and the pots after it show at the outputs.

What DC readings cannot see: the external parts' values (measure them before fitting them), a
differentiator's or integrator's input network on a machine that cannot patch it as a summer (a
differentiator's output is 0 for a steady input; an integrator in IC holds its value). The sheet
lists what the check leaves out.

Each reading's tolerance is what the dial resolution (each pot within half a step) and the
component tolerances (the machine's own resistor networks: INTERNAL_TOLERANCE) allow, the
independent errors added in quadrature (sqrt 3 times their root sum of squares, the worst case of
one and three standard deviations of several), plus the voltmeter's last digit.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field, replace

import numpy as np

from patchgen.patch.netlist import Netlist
from patchgen.profiles.machine import MachineProfile, the_machine

INTERNAL_TOLERANCE = 0.002  # assumed: the machine's matched input and feedback resistors, 0.2 %
METER_RESOLUTION_V = 0.001  # the reading's last digit (the GP-6's DVM; THE ANALOG THING's meter: 10 mV)
FULL_SCALE = 0.8  # the largest expected reading as a fraction of the reference
IC_TEST_V = (5.0, -3.0, 4.0, -2.0, 3.0, -4.0, 2.0, -5.0)  # integrator test values, distinct so signs show
SUMMER_ROLES = ("summer", "inverter", "lag")  # a lag is a summer at DC


@dataclass(frozen=True)
class Condition:
    """One set of test conditions: sensor input voltages, integrator values in IC, the amplifiers
    patched as summers for the check, and how the technician sets them up."""

    name: str
    sensors_V: dict[str, float]
    ic_V: dict[str, float]
    as_summers: tuple[str, ...]
    setup: str
    source: str = ""  # where the test voltage comes from (a spare pot's setting, or a bench supply)


@dataclass(frozen=True)
class StaticReading:
    """One reading: where, under which condition, the value expected, its tolerance and what it
    depends on (pots and amplifier inputs whose error moves it past the tolerance)."""

    condition: str
    point: str
    expected_V: float
    tolerance_V: float
    isolates: tuple[str, ...]


@dataclass(frozen=True)
class StaticCheck:
    """The conditions, every reading and what the check cannot see."""

    conditions: tuple[Condition, ...]
    readings: tuple[StaticReading, ...]
    unchecked: tuple[str, ...] = field(default=())


@dataclass(frozen=True)
class Wire:
    """One amplifier input as the static solver takes it: into which amplifier, from where, its
    gain (weight x pot setting) and the pot and jack that make it."""

    amplifier: str
    source: str
    gain: float
    pot: str | None
    jack: str
    weight: int


def wires_of(net: Netlist) -> list[Wire]:
    """Every amplifier input of the netlist, in order."""
    pots = {p.id: p for p in net.pots}
    return [Wire(a.id, i.source, i.weight * (pots[i.pot].setting if i.pot else 1.0), i.pot, i.jack, i.weight)
            for a in net.amplifiers for i in a.inputs]


def solve(net: Netlist, wires: list[Wire], cond: Condition, rail: float | None = None) -> dict[str, float]:
    """Every amplifier output (V) under a condition, from the given wiring (which may be a faulty
    one: patchgen.patch.fault_finding varies it). Summers, inverters, lags and whatever the
    condition patches as a summer: -sum g v; differentiators: 0 (a steady input); integrators: their
    IC value. With ``rail``, outputs are held at +/- rail (a faulty wiring may drive an amplifier
    there, or close a loop with no solution: then the least-squares one, clipped)."""
    amps = [a.id for a in net.amplifiers]
    roles = {a.id: a.role for a in net.amplifiers}
    idx = {a: k for k, a in enumerate(amps)}
    n = len(amps)
    M = np.eye(n)
    rhs = np.zeros(n)
    for a in amps:
        r = roles[a]
        if r in ("differentiator", "integrator") and a not in cond.as_summers:
            rhs[idx[a]] = cond.ic_V.get(a, 0.0) if r == "integrator" else 0.0
            continue
        for w in wires:
            if w.amplifier != a:
                continue
            if w.source in idx:
                M[idx[a], idx[w.source]] += w.gain
            else:
                rhs[idx[a]] -= w.gain * cond.sensors_V.get(w.source, 0.0)
    try:
        x = np.linalg.solve(M, rhs)
    except np.linalg.LinAlgError:
        if rail is None:
            raise
        x = np.linalg.lstsq(M, rhs, rcond=None)[0]
    if rail is not None:
        x = np.clip(x, -rail, rail)
    return {a: float(x[idx[a]]) for a in amps}


def static_check(net: Netlist, machine: MachineProfile) -> StaticCheck:
    """The static check of a patch: conditions chosen so that every pot, weight and sign is
    exercised and every reading stays inside FULL_SCALE of the reference.

    Parameters
    ----------
    net : Netlist
        The patch.
    machine : MachineProfile
        Its reference, pot resolution and count (a spare pot makes the test voltages), and whether
        its integrating amplifiers can be patched as summers.

    Returns
    -------
    StaticCheck
        The conditions, one reading per amplifier output (and u_c) per condition, and what DC
        readings cannot see.
    """
    wires = wires_of(net)
    ints = [a.id for a in net.amplifiers if a.role == "integrator"]
    sensors = [s.id for s in net.sensors if any(w.source == s.id for w in wires)]
    spares = spare_pots(net, machine)
    spare = spares[0] if spares else None
    dynamic = [a.id for a in net.amplifiers if a.role in ("integrator", "differentiator")]
    switchable = tuple(a for a in dynamic if "summer" in _slot_roles(machine, net, a))
    conds: list[Condition] = []
    test_ic = {a: IC_TEST_V[k % len(IC_TEST_V)] for k, a in enumerate(ints)}
    ic_input = machine.procedure.ic_input
    groups = [ints[k:k + len(spares)] for k in range(0, len(ints), len(spares))] if spares else [ints]
    for group in groups if ints else []:
        # each integrator's IC jack from a spare pot of its own: as many at a time as pots are spare
        name = "IC" if len(groups) == 1 else "IC " + " ".join(group)
        rest = f"; the other integrators' {ic_input}s grounded" if len(groups) > 1 else ""
        conds.append(_ic_sourced(_scaled(net, wires, machine, Condition(
            name, {}, {a: test_ic[a] for a in group}, (),
            f"IC mode; sensor cords unplugged, inputs grounded{rest}"), spare), spares, machine.reference_V, ic_input))
    for s in sensors:
        conds.append(_scaled(net, wires, machine, Condition(
            f"{s} only", {s: 1.0}, {}, (), f"IC mode, integrators at 0; other sensor inputs grounded; {s} input at"),
            spare))
    if switchable:
        # one sensor at a time into the amplifiers patched as summers, so that a cord from the wrong
        # sensor shows (every sensor at one voltage would read alike)
        direct = [s for s in sensors if any(w.source == s and w.amplifier in switchable for w in wires)]
        patched = (f"{', '.join(switchable)} patched as summers (feedback resistor for an integrator's capacitor, "
                   "input resistor for a differentiator's C and R)")
        for group in ([[s] for s in direct] or [sensors]):
            name = "as summers" + ("" if len(group) > 1 or not direct else f", {group[0]}")
            conds.append(_scaled(net, wires, machine, Condition(
                name, {s: 1.0 for s in group}, {}, switchable,
                f"{patched}; the other sensor inputs grounded; {', '.join(group)} input at"), spare))
    readings = []
    for c in conds:
        base, perturbed = solve(net, wires, c), _perturbed(net, wires, machine, c)
        for point in [a.id for a in net.amplifiers] + ["u_c"]:
            readings.append(_reading(net, wires, c, point, base, perturbed))
    unchecked = [f"{a}: its input network ({the_machine(machine.name)} cannot patch it as a summer)"
                 for a in dynamic if a not in switchable]
    if net.parts:
        unchecked.append(f"the external parts' values ({', '.join(p.id for p in net.parts)}): measure each before "
                         "fitting it")
    return StaticCheck(tuple(conds), tuple(readings), tuple(unchecked))


def _slot_roles(machine: MachineProfile, net: Netlist, amp_id: str) -> tuple[str, ...]:
    """The roles the machine's amplifier slot allows."""
    slots = (machine.slaved(net.units) if net.units > 1 else machine).amplifiers
    return tuple(next((a.roles for a in slots if a.id == amp_id), ()))


def spare_pots(net: Netlist, machine: MachineProfile) -> list[str]:
    """The pots the patch leaves free (P1 ... on one unit, U1.P1 ... on slaved units), in order."""
    used = {p.id for p in net.pots}
    if net.units == 1:
        names = [f"P{k}" for k in range(1, machine.pot_count + 1)]
    else:
        names = [f"U{u}.P{k}" for u in range(1, net.units + 1) for k in range(1, machine.pot_count + 1)]
    return [p for p in names if p not in used]


def test_voltage_source(volts: float, pot: str | None, reference_V: float) -> str:
    """Where a test voltage comes from: a spare pot's setting from the reference of its sign
    ("spare pot P8 at 0.220 from -10 V"), or a bench supply when no pot is spare."""
    if pot is None:
        return "a bench supply (no pot is spare)"
    sign = "+" if volts >= 0 else "−"
    return f"spare pot {pot} at {abs(volts) / reference_V:.3f} from {sign}{reference_V:g} V"


def _volts(v: float) -> str:
    """A signed voltage as the sheet writes it: +2.2 V, −2.2 V."""
    return f"{'+' if v >= 0 else '−'}{abs(v):g} V"


def _ic_sourced(cond: Condition, spares: list[str], reference_V: float, ic_input: str) -> Condition:
    """An IC condition with where each integrator's IC-input voltage comes from (minus its value:
    in IC an integrator's output is minus its IC input), a spare pot each, in the setup; the
    input named as the machine names it (``ic_input``: the GP-6's IC jack)."""
    said = []
    for k, (a, v) in enumerate(cond.ic_V.items()):
        jack = -v if v else 0.0
        pot = spares[k] if spares else None
        said.append(f"{a}'s {ic_input} grounded" if jack == 0 else
                    f"{a}'s {ic_input} at {_volts(jack)} ({test_voltage_source(jack, pot, reference_V)})")
    source = "; ".join(said)
    return replace(cond, setup=f"{cond.setup}; {source}", source=source)


def _scaled(net: Netlist, wires: list[Wire], machine: MachineProfile, cond: Condition, spare: str | None) -> Condition:
    """The condition with its sensor voltages (or its integrators' ICs) scaled so that the largest
    reading is FULL_SCALE of the reference (at most the reference itself), each a dial setting of
    a spare pot, and the source of the test voltage named."""
    ref = machine.reference_V
    if cond.sensors_V:
        peak = max(abs(v) for v in solve(net, wires, cond).values())
        level = min(1.0, FULL_SCALE / peak) if peak > 0 else 0.1
        setting = max(machine.pot_resolution, math.floor(level / machine.pot_resolution) * machine.pot_resolution)
        volts = setting * ref
        sensors = {s: round(v * volts, 9) for s, v in cond.sensors_V.items()}
        source = test_voltage_source(volts, spare, ref)
        return Condition(cond.name, sensors, cond.ic_V, cond.as_summers, f"{cond.setup} {volts:g} V ({source})",
                         source)
    peak = max(abs(v) for v in solve(net, wires, cond).values())
    k = FULL_SCALE * ref / peak if peak > 0 else 1.0
    step = machine.pot_resolution * ref  # a spare pot's step from the reference: each IC a setting of it
    ic = {a: round(math.floor(abs(v * k) / step + 1e-9) * step, 9) * math.copysign(1.0, v)
          for a, v in cond.ic_V.items()}
    return Condition(cond.name, {}, ic, (), cond.setup)


def _perturbed(net: Netlist, wires: list[Wire], machine: MachineProfile, cond: Condition) -> tuple[list, list]:
    """Every amplifier's output under a condition with each input in turn off by its worst error,
    and with each input's sign flipped (None where the flip closes a loop of gain exactly 1: no
    steady output at all): solved once per condition, read by each of its readings."""
    res = machine.pot_resolution
    moved, flipped = [], []
    for k, w in enumerate(wires):
        err = (w.weight * res / 2 if w.pot else 0.0) + INTERNAL_TOLERANCE * abs(w.gain)
        moved.append(solve(net, wires[:k] + [Wire(w.amplifier, w.source, w.gain + err, w.pot, w.jack, w.weight)]
                           + wires[k + 1:], cond))
        try:
            flipped.append(solve(net, wires[:k] + [Wire(w.amplifier, w.source, -w.gain, w.pot, w.jack, w.weight)]
                                 + wires[k + 1:], cond))
        except np.linalg.LinAlgError:
            flipped.append(None)
    return moved, flipped


def _reading(net: Netlist, wires: list[Wire], cond: Condition, point: str, base: dict[str, float],
             perturbed: tuple[list, list]) -> StaticReading:
    """One reading with its tolerance (each input's worst error, summed) and what it isolates."""
    amp = net.output.source if point == "u_c" else point
    expect = base[amp]
    moved, flipped = perturbed
    squares = (INTERNAL_TOLERANCE * expect) ** 2
    for m in moved:  # in wire order, as a sum that gives the same bytes every time
        squares += (m[amp] - expect) ** 2
    # independent errors add in quadrature (three times the root sum of squares covers their sum's
    # spread when each is a uniform error of that half-width: its standard deviation is 1/sqrt(3))
    tol = METER_RESOLUTION_V + math.sqrt(3.0 * squares)
    isolates = []
    for w, f in zip(wires, flipped):  # an input whose sign flipped would move this reading past its tolerance
        reading = math.inf if f is None else f[amp]
        if abs(reading - expect) > tol:
            isolates.append(w.pot or f"{w.amplifier} {w.jack}")
    return StaticReading(cond.name, point, expect, tol, tuple(dict.fromkeys(isolates)))


CSV_COLUMNS = ("condition", "point", "expected_V", "tolerance_V", "isolates", "measured_V")


def static_check_csv(check: StaticCheck) -> str:
    """The check as CSV, one row per reading, with an empty measured_V column for the technician."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for r in check.readings:
        writer.writerow([r.condition, r.point, f"{r.expected_V:.4f}", f"{r.tolerance_V:.4f}", " ".join(r.isolates), ""])
    return out.getvalue()
