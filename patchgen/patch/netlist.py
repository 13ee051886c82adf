"""The netlist: what is patched on the machine, as a versioned JSON document.

Schema id ``patchgen.netlist/4`` (2 added ``parts``, the external parts a patch needs; 3 each
integrator's ``mode``, its rate k0 and how it is selected; 4 an input's ``negated``, a coefficient
set negative on a machine whose coefficients carry their sign: a version-3 reader would take its
sign wrong). Ideal meaning of each amplifier role
(all amplifiers invert; ``k_j`` is the pot setting feeding input j, or 1 with no pot; ``w_j`` the
input weight 1 or 10; ``T`` the integrator's time scale 1/k0 of its mode, or the netlist's
``time_scale_s`` for an integrator that names no mode):

- summer, inverter: ``out = -sum_j w_j k_j v_j`` (``w_j`` is negative for an input marked
                    ``negated``, on a machine whose coefficients carry their sign)
- integrator:       ``d(out)/dt = -(1/T) sum_j w_j k_j v_j``, ``out(0) = ic_V``
- differentiator:   ``rolloff_s * d(out)/dt + out = -T_d_s * d/dt(sum_j w_j k_j v_j)``
- lag:              ``tau_s * d(out)/dt + out = -sum_j w_j k_j v_j`` (an integrator with
                    resistive feedback)

Sources are sensor ids (``s``, ``theta``, ``s_dot``) or amplifier ids. Sensor voltages are
``volts_per_unit`` times the physical quantity, with its sign. The control output is the
voltage of ``output.source``; the actuator turns it into force (K_U newtons per volt).
``carries`` states what an amplifier output is meant to be: ``polarity * volts_per_unit *
quantity``, so a reader can check every sign.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Literal, NamedTuple

from pydantic import BaseModel, ConfigDict, Field, model_serializer

SCHEMA_ID = "patchgen.netlist/4"

AmpRole = Literal["integrator", "summer", "inverter", "differentiator", "lag"]


class _Doc(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Signal(_Doc):
    """What a voltage represents: polarity * volts_per_unit * quantity."""

    quantity: str = Field(description="e.g. theta_dot, int_theta, u_c, xhat_theta_dot")
    polarity: Literal[1, -1]
    volts_per_unit: float = Field(description="volts per SI unit of the quantity (1 for volts)")
    unit: str = ""


class SensorInput(_Doc):
    """A sensor voltage entering the patch: its id, what it measures and its volts per unit."""

    id: str = Field(description="signal id used as a source: s, theta or s_dot")
    label: str
    quantity: str
    unit: str
    volts_per_unit: float


class AmpInput(_Doc):
    """One patched input of an amplifier: its source, the pot in between (if any), weight and jack."""

    source: str = Field(description="sensor id or amplifier id whose output feeds this input")
    pot: str | None = Field(default=None, description="pot id between source and input, or none")
    weight: int = Field(gt=0, description="input weight (the profile's, e.g. 1 or 10)")
    jack: str = Field(description="which input jack of the amplifier, e.g. x1a, x10b")
    negated: bool = Field(default=False, description="the machine sets this input's coefficient negative (a "
                                                     "machine with signed coefficients); left out when false")

    @model_serializer(mode="wrap")
    def _drop_default_sign(self, handler):
        """A plain input is written as before the field existed (the same bytes for patch-cord machines)."""
        out = handler(self)
        if not self.negated:
            out.pop("negated", None)
        return out


class Mode(_Doc):
    """An integrator's mode as the machine profile states it: its rate and how it is selected."""

    name: str = Field(description="the profile's name for the mode, e.g. 'standard' or 'SLOW'")
    k0_per_s: float = Field(gt=0, description="1/s: d(out)/dt = -k0 x (a x1 input at 1 V); T = 1/k0")
    jumper: str | None = Field(default=None, description="the integrator's jack patched to its own output to "
                                                         "select the mode (a cord on the wire list), or none")


