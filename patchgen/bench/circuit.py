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
from patchgen.patch.readback import law_read
from patchgen.patch.reading import Stage, read
from patchgen.plant.plant_model import PLANT_MODELS
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

# amplifier kinds as the inner loop knows them
SUMMER, INTEGRATOR, LAG, DIFFERENTIATOR = 0, 1, 2, 3
_KIND = {"summer": SUMMER, "inverter": SUMMER, "integrator": INTEGRATOR, "lag": LAG,
         "differentiator": DIFFERENTIATOR}
_STATEFUL_OUTPUT = (INTEGRATOR, LAG)  # output is a state: no feed-through (patchgen.patch.reading)


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
    modes: np.ndarray  # complex eigenvalues of the wired law's A_c (patchgen.patch.readback), as compiled

    @property
    def n_sensors(self) -> int:
        """How many sensors feed the circuit."""
        return len(self.sensor_ids)

    @property
    def n_amps(self) -> int:
        """How many amplifiers the circuit has."""
        return len(self.amp_ids)

    def signal_index(self, name: str) -> int:
        """Index in the signal vector of a sensor id or amplifier id."""
        names = self.sensor_ids + self.amp_ids
        return names.index(name)

    def time_rates(self) -> list[float]:
        """1 / time constant of each lag and each differentiator's roll-off (1/s)."""
        return [float(self.param2[j] if k == DIFFERENTIATOR else self.param1[j])
                for j, k in enumerate(self.amp_kind) if k in (LAG, DIFFERENTIATOR)]

    def internal_rates(self) -> list[float]:
        """|eigenvalue| (1/s) of each mode of the circuit's own dynamics (the wired law's A_c, the
        sensors held at zero): how fast its states move among themselves. A lag built from an
        integrator and a summer (a difference on a machine without a differentiator) has no element
        time constant of its own; its mode has, and the step must resolve it as it resolves a lag."""
        lam = np.abs(self.modes)
        return [float(v) for v in lam if v > 1e-9 * max(1.0, lam.max())] if lam.size else []

    def drifting(self) -> np.ndarray:
        """Mask of amplifiers whose capacitor integrates offset and bias (integrators, lags)."""
        return np.isin(self.amp_kind, _STATEFUL_OUTPUT)


def sensor_constants(net: Netlist, bench: BenchProfile) -> np.ndarray:
    """Volts per SI unit of each of the netlist's sensors, as the bench's sensors give them.

    The one source of sensor constants for the simulator and the SPICE deck: the patch meets the
    bench's sensors, whatever constants the design was scaled with (the netlist's volts_per_unit).
    """
    return np.array([float(getattr(bench.sensors, s.quantity)) for s in net.sensors], dtype=np.float64)


def compile_circuit(net: Netlist, machine: MachineProfile, bench: BenchProfile) -> Circuit:
    """Compile a netlist (read by patchgen.patch.reading) for the bench it meets.

    Unknown sources, missing time constants and algebraic loops are errors. A differentiator
    with no ``rolloff_s`` gets the machine's default roll-off (a pure differentiator cannot be
    patched, nor simulated at a fixed step); with no ``T_d_s`` it gets the machine time scale.
    """
    src = f"netlist {net.design}"
    states = PLANT_MODELS[bench.plant].state_names  # the bench's plant's
    for i, s in enumerate(net.sensors):
        if s.quantity not in states:
            raise InputError(src, f"sensors[{i}].quantity",
                             f"unknown quantity {s.quantity!r} (known: {', '.join(states)})")
    reading = read(net, machine.imperfections.differentiator_rolloff_s)
    index = {sid: i for i, sid in enumerate(reading.sensors)}
    index.update({aid: len(reading.sensors) + j for j, aid in enumerate(reading.order)})
    kind, ptr, in_src, in_gain, p1, p2, ic = [], [0], [], [], [], [], []
    for aid in reading.order:
        a = reading.amplifiers[aid]
        kd = _KIND[a.role]
        kind.append(kd)
        in_src += [index[f.source] for f in a.feeds]
        in_gain += [f.gain for f in a.feeds]
        ptr.append(len(in_src))
        ic.append(a.ic_V)
        q1, q2 = _params(a)
        p1.append(q1)
        p2.append(q2)

    return Circuit(
        design=net.design,
        sensor_ids=reading.sensors,
        sensor_state=np.array([states.index(s.quantity) for s in net.sensors], dtype=np.int64),
        sensor_gain=sensor_constants(net, bench),
        amp_ids=reading.order,
        amp_kind=np.array(kind, dtype=np.int64),
        in_ptr=np.array(ptr, dtype=np.int64),
        in_src=np.array(in_src, dtype=np.int64),
        in_gain=np.array(in_gain, dtype=np.float64),
        param1=np.array(p1, dtype=np.float64),
        param2=np.array(p2, dtype=np.float64),
        ic_V=np.array(ic, dtype=np.float64),
        output_index=index[reading.output],
        modes=np.linalg.eigvals(law_read(reading, src).Ac),
    )


def _params(a: Stage) -> tuple[float, float]:
    """param1, param2 of one amplifier (see Circuit): the rates its element values give."""
    if a.role == "integrator":
        return 1.0 / a.T_s, 0.0
    if a.role == "lag":
        return 1.0 / a.tau_s, 0.0
    if a.role == "differentiator":
        return a.T_d_s / a.rolloff_s, 1.0 / a.rolloff_s
    return 0.0, 0.0
