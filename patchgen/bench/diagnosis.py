"""Why a patch holds or not: the wired loop linearised about upright, with the bench's actuator
(its lag) and with the ideal actuator the design may have assumed. The dead zone and the limits
are not linear; the simulation shows them.

The verdict has three values. Stable: every pole left of the axis by more than MARGINAL_TOL.
Unstable: a pole right of it. Marginal: the rightmost pole on the axis within that tolerance; a
pole at the origin then means a conserved quantity, named from the pole's left eigenvector (the
plant conserves g/l ∫θ - θ̇ - c/(m l²) θ - ṡ/l whatever the force, so a pure integral of θ leaves
such a pole that no pot can move).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from patchgen.bench.bench_linear import actuator_lag, bench_plant
from patchgen.design.lqg import Design
from patchgen.design.margins import Margins, loop_margins
from patchgen.patch.as_patched import AsPatched, as_patched, figures
from patchgen.patch.netlist import Netlist
from patchgen.patch.readback import wired_law
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

# 1/s: a pole within this of the imaginary axis is on it (the eigenvalue solver's error on these
# loops, of order 1e-12, is far below it; the slowest real mode of a patch, 1e-5 1/s leaks, above)
MARGINAL_TOL = 1e-7
# the weight below which a state is left out of a conserved quantity's name, relative to the largest
NAMED_WEIGHT = 1e-6


@dataclass(frozen=True)
class LoopPoles:
    """The closed-loop poles (1/s) of the wired loop with one actuator model, named in words.

    ``conserved`` is the quantity a pole at the origin keeps constant, as the weight of each
    state (the largest 1; empty when there is no such pole).
    """

    actuator: str
    poles: np.ndarray
    conserved: dict[str, float] = field(default_factory=dict)

    @property
    def conserved_text(self) -> str:
        """The conserved quantity written out: weight and state name, term by term."""
        text = " ".join(f"{'-' if c < 0 else '+'} {abs(c):.4g} {n}" for n, c in self.conserved.items())
        return text.removeprefix("+ ")

    @property
    def verdict(self) -> str:
        """"stable", "marginal" (rightmost pole on the axis within MARGINAL_TOL) or "unstable"."""
        r = float(np.max(self.poles.real))
        return "stable" if r < -MARGINAL_TOL else ("marginal" if r <= MARGINAL_TOL else "unstable")

    @property
    def stable(self) -> bool:
        """Every pole left of the axis by more than MARGINAL_TOL."""
        return self.verdict == "stable"

    @property
    def worst(self) -> complex:
        """The rightmost pole."""
        return complex(self.poles[np.argmax(self.poles.real)])

    def line(self) -> str:
        """One line for a terminal: the actuator, stable or not, the rightmost pole."""
        w = self.worst
        pole = f"{w.real:+.3f}" + (f" ± {abs(w.imag):.3f}j" if abs(w.imag) > 1e-9 else "")
        verdict = {"stable": "stable", "marginal": "MARGINAL", "unstable": "UNSTABLE"}[self.verdict]
        why = f"; it conserves {self.conserved_text}" if self.conserved else ""
        return f"wired loop with the {self.actuator}: {verdict} (rightmost pole {pole} 1/s{why})"


def linear_loop(net: Netlist, plant: PlantParams, bench: BenchProfile, lagged: bool
                ) -> tuple[np.ndarray, list[str]]:
    """The closed loop of the bench (patchgen.bench.bench_linear) and the wired controller,
    linearised about upright.

    Parameters
    ----------
    net : Netlist
        The patch; its controller is read back as wired (patchgen.patch.readback).
    plant : PlantParams
        The plant's mechanism (eq. 2.28).
    bench : BenchProfile
        The bench: its actuator, its sensors' constants and filters.
    lagged : bool
        With the actuator's lag (False: the ideal actuator, the force following the command).

    Returns
    -------
    (numpy.ndarray, list of str)
        The closed loop's A and its states' names (the bench's, then the wired states).
    """
    law = wired_law(net)
    bp = bench_plant(net, plant, bench, lagged)
    Cy = bp.rows(law.inputs)
    nb, nc = bp.A.shape[0], law.Ac.shape[0]
    A = np.zeros((nb + nc, nb + nc))  # u_c = Cc xc + Dc y
    A[:nb, :nb] = bp.A + bp.B @ (law.Dc @ Cy)
    A[:nb, nb:] = bp.B @ law.Cc
    A[nb:, :nb] = law.Bc @ Cy
    A[nb:, nb:] = law.Ac
    return A, list(bp.states) + list(law.states)


def bench_margins(net: Netlist, plant: PlantParams, bench: BenchProfile) -> Margins:
    """Gain and phase margins of the wired loop on the bench, broken at the command voltage u_c
    (:func:`bench_open_loop`)."""
    return loop_margins(*bench_open_loop(net, plant, bench))


def as_patched_on_bench(design: Design, net: Netlist, machine: MachineProfile, bench: BenchProfile) -> AsPatched:
    """The patch judged as patched (patchgen.patch.as_patched) on the design model and on the
    bench: the wired loop linearised with the bench's actuator, broken at u_c (:func:`bench_open_loop`).

    Parameters
    ----------
    design : Design
        The design the patch realises (its spec gives the plant).
    net : Netlist
        The patch.
    machine, bench : MachineProfile, BenchProfile
        The machine it is on, the bench it meets.

    Returns
    -------
    AsPatched
        With its ``bench`` loop.
    """
    lag = actuator_lag(bench)
    tag = f"actuator lag {lag:g} s" if lag else "actuator without lag"
    loop = figures(f"{bench.id} bench, linearised ({tag})", "as patched",
                   *bench_open_loop(net, design.plant, bench))
    return as_patched(design, net, machine).with_bench(loop)


def bench_open_loop(net: Netlist, plant: PlantParams, bench: BenchProfile) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The wired loop on the bench, broken at the command voltage u_c.

    The loop as the bench closes it, linearised about upright (patchgen.bench.bench_linear: the
    plant with its drive, the actuator's lag, the sensors' filters; the dead zone, limits and
    encoder counts are not linear), the controller read back from the netlist with its pots as
    dialled. Broken where the patch's output drives the actuator, it is L(s) = -u_c(s)/w(s) for a
    command w into the actuator, closed as w = -k L w (patchgen.design.margins.loop_margins), so
    k = 1 is the loop as wired.

    Parameters
    ----------
    net, plant, bench : Netlist, PlantParams, BenchProfile
        The patch, the plant's mechanism and the bench.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        A, B, C of L(s) for patchgen.design.margins.loop_margins.
    """
    law = wired_law(net)
    bp = bench_plant(net, plant, bench)
    Cy = bp.rows(law.inputs)
    nb, nc = bp.A.shape[0], law.Ac.shape[0]
    A, B, C = np.zeros((nb + nc, nb + nc)), np.zeros((nb + nc, 1)), np.zeros((1, nb + nc))
    A[:nb, :nb] = bp.A
    A[nb:, :nb] = law.Bc @ Cy
    A[nb:, nb:] = law.Ac
    B[:nb] = bp.B
    C[0, :nb] = (law.Dc @ Cy)[0]
    C[0, nb:] = law.Cc[0]
    return A, B, -C


def loop_poles(A: np.ndarray, names: list[str], actuator: str) -> LoopPoles:
    """The poles of a closed loop and, for a pole at the origin, the quantity it conserves."""
    lam, W = np.linalg.eig(A.T)  # left eigenvectors of A: w' A = lam w'
    conserved: dict[str, float] = {}
    k = int(np.argmin(np.abs(lam)))
    if abs(lam[k]) <= MARGINAL_TOL:
        w = (W[:, k] / W[np.argmax(np.abs(W[:, k])), k]).real
        conserved = {n: float(c) for c, n in zip(w, names) if abs(c) > NAMED_WEIGHT}
    return LoopPoles(actuator, lam, conserved)


def diagnose(net: Netlist, plant: PlantParams, bench: BenchProfile) -> list[LoopPoles]:
    """The linearised loop with an ideal actuator and, when the bench has one, with its lag:
    why a patch holds on paper and not on the bench.

    Returns
    -------
    list of LoopPoles
        The ideal actuator first, then the bench's (a lag model with tau > 0).
    """
    lag = actuator_lag(bench)
    out = [loop_poles(*linear_loop(net, plant, bench, False), "ideal actuator (pure gain K_U)")]
    if lag:
        out.append(loop_poles(*linear_loop(net, plant, bench, True), f"bench actuator (lag {lag:g} s)"))
    return out
