"""The patched circuit as flat arrays: what the simulator's inner loop evaluates, exactly as wired.

A netlist is compiled into a signal vector ``[sensor voltages..., amplifier outputs...]`` and, for
each amplifier in evaluation order, its inputs as (signal index, gain) with gain = weight * pot
setting (sign-free: every GP-6 amplifier inverts, and the inversion is applied by the role).
Amplifiers whose output does not depend on their present input (integrators, lags) come first:
their outputs are states. Amplifiers with direct feed-through (summers, inverters, differentiators)
follow, each after every feed-through amplifier it reads. A loop of feed-through amplifiers is an
algebraic loop, which the machine cannot settle and the simulator refuses.

A differentiator ``r * d(out)/dt + out = -T_d * d(v)/dt`` (v its weighted input sum) is evaluated as
``out = -(T_d / r) * (v - f)`` with the filter state ``r * df/dt = v - f``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from patchgen.inputs.errors import InputError
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PLANT_STATES
from patchgen.profiles.machine import MachineProfile

# amplifier kinds as the inner loop knows them
SUMMER, INTEGRATOR, LAG, DIFFERENTIATOR = 0, 1, 2, 3
_KIND = {"summer": SUMMER, "inverter": SUMMER, "integrator": INTEGRATOR, "lag": LAG,
         "differentiator": DIFFERENTIATOR}
_STATEFUL_OUTPUT = (INTEGRATOR, LAG)  # output is a state: no feed-through


class AlgebraicLoopError(InputError):
    """Feed-through amplifiers wired in a loop with no integrator or lag in it."""


@dataclass(frozen=True)
class Circuit:
    """A netlist compiled for simulation. Arrays are indexed by evaluation order.

    ``param1``/``param2`` per amplifier: integrator 1/T and unused; lag 1/tau and unused;
    differentiator T_d/r and 1/r; summer unused.
    """

    design: str
    sensor_ids: tuple[str, ...]
    sensor_state: np.ndarray  # int64: index into the plant state of each sensor's quantity
    sensor_gain: np.ndarray  # V per SI unit
    amp_ids: tuple[str, ...]
    amp_kind: np.ndarray  # int64
    in_ptr: np.ndarray  # int64, len n_amp + 1: inputs of amp j are in_ptr[j]:in_ptr[j+1]
    in_src: np.ndarray  # int64 signal index
    in_gain: np.ndarray  # weight * pot setting (>= 0)
    param1: np.ndarray
    param2: np.ndarray
    ic_V: np.ndarray
    output_index: int  # signal index of the control voltage u_c

    @property
    def n_sensors(self) -> int:
        return len(self.sensor_ids)

    @property
    def n_amps(self) -> int:
        return len(self.amp_ids)

    def signal_index(self, name: str) -> int:
        """Index in the signal vector of a sensor id or amplifier id."""
        names = self.sensor_ids + self.amp_ids
        return names.index(name)

    def time_rates(self) -> list[float]:
        """1 / time constant of each lag and each differentiator's roll-off (1/s)."""
        return [float(self.param2[j] if k == DIFFERENTIATOR else self.param1[j])
                for j, k in enumerate(self.amp_kind) if k in (LAG, DIFFERENTIATOR)]

    def drifting(self) -> np.ndarray:
        """Mask of amplifiers whose capacitor integrates offset and bias (integrators, lags)."""
        return np.isin(self.amp_kind, _STATEFUL_OUTPUT)


