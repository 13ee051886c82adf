"""Read a netlist back into the control law it wires, from the netlist alone.

Gives the linear controller from sensor voltages (in the netlist's sensor order) to the control
voltage: xc' = Ac xc + Bc y, u_c = Cc xc + Dc y, with ideal elements (see patchgen.patch.netlist for
the meaning of each role). Used to prove a patch realises its design (signs included) and to
check the allocator's own claims about what each amplifier carries.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from patchgen.patch.netlist import Netlist

DYNAMIC = ("integrator", "lag", "differentiator")


@dataclass(frozen=True)
class WiredLaw:
    inputs: tuple[str, ...]  # sensor ids
    states: tuple[str, ...]  # amplifier ids with a state
    Ac: np.ndarray
    Bc: np.ndarray
    Cc: np.ndarray
    Dc: np.ndarray

    def freqresp(self, w: np.ndarray) -> np.ndarray:
        """Complex gain from each sensor voltage to u_c at each frequency, shape (len(w), n_inputs)."""
        n = self.Ac.shape[0]
        out = np.empty((len(w), len(self.inputs)), dtype=complex)
        for k, wk in enumerate(w):
            G = self.Cc @ np.linalg.solve(1j * wk * np.eye(n) - self.Ac, self.Bc) if n else 0
            out[k] = (G + self.Dc)[0]
        return out


def _gain(net: Netlist, inp) -> float:
    k = net.pot(inp.pot).setting if inp.pot else 1.0
    return inp.weight * k


def wired_law(net: Netlist, output: str | None = None) -> WiredLaw:
    """The linear law from the sensors to `output` (default: the control output's source)."""
    sensors = [s.id for s in net.sensors]
    dyn = [a.id for a in net.amplifiers if a.role in DYNAMIC]
    ny, nx = len(sensors), len(dyn)
    amps = {a.id: a for a in net.amplifiers}
    T = net.time_scale_s
    expr: dict[str, np.ndarray] = {}  # amp/sensor id -> row over [x; y]
    for i, s in enumerate(sensors):
        e = np.zeros(nx + ny)
        e[nx + i] = 1.0
        expr[s] = e
    visiting: set[str] = set()

    def input_sum(a) -> np.ndarray:
        return sum((_gain(net, inp) * value(inp.source) for inp in a.inputs), np.zeros(nx + ny))

    def value(src: str) -> np.ndarray:
        if src in expr:
            return expr[src]
        if src not in amps:
            raise ValueError(f"netlist: unknown source {src!r}")
        a = amps[src]
        if src in visiting:
            raise ValueError(f"netlist: algebraic loop through {src}")
        visiting.add(src)
        e = np.zeros(nx + ny)
        if a.role in ("integrator", "lag"):
            e[dyn.index(src)] = 1.0
        elif a.role == "differentiator":
            # z' = (in - z)/r, out = -(T_d/r)(in - z)
            e = -(a.T_d_s / a.rolloff_s) * (input_sum(a) - _unit(dyn.index(src), nx + ny))
        else:
            e = -input_sum(a)
        visiting.discard(src)
        expr[src] = e
        return e

    Ac, Bc = np.zeros((nx, nx)), np.zeros((nx, ny))
    for k, aid in enumerate(dyn):
        a = amps[aid]
        s = input_sum(a)
        if a.role == "integrator":
            row = -s / T
        elif a.role == "lag":
            row = (-s - _unit(k, nx + ny)) / a.tau_s
        else:
            row = (s - _unit(k, nx + ny)) / a.rolloff_s
        Ac[k], Bc[k] = row[:nx], row[nx:]
    o = value(output or net.output.source)
    return WiredLaw(tuple(sensors), tuple(dyn), Ac, Bc, o[None, :nx], o[None, nx:])


def _unit(i: int, n: int) -> np.ndarray:
    e = np.zeros(n)
    e[i] = 1.0
    return e
