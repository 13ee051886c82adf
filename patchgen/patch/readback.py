"""Read a netlist back into the control law it wires, from the netlist alone.

Gives the linear controller from sensor voltages (in the netlist's sensor order) to the control
voltage: xc' = Ac xc + Bc y, u_c = Cc xc + Dc y, with ideal elements (see patchgen.patch.netlist for
the meaning of each role). Used to prove a patch realises its design (signs included) and to
check the allocator's own claims about what each amplifier carries.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from patchgen.design.controller import Controller
from patchgen.inputs.errors import InputError
from patchgen.patch.netlist import Netlist
from patchgen.patch.reading import Reading, read

DYNAMIC = ("integrator", "lag", "differentiator")


@dataclass(frozen=True)
class WiredLaw:
    """The linear law a netlist wires: xc' = Ac xc + Bc y, u_c = Cc xc + Dc y over the sensor voltages y."""

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


def wired_law(net: Netlist, output: str | None = None) -> WiredLaw:
    """The linear law from the sensors to ``output`` (default: the control output's source).

    Parameters
    ----------
    net : Netlist
        The patch, read through :func:`patchgen.patch.reading.read` (ideal elements: a
        differentiator must name its roll-off).
    output : str, optional
        A sensor or amplifier id whose voltage is the law's output.

    Returns
    -------
    WiredLaw
        Ac, Bc, Cc, Dc over the states of the integrators, lags and differentiator roll-offs.
    """
    return law_read(read(net), f"netlist {net.design}", output)


def law_read(r: Reading, source: str, output: str | None = None) -> WiredLaw:
    """:func:`wired_law` of a netlist already read (a simulator's reading, its differentiators given
    the machine's default roll-off); ``source`` names it in an error."""
    sensors = list(r.sensors)
    dyn = [aid for aid, a in r.amplifiers.items() if a.role in DYNAMIC]
    ny, nx = len(sensors), len(dyn)
    expr: dict[str, np.ndarray] = {s: _unit(nx + i, nx + ny) for i, s in enumerate(sensors)}  # row over [x; y]

    def input_sum(a) -> np.ndarray:
        return sum((f.gain * expr[f.source] for f in a.feeds), np.zeros(nx + ny))

    for aid in r.order:  # states first, then each feed-through amplifier after what it reads
        a = r.amplifiers[aid]
        if a.stateful:
            expr[aid] = _unit(dyn.index(aid), nx + ny)
        elif a.role == "differentiator":  # z' = (in - z)/r, out = -(T_d/r)(in - z)
            if not a.rolloff_s:
                raise InputError(source, f"amplifiers.{aid}.rolloff_s",
                                 "a differentiator needs a roll-off > 0 (a pure one has no state-space law)")
            expr[aid] = -(a.T_d_s / a.rolloff_s) * (input_sum(a) - _unit(dyn.index(aid), nx + ny))
        else:
            expr[aid] = -input_sum(a)
    Ac, Bc = np.zeros((nx, nx)), np.zeros((nx, ny))
    for k, aid in enumerate(dyn):
        a = r.amplifiers[aid]
        s = input_sum(a)
        if a.role == "integrator":
            row = -s / a.T_s
        elif a.role == "lag":
            row = (-s - _unit(k, nx + ny)) / a.tau_s
        else:
            row = (s - _unit(k, nx + ny)) / a.rolloff_s
        Ac[k], Bc[k] = row[:nx], row[nx:]
    o = expr[output or r.output]
    return WiredLaw(tuple(sensors), tuple(dyn), Ac, Bc, o[None, :nx], o[None, nx:])


def si_controller(net: Netlist) -> Controller:
    """The wired law in the design's units: from the sensors' quantities (m, rad, m/s; the
    netlist's sensor order) to the force u (N), through the sensor constants and K_U.

    Parameters
    ----------
    net : Netlist
        The patch, its pots as dialled.

    Returns
    -------
    Controller
        xc' = Ac xc + Bc y, u = Cc xc + Dc y over the wired states (patchgen.design.lqg's
        convention: a design's controller in the same form).
    """
    law = wired_law(net)
    vpu = {s.id: s.volts_per_unit for s in net.sensors}
    ks = np.diag([vpu[s] for s in law.inputs])
    KU = net.output.K_U_N_per_V
    return Controller(law.states, law.Ac, law.Bc @ ks, KU * law.Cc, KU * law.Dc @ ks)


def _unit(i: int, n: int) -> np.ndarray:
    e = np.zeros(n)
    e[i] = 1.0
    return e