def compile_circuit(net: Netlist, machine: MachineProfile) -> Circuit:
    """Compile a netlist; unknown sources, missing time constants and algebraic loops are errors.

    A differentiator with no ``rolloff_s`` gets the machine's default roll-off (a pure
    differentiator cannot be patched, nor simulated at a fixed step); with no ``T_d_s`` it gets
    the machine time scale.
    """
    src = f"netlist {net.design}"
    sensor_ids = tuple(s.id for s in net.sensors)
    for i, s in enumerate(net.sensors):
        if s.quantity not in PLANT_STATES:
            raise InputError(src, f"sensors[{i}].quantity",
                             f"unknown quantity {s.quantity!r} (known: {', '.join(PLANT_STATES)})")
    amps = {a.id: a for a in net.amplifiers}
    if len(amps) != len(net.amplifiers):
        raise InputError(src, "amplifiers", "an amplifier id is used twice")
    pots = {p.id: p for p in net.pots}
    known = set(sensor_ids) | set(amps)
    for i, a in enumerate(net.amplifiers):
        for k, inp in enumerate(a.inputs):
            where = f"amplifiers[{i}].inputs[{k}]"
            if inp.source not in known:
                raise InputError(src, f"{where}.source", f"unknown source {inp.source!r}")
            if inp.pot is not None and inp.pot not in pots:
                raise InputError(src, f"{where}.pot", f"unknown pot {inp.pot!r}")
    if net.output.source not in known:
        raise InputError(src, "output.source", f"unknown source {net.output.source!r}")

    order = _evaluation_order(net, src)
    index = {sid: i for i, sid in enumerate(sensor_ids)}
    index.update({aid: len(sensor_ids) + j for j, aid in enumerate(order)})

    position = {a.id: i for i, a in enumerate(net.amplifiers)}
    kind, ptr, in_src, in_gain, p1, p2, ic = [], [0], [], [], [], [], []
    for aid in order:
        a = amps[aid]
        kd = _KIND[a.role]
        kind.append(kd)
        for inp in a.inputs:
            setting = pots[inp.pot].setting if inp.pot is not None else 1.0
            in_src.append(index[inp.source])
            in_gain.append(inp.weight * setting)
        ptr.append(len(in_src))
        ic.append(a.ic_V or 0.0)
        if kd == INTEGRATOR:
            p1.append(1.0 / net.time_scale_s)
            p2.append(0.0)
        elif kd == LAG:
            if not a.tau_s or a.tau_s <= 0:
                raise InputError(src, f"amplifiers[{position[aid]}].tau_s",
                                 "a lag amplifier needs tau_s > 0")
            p1.append(1.0 / a.tau_s)
            p2.append(0.0)
        elif kd == DIFFERENTIATOR:
            r = a.rolloff_s if a.rolloff_s else machine.imperfections.differentiator_rolloff_s
            td = a.T_d_s if a.T_d_s is not None else net.time_scale_s
            p1.append(td / r)
            p2.append(1.0 / r)
        else:
            p1.append(0.0)
            p2.append(0.0)

    return Circuit(
        design=net.design,
        sensor_ids=sensor_ids,
        sensor_state=np.array([PLANT_STATES.index(s.quantity) for s in net.sensors],
                              dtype=np.int64),
        sensor_gain=np.array([s.volts_per_unit for s in net.sensors], dtype=np.float64),
        amp_ids=tuple(order),
        amp_kind=np.array(kind, dtype=np.int64),
        in_ptr=np.array(ptr, dtype=np.int64),
        in_src=np.array(in_src, dtype=np.int64),
        in_gain=np.array(in_gain, dtype=np.float64),
        param1=np.array(p1, dtype=np.float64),
        param2=np.array(p2, dtype=np.float64),
        ic_V=np.array(ic, dtype=np.float64),
        output_index=index[net.output.source],
    )


def _evaluation_order(net: Netlist, src: str) -> list[str]:
    """State-output amplifiers first (netlist order), then feed-through ones topologically."""
    kinds = {a.id: _KIND[a.role] for a in net.amplifiers}
    order = [a.id for a in net.amplifiers if kinds[a.id] in _STATEFUL_OUTPUT]
    through = [a for a in net.amplifiers if kinds[a.id] not in _STATEFUL_OUTPUT]
    deps = {a.id: [i.source for i in a.inputs
                   if i.source in kinds and kinds[i.source] not in _STATEFUL_OUTPUT]
            for a in through}
    done: set[str] = set()
    visiting: list[str] = []

    def visit(aid: str) -> None:
        if aid in done:
            return
        if aid in visiting:
            loop = visiting[visiting.index(aid):] + [aid]
            raise AlgebraicLoopError(
                src, "amplifiers",
                f"algebraic loop {' -> '.join(loop)}: feed-through amplifiers (summers, inverters, "
                "differentiators) wired in a ring with no integrator or lag in it")
        visiting.append(aid)
        for dep in deps[aid]:
            visit(dep)
        visiting.pop()
        done.add(aid)
        order.append(aid)

    for a in through:
        visit(a.id)
    return order