class Amplifier(_Doc):
    """One amplifier as patched: role, inputs, the signal it carries and its element values."""

    id: str = Field(description="the machine's amplifier id (profile)")
    role: AmpRole
    inputs: list[AmpInput]
    carries: Signal
    ic_V: float | None = Field(default=None, description="initial condition (integrators, lags); none on an "
                               "integrator: it starts settled on its input (a lag closed through a difference, "
                               "running while the pendulum is held, as a differentiator is)")
    mode: Mode | None = Field(default=None, description="an integrator's mode (its k0); none for other roles")
    T_d_s: float | None = Field(default=None, description="differentiator gain time constant")
    rolloff_s: float | None = Field(default=None, description="differentiator roll-off time constant")
    tau_s: float | None = Field(default=None, description="lag time constant")
    purpose: str = ""


class Pot(_Doc):
    """One coefficient pot: its setting, what it feeds and the coefficient it realises."""

    id: str
    setting: float = Field(ge=0, description="dial setting, quantised to the dial resolution")
    source: str
    amplifier: str
    jack: str
    weight: int = Field(gt=0, description="input weight (the profile's, e.g. 1 or 10)")
    signal: str = Field(description="human name of the signal through the pot")
    coefficient: float = Field(description="the design coefficient this pot realises (V/V, signed)")
    realized: float = Field(description="signed coefficient realised: sign * setting * weight")
    note: str = ""

    @property
    def error(self) -> float:
        """Relative error of the realised coefficient against the design (0 when both 0)."""
        if self.coefficient == 0.0:
            return 0.0 if self.realized == 0.0 else float("inf")
        return self.realized / self.coefficient - 1.0


class Part(_Doc):
    """An external part a patch needs beyond the machine's own (patchgen.patch.parts): its value,
    what to fit, its tolerance and where it goes."""

    id: str = Field(description="C1, C2, ... and R1, R2, ...")
    kind: Literal["capacitor", "resistor"]
    value: float = Field(gt=0, description="nominal value, F or ohm, as the element values need it")
    unit: Literal["F", "ohm"]
    fit: str = Field(description="stock part(s) to fit, e.g. '6.34 kohm (E96)' or '68 nF + 3.3 nF in parallel'")
    fit_value: float = Field(gt=0, description="the value the stock part(s) give")
    tolerance: float = Field(ge=0, description="the stock parts' tolerance, a fraction")
    amplifier: str
    jack: str | None = Field(default=None, description="the input jack it serves, or none (feedback)")
    connection: str = Field(description="where it goes, in words")
    purpose: str = ""


class ControlOutput(_Doc):
    """Where the control voltage u_c leaves the machine for the servo amplifier."""

    source: str
    quantity: str = "u_c"
    K_U_N_per_V: float


class Netlist(_Doc):
    """Everything patched on the machine for one design, as a versioned JSON document."""

    schema_id: str = Field(default=SCHEMA_ID, alias="schema")
    design: str
    description: str = ""
    machine: str
    machine_name: str
    units: int = 1
    reference_V: float
    time_scale_s: float = Field(description="the slowest integrator mode's 1/k0, at which the law was scaled")
    pot_resolution: float
    sensors: list[SensorInput]
    amplifiers: list[Amplifier]
    pots: list[Pot]
    output: ControlOutput
    parts: list[Part] = Field(default_factory=list, description="external parts, in amplifier order")
    operation: list[str] = Field(default_factory=list, description="mode and IC steps, in order")
    notes: list[str] = Field(default_factory=list)

    model_config = ConfigDict(extra="forbid", populate_by_name=True)

    def amp(self, amp_id: str) -> Amplifier:
        for a in self.amplifiers:
            if a.id == amp_id:
                return a
        raise KeyError(amp_id)

    def pot(self, pot_id: str) -> Pot:
        for p in self.pots:
            if p.id == pot_id:
                return p
        raise KeyError(pot_id)

    def to_json(self) -> str:
        """Deterministic JSON text (sorted keys, fixed indentation, trailing newline)."""
        return json.dumps(self.model_dump(mode="json", by_alias=True), indent=2, sort_keys=True, allow_nan=False) + "\n"


