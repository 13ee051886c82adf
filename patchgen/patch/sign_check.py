"""The sign check: every pot's sign seen on the machine's meter before the loop is closed, one pot's
path at a time, moving only what a person can move.

A step sets the pot it checks and the pots of one path through it at their settings (every other
pot at 0), moves one input and says which way the reading must go. What is moved:

- a position sensor by hand (the cart along the track or the arm about its axis, the pendulum
  about upright: the plant's position and angle),
  which checks the sensor's own polarity too;
- any other sensor's input (a rate), its cord unplugged, at a test voltage from a spare pot;
- an integrator's output, through its IC jack at a test voltage from a spare pot (in IC an
  integrator's output is minus its IC jack), for a pot fed from a state no hand can move.

The reading is u_c when the pot's amplifier reaches the output through summers alone (their pots
set too) and the pot's path shows there, else that amplifier itself; an integrator's is read in
OP, as the direction it ramps, and at once back to IC. A path through a differentiator shows while
the hand moves. Each step is chosen so that the pot with its sign flipped would move the reading
the other way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from patchgen.patch.netlist import Netlist
from patchgen.patch.static_check import FULL_SCALE, Condition, Wire, solve, spare_pots, test_voltage_source, wires_of
from patchgen.plant.plant_model import CART, PlantModel
from patchgen.profiles.machine import MachineProfile

SUMMING = ("summer", "inverter", "lag")  # a steady output for a steady input (a lag once settled)
TARGET_V = 2.0  # a test voltage is chosen so that the reading is about this
MAX_DEPTH = 8  # the longest path searched back from a pot to what moves it


@dataclass(frozen=True)
class Drive:
    """What a step moves: a sensor by hand (``hand``), a sensor input at a test voltage (``input``),
    or an integrator's IC jack at a test voltage (``ic``; the integrator reads minus it)."""

    kind: str
    target: str
    volts: float = 0.0
    source: str = ""  # where a test voltage comes from: a spare pot's setting, or a bench supply


@dataclass(frozen=True)
class SignStep:
    """One row of the sign check: the pot checked, the pots set (the checked one first; every other
    at 0), what is moved, where the reading is taken and which way it must go (+1 or -1; for
    ``ramp``, the direction the integrator ramps in OP)."""

    pot: str
    on: tuple[str, ...]
    drive: Drive
    read: str
    expect: int
    ramp: bool = False
    moving: bool = False  # a differentiator on the path: the reading shows while the hand moves


@dataclass(frozen=True)
class _Route:
    """A path from what moves to the pot's source: its origin, the pots on it, its differentiators."""

    kind: str  # hand, ic, input
    origin: str
    pots: tuple[str, ...]
    differentiators: tuple[str, ...]

    @property
    def rank(self) -> tuple[int, int]:
        """By hand before a test voltage, an integrator's IC before a sensor input, no differentiator
        before one; fewer pots first."""
        order = {"hand": 0, "ic": 1, "input": 2}[self.kind] + (3 if self.differentiators else 0)
        return order, len(self.pots)


def sign_check(net: Netlist, machine: MachineProfile, plant: PlantModel = CART) -> tuple[SignStep, ...]:
    """One step per pot that checks its sign by moving a sensor or a test voltage.

    Parameters
    ----------
    net : Netlist
        The patch.
    machine : MachineProfile
        Its reference and pot resolution (a test voltage is a spare pot's setting).
    plant : PlantModel
        The plant whose position and angle a person moves by hand.

    Returns
    -------
    tuple of SignStep
        In the order of the pots; a pot whose sign no reading would show (one set to 0) has none.
    """
    wires = wires_of(net)
    roles = {a.id: a.role for a in net.amplifiers}
    hand = {s.id for s in net.sensors if s.quantity in (plant.position, plant.angle)}
    spares = spare_pots(net, machine)
    steps = []
    for p in net.pots:
        reads = [_downstream(net, wires, roles, p.amplifier)]
        if reads[0][0] != p.amplifier:  # else at the pot's own amplifier, when u_c hides its path
            reads.append((p.amplifier, (), False))
        candidates = sorted(_upstream(wires, roles, hand, p.source), key=lambda r: r.rank)
        chosen = (_step(net, wires, roles, machine, p.id, route, read, down, ramp, spares[0] if spares else None)
                  for route in candidates for read, down, ramp in reads)
        step = next((s for s in chosen if s is not None), None)
        if step is not None:  # none for a pot at 0, whose sign nothing shows
            steps.append(step)
    return tuple(steps)


