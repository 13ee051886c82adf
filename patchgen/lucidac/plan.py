"""A netlist placed on the LUCIDAC's elements and lanes: which element carries what, each lane's
signed coefficient, the sensors on front-panel inputs and u_c on a front-panel output.

The netlist means what it means everywhere (patchgen.patch.reading): summer ``out = -sum g v``,
integrator ``d(out)/dt = -k0 sum g v`` with g the signed gain of each input. On the LUCIDAC
(lucipy 1.7):

- an integrator inverts, ``d(out)/dt = -k0 sum c v`` (simulator.Simulation.rhs), so a lane into it
  has c = g, at the integrator's own k0 (the netlist's mode);
- an identity element passes its input sum through, ``out = +sum c v`` (lucipy docs, Simulation:
  M^out_4..7 = M^in_0a..1b), so a lane into a netlist summer has c = -g;
- a lane's coefficient lies in [-1, 1], times 10 with the I block's upscaling
  (circuits.Routing.coeff_upscale): a larger one is split over ceil(|c| / 10) lanes of equal share;
- a front-panel input (ACL_IN, lanes 24-31) enters one element input behind the C block, with no
  coefficient (circuits.Routing.front_input): a sensor whose one consumer takes it at +1 is wired
  straight there; any other enters a free integrator on the fast k0 with its own output fed back
  at 1, which carries minus the sensor with a lag of 1/k0 = 0.1 ms (the identity elements are kept
  for gain stages), and the consumers weight that;
- a front-panel output (ACL_OUT) carries one lane past the C block but not the I block, so its
  coefficient is within [-1, 1] with no upscaling (lucipy's dense matrices: the upscaling is the
  I block's): u_c's element carries u_c itself, at coefficient 1;
- a coefficient needing more than STAGE_ABOVE lanes goes through a gain stage when an identity
  element is free: the stage takes the source |c| / 10 times, the target takes the stage 10 times.

Machine units are volts over the profile's reference_V; coefficients are ratios of volts and
carry over unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from patchgen.inputs.errors import ResourceError
from patchgen.patch.netlist import Netlist
from patchgen.patch.reading import read
from patchgen.profiles.machine import MachineProfile

ACL_FIRST = 24      # lanes 24-31 reach the front panel (circuits.DefaultLUCIDAC.acl_offset)
ACL_COUNT = 8       # front-panel inputs and outputs, each (circuits.DefaultLUCIDAC.num_acls)
STAGE_ABOVE = 2     # a coefficient over more lanes than this goes through a gain stage, when one is free


@dataclass(frozen=True)
class Element:
    """One LUCIDAC element: ``kind`` "int" (integrator ``index`` 0-7, ``k0_per_s``) or "id"
    (identity element ``index`` 0-3); ``amp`` the netlist amplifier it is, or the sensor it buffers."""

    name: str           # I0 ... I7, ID0 ... ID3 (the profile's ids)
    kind: str
    index: int
    amp: str
    carries: str
    k0_per_s: float | None = None
    scale: float = 1.0  # the element carries (the signal it stands for) / scale


@dataclass(frozen=True)
class Lane:
    """One lane: ``source`` element (or "ACL_IN n") into ``target`` element (or "ACL_OUT n"),
    coefficient ``coeff``; ``gain`` the netlist's signed gain it realises (its share of it) and
    ``signal`` the netlist source it carries."""

    source: str
    target: str
    coeff: float
    gain: float
    signal: str


@dataclass(frozen=True)
class LanePlan:
    """The whole placement: elements, lanes (front-panel lanes first), sensors and output."""

    design: str
    elements: tuple[Element, ...]
    lanes: tuple[Lane, ...]
    sensor_acl: dict[str, int]          # sensor id -> front-panel input number
    sensor_volts_per_unit: dict[str, float]
    output_acl: int
    reference_V: float
    notes: tuple[str, ...]
    slow_k0_per_s: float  # the integrators' slow mode (the profile's slowest): lucipy's slow flag

    def element(self, name: str) -> Element:
        return next(e for e in self.elements if e.name == name)


def plan(net: Netlist, machine: MachineProfile) -> LanePlan:
    """Place the netlist on the LUCIDAC; a shortfall of elements or lanes is one ResourceError line."""
    src = f"netlist {net.design}"
    # from the profile: a lane per coefficient pot, a lane's largest coefficient its top weighted
    # input, and a sensor's buffer on the fastest integrator mode (the shortest lag)
    n_lanes, lane_max = machine.pot_count, max(machine.input_weights) * machine.pot_max
    modes = [m.k0_per_s for m in machine.modes()]  # slowest first
    buffer_k0 = modes[-1]
    reading = read(net)
    elements: dict[str, Element] = {}
    for a in net.amplifiers:
        kind = "int" if a.role == "integrator" else "id"
        elements[a.id] = Element(a.id, kind, _index(a.id), a.id, a.carries.quantity,
                                 a.mode.k0_per_s if a.mode is not None else None)
    gains = {aid: _merged(reading.amplifiers[aid].feeds) for aid in elements}
    free = {k: [a.id for a in machine.amplifiers if a.id not in elements and a.id.startswith(p)]
            for k, p in (("int", "I"), ("id", "ID"))}
    free["int"] = [a for a in free["int"] if not a.startswith("ID")]
    sensor_acl = {s.id: i for i, s in enumerate(net.sensors)}
    if len(sensor_acl) + 1 > ACL_COUNT:
        raise ResourceError(src, "machine", f"{len(sensor_acl)} sensors and u_c need {len(sensor_acl) + 1} of the "
                            f"{ACL_COUNT} front-panel lanes")
    lanes: list[Lane] = []
    notes: list[str] = []
    direct: dict[str, str] = {}
    for s, acl in sensor_acl.items():
        users = [(aid, g) for aid in gains for f, g in gains[aid].items() if f == s]
        if len(users) == 1 and math.isclose(_lucidac(elements[users[0][0]], users[0][1]), 1.0):
            direct[s] = users[0][0]
            lanes.append(Lane(f"ACL_IN {acl}", users[0][0], 1.0, users[0][1], s))
            continue
        buf = _take(free, "int", src, f"sensor {s} needs an element of its own (front-panel inputs carry no "
                    "coefficient)")
        elements[buf] = Element(buf, "int", _index(buf), s, f"-{s} (front-panel input {acl})", buffer_k0, -1.0)
        lanes += [Lane(f"ACL_IN {acl}", buf, 1.0, 1.0, s), Lane(buf, buf, 1.0, 1.0, s)]
        notes.append(f"{s} enters on front-panel input {acl} into integrator {buf} (k0 {buffer_k0:g} 1/s, its own "
                     f"output fed back at 1): it carries -{s} with a lag of {1e3 / buffer_k0:g} ms, which the "
                     "netlist does not have")
    output_acl = len(sensor_acl)
    lanes.append(Lane(net.output.source, f"ACL_OUT {output_acl}", 1.0, 1.0, "u_c"))
    for aid in [a.id for a in net.amplifiers]:
        for source, g in gains[aid].items():
            if direct.get(source) == aid:
                continue
            feeder = next(e for e in elements.values() if e.amp == source)
            c = _lucidac(elements[aid], g) * feeder.scale
            if abs(c) > STAGE_ABOVE * lane_max and free["id"]:  # a gain stage spares lanes
                stage = _take(free, "id", src, "")
                k = abs(c) / lane_max
                elements[stage] = Element(stage, "id", _index(stage), f"{source} x{k:.4g}",
                                          f"{k:.4g} x {feeder.carries}", None, feeder.scale / k)
                lanes += _split(feeder.name, stage, k, g / lane_max, source, lane_max)
                lanes += _split(stage, aid, math.copysign(lane_max, c), math.copysign(lane_max, g), source, lane_max)
                notes.append(f"{source} into {aid}: coefficient {c:.4g} as a gain stage, identity element {stage} "
                             f"({k:.4g}) then {lane_max:g}")
                continue
            lanes += _split(feeder.name, aid, c, g, source, lane_max)
    if len(lanes) > n_lanes:
        raise ResourceError(src, "machine", f"the patch needs {len(lanes)} lanes; {machine.name} has {n_lanes}")
    order = sorted(elements.values(), key=lambda e: (e.kind != "int", e.index))
    return LanePlan(net.design, tuple(order), tuple(lanes), sensor_acl,
                    {s.id: s.volts_per_unit for s in net.sensors}, output_acl, net.reference_V, tuple(notes),
                    modes[0])


def _take(free: dict[str, list[str]], kind: str, src: str, why: str) -> str:
    if not free[kind]:
        raise ResourceError(src, "machine", f"{why}; every {'integrator' if kind == 'int' else 'identity element'} "
                            "of the LUCIDAC is taken")
    return free[kind].pop(0)


def _split(source: str, target: str, c: float, gain: float, signal: str, lane_max: float) -> list[Lane]:
    """A coefficient over ceil(|c| / lane_max) lanes of equal share."""
    n = max(1, math.ceil(abs(c) / lane_max - 1e-12))
    return [Lane(source, target, c / n, gain / n, signal)] * n


def _index(name: str) -> int:
    return int(name.lstrip("ID"))


def _merged(feeds) -> dict[str, float]:
    """An element's signed gains, one per source (a coefficient split over inputs summed again)."""
    out: dict[str, float] = {}
    for f in feeds:
        out[f.source] = out.get(f.source, 0.0) + f.gain
    return out


def _lucidac(target: Element, gain: float) -> float:
    """The lane coefficient that gives the netlist's gain: as is into an inverting integrator,
    negated into a non-inverting identity element, divided by the element's own scale-down."""
    return (gain if target.kind == "int" else -gain) / target.scale
