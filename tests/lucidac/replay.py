"""The exported circuit run in lucipy's simulator with the bench's sensor voltages on its
front-panel inputs: patchgen's ideal run of the same patch, replayed.

lucipy 1.7's Simulation leaves two parts of the LUCIDAC out: its front-panel input is a stub
(``set_acl_in``: "the ACL Input is NOT YET fully implemented"; with it set, ``rhs`` drops the math
block's outputs), and ``Mul_out`` keeps the identity elements' outputs at zero where lucipy's own
documentation defines them as their inputs (docs/simulation.rst: M^out_4..7 = M^in_0a..1b).
:class:`Replay` completes those two in a subclass and keeps the rest of lucipy's: the U, C and I
matrices of the circuit (``to_dense_matrices``, with the upscaling), the integrators' k0
(``int_factor``, realtime: seconds), their sign (``rhs``: they negate), the multipliers' (they do
not) and ``solve_ivp``.
"""

from __future__ import annotations

import numpy as np
from lucipy.simulator import Simulation
from scipy.interpolate import CubicSpline

ACL = slice(24, 32)  # the front-panel lanes (lucipy circuits.DefaultLUCIDAC.acl_offset, num_acls)


class Replay(Simulation):
    """lucipy's Simulation with front-panel inputs ``acl_in(t)`` (machine units, 8 values) replacing
    the lanes whose acl_select is external, and identity elements passing their inputs through."""

    def __init__(self, circuit, acl_in, identities: bool = True):
        super().__init__(circuit, realtime=True)
        self.U, self.Cm, self.Im = circuit.to_dense_matrices()
        self.external = np.array([s == "external" for s in circuit.acl_select])
        self.acl_in = acl_in
        self.identities = identities

    def lanes(self, t: float, iout: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The 32 lanes after the C block and the 16 math-block outputs, for integrator outputs
        ``iout`` at time t (the multipliers and identity elements unrolled, as lucipy's Mul_out)."""
        mout = np.zeros(8)
        for _ in range(6):
            out = np.concatenate((iout, mout))
            lanes = self.Cm @ (self.U @ out)
            acl = lanes[ACL]
            acl[self.external] = np.asarray(self.acl_in(t))[self.external]
            m_in = (self.Im @ lanes)[8:16]
            new = np.concatenate((np.prod(m_in.reshape(4, 2), axis=1), m_in[0:4] if self.identities else np.zeros(4)))
            if np.array_equal(new, mout):
                break
            mout = new
        return lanes, np.concatenate((iout, mout))

    def rhs(self, t, state, clip=False):
        lanes, _ = self.lanes(t, state)
        return -(self.Im @ lanes)[0:8] * self.int_factor  # integrators negate (lucipy Simulation.rhs)


def sensor_inputs(history: dict[str, np.ndarray], plan) -> callable:
    """acl_in(t): each sensor's voltage on the bench (volts per unit x its quantity), in machine
    units, on its front-panel input; a cubic spline through patchgen's recorded points."""
    t = history["t"]
    splines = {acl: CubicSpline(t, plan.sensor_volts_per_unit[s] * history[s] / plan.reference_V)
               for s, acl in plan.sensor_acl.items()}

    def acl_in(tt: float) -> np.ndarray:
        v = np.zeros(8)
        for acl, sp in splines.items():
            v[acl] = sp(tt)
        return v
    return acl_in


def start(plan, history: dict[str, np.ndarray]) -> np.ndarray:
    """Each integrator's state at t = 0 (machine units) where patchgen's run starts it: the
    netlist's integrators at their first recorded value (a lag of a difference starts settled), a
    sensor buffer settled on minus its sensor."""
    x0 = np.zeros(8)
    for e in plan.elements:
        if e.kind != "int":
            continue
        if e.amp in plan.sensor_acl:
            x0[e.index] = -plan.sensor_volts_per_unit[e.amp] * history[e.amp][0] / plan.reference_V
        else:
            x0[e.index] = history[e.name][0] / (plan.reference_V * e.scale)
    return x0


def replay(circuit, plan, history: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The circuit driven by the recorded sensors: each element's output and u_c at the output
    jack, in volts (machine units x reference_V; an element that carries its signal scaled down,
    times its scale), at patchgen's recorded times."""
    sim = Replay(circuit, sensor_inputs(history, plan))
    t = history["t"]
    res = sim.solve_ivp(float(t[-1]), ics=start(plan, history), ics_sign=1, t_eval=t, method="LSODA", rtol=1e-8,
                        atol=1e-10, max_step=1e-3)
    assert res.status == 0, res.message
    out: dict[str, list[float]] = {e.name: [] for e in plan.elements}
    out["u_c"] = []
    for k, tk in enumerate(res.t):
        lanes, m = sim.lanes(tk, res.y[:, k])
        for e in plan.elements:
            out[e.name].append(m[e.index if e.kind == "int" else 12 + e.index] * plan.reference_V * e.scale)
        out["u_c"].append(lanes[24 + plan.output_acl] * plan.reference_V)
    return {k: np.array(v) for k, v in out.items()}