def _downstream(net: Netlist, wires: list[Wire], roles: dict[str, str], amp: str) -> tuple[str, tuple[str, ...], bool]:
    """Where a pot's step is read: u_c through summers from its amplifier (the pots on the way), or
    the amplifier itself (an integrator: read as it ramps)."""
    if roles[amp] == "integrator":
        return amp, (), True
    frontier: list[tuple[str, tuple[str, ...]]] = [(amp, ())]
    seen = {amp}
    while frontier:
        node, pots = frontier.pop(0)
        if node == net.output.source:
            return node, pots, False
        for w in wires:
            if w.source == node and w.amplifier not in seen and roles[w.amplifier] in SUMMING:
                seen.add(w.amplifier)
                frontier.append((w.amplifier, pots + ((w.pot,) if w.pot else ())))
    return amp, (), False


def _upstream(wires: list[Wire], roles: dict[str, str], hand: set[str], source: str) -> list[_Route]:
    """Every path back from a pot's source to a sensor or an integrator, through summers and
    differentiators."""
    found: list[_Route] = []

    def walk(node: str, pots: tuple[str, ...], diffs: tuple[str, ...], seen: frozenset[str]) -> None:
        if node not in roles:
            found.append(_Route("hand" if node in hand else "input", node, pots, diffs))
            return
        if roles[node] == "integrator":
            found.append(_Route("ic", node, pots, diffs))
            return
        if len(seen) > MAX_DEPTH:
            return
        diffs = diffs + ((node,) if roles[node] == "differentiator" else ())
        for w in wires:
            if w.amplifier == node and w.source not in seen:
                walk(w.source, pots + ((w.pot,) if w.pot else ()), diffs, seen | {w.source})

    walk(source, (), (), frozenset({source}))
    return found


def _step(net: Netlist, wires: list[Wire], roles: dict[str, str], machine: MachineProfile, pot: str, route: _Route,
          read: str, down: tuple[str, ...], ramp: bool, spare: str | None) -> SignStep | None:
    """The step along one route, or None when the pot's sign would not show in its reading."""
    on = tuple(dict.fromkeys((pot, *route.pots, *down)))
    diffs = tuple(dict.fromkeys(route.differentiators + ((read,) if roles[read] == "differentiator" else ())))
    set_wires = [w if w.pot is None or w.pot in on else replace(w, gain=0.0) for w in wires]
    unit = _condition(route, 1.0, diffs)
    flipped = [replace(w, gain=-w.gain) if w.pot == pot else w for w in set_wires]
    try:
        value, peak = _reading(net, set_wires, unit, read, ramp)
        other, _ = _reading(net, flipped, unit, read, ramp)
    except np.linalg.LinAlgError:  # a loop of gain exactly 1 on the path: no steady reading
        return None
    if abs(value) < 1e-9 or math.copysign(1.0, value) == math.copysign(1.0, other) or abs(other) < 1e-9:
        return None
    drive = Drive("hand", route.origin)
    if route.kind != "hand":
        ref, res = machine.reference_V, machine.pot_resolution
        volts = min(TARGET_V / abs(value), FULL_SCALE * ref / peak, FULL_SCALE * ref)
        volts = max(res, math.floor(volts / ref / res) * res) * ref
        if route.kind == "ic":  # the integrator's output at +volts: its IC jack at minus that
            drive = Drive("ic", route.origin, -volts, test_voltage_source(-volts, spare, ref))
        else:
            drive = Drive("input", route.origin, volts, test_voltage_source(volts, spare, ref))
    return SignStep(pot, on, drive, read, 1 if value > 0 else -1, ramp, bool(diffs) and route.kind == "hand")


def _condition(route: _Route, volts: float, diffs: tuple[str, ...]) -> Condition:
    """The static solver's condition for a route: its origin at ``volts`` (an integrator's output),
    its differentiators passing the change (patched as summers, in the solver's terms)."""
    if route.kind == "ic":
        return Condition("sign", {}, {route.origin: volts}, diffs, "")
    return Condition("sign", {route.origin: volts}, {}, diffs, "")


def _reading(net: Netlist, wires: list[Wire], cond: Condition, read: str, ramp: bool) -> tuple[float, float]:
    """The reading per unit of the drive (for ``ramp``, minus the integrator's weighted input: the
    direction it ramps), and the largest amplifier output."""
    out = solve(net, wires, cond)
    peak = max([abs(v) for v in out.values()] + [abs(v) for v in cond.sensors_V.values()])
    if not ramp:
        return out[read], peak
    value = {**cond.sensors_V, **out}
    return -sum(w.gain * value.get(w.source, 0.0) for w in wires if w.amplifier == read), peak