def read_netlist(path: str | Path) -> Netlist:
    """A netlist from its JSON file, validated against the schema."""
    return Netlist.model_validate_json(Path(path).read_text())


def json_schema() -> dict:
    """The netlist's JSON schema (documented in docs/netlist.md)."""
    return Netlist.model_json_schema(by_alias=True)


class Cord(NamedTuple):
    """One patch cord: its two ends as the wire list writes them, and the elements it joins.

    ``source`` is the sensor, amplifier, pot or part whose output (a pot's wiper) the cord
    carries; ``target`` the pot (its top), amplifier or part it feeds ("" for the servo
    amplifier); ``jack`` the amplifier input it serves ("" for a pot's top, a mode jumper or a
    part across a feedback)."""

    frm: str
    to: str
    source: str
    target: str
    jack: str = ""


def cords(net: Netlist) -> list[Cord]:
    """Every patch cord, in a stable order: pots fed first, then amplifier inputs (a
    differentiator's through its external capacitor and series resistor), an integrator's mode
    jumper, then parts across a feedback; on slaved units, grouped by the unit each cord ends on."""
    out: list[Cord] = []
    for p in net.pots:
        out.append(Cord(_jack_name(net, p.source), f"{p.id} top", p.source, p.id))
    for a in net.amplifiers:
        for inp in a.inputs:
            src = f"{inp.pot} wiper" if inp.pot else _jack_name(net, inp.source)
            origin = inp.pot or inp.source
            cap = next((x for x in net.parts if x.amplifier == a.id and x.jack == inp.jack and x.kind == "capacitor"),
                       None)
            res = next((x for x in net.parts if x.amplifier == a.id and x.jack == inp.jack and x.kind == "resistor"),
                       None)
            if cap is not None and res is not None:  # a differentiator's input: capacitor, then series resistor
                out += [Cord(src, f"{cap.id} ({cap.fit})", origin, a.id, inp.jack),
                        Cord(cap.id, f"{res.id} ({res.fit})", cap.id, res.id),
                        Cord(res.id, f"{a.id} summing junction", res.id, a.id)]
                continue
            out.append(Cord(src, f"{a.id} in {inp.jack} (x{inp.weight})", origin, a.id, inp.jack))
        if a.mode is not None and a.mode.jumper:
            out.append(Cord(f"{a.id} {a.mode.jumper}", f"{a.id} out ({a.mode.name}: k0 {a.mode.k0_per_s:g} 1/s)",
                            a.id, a.id))
        for x in net.parts:
            if x.amplifier == a.id and x.jack is None:
                out.append(Cord(f"{x.id} ({x.fit})", f"across {a.id} feedback: summing junction to output", x.id,
                                a.id))
    out.append(Cord(_jack_name(net, net.output.source), "servo amplifier input (u_c)", net.output.source, ""))
    if net.units > 1:  # slaved units: each unit's cords together, in the order above
        out.sort(key=lambda c: _unit(c.to))
    return out


def wire_list(net: Netlist) -> list[tuple[str, str]]:
    """Every patch cord as (from, to), in the order of :func:`cords`."""
    return [(c.frm, c.to) for c in cords(net)]


def _unit(end: str) -> int:
    """The unit a cord ends on (U2.P3 top, across U1.A4 feedback: 2, 1); after every unit for the
    servo amplifier."""
    m = re.search(r"\bU(\d+)\.", end)
    return int(m.group(1)) if m else 1_000


def _jack_name(net: Netlist, source: str) -> str:
    for s in net.sensors:
        if s.id == source:
            return f"{s.id} sensor"
    return f"{source} out"
