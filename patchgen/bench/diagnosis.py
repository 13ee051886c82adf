"""Why a patch holds or not: the wired loop linearised about upright, with the bench's actuator
(its lag) and with the ideal actuator the design may have assumed. The dead zone and the limits
are not linear; the simulation shows them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from patchgen.patch.netlist import Netlist
from patchgen.patch.readback import wired_law
from patchgen.plant.equations import PlantParams, linear_matrices
from patchgen.profiles.bench import BenchProfile


@dataclass(frozen=True)
class LoopPoles:
    """The closed-loop poles (1/s) of the wired loop with one actuator model, named in words."""

    actuator: str
    poles: np.ndarray

    @property
    def stable(self) -> bool:
        """Every pole in the open left half-plane."""
        return bool(np.max(self.poles.real) < 0)

    @property
    def worst(self) -> complex:
        """The rightmost pole."""
        return complex(self.poles[np.argmax(self.poles.real)])

    def line(self) -> str:
        """One line for a terminal: the actuator, stable or not, the rightmost pole."""
        w = self.worst
        pole = f"{w.real:+.3f}" + (f" ± {abs(w.imag):.3f}j" if abs(w.imag) > 1e-9 else "")
        verdict = "stable" if self.stable else "UNSTABLE"
        return f"wired loop with the {self.actuator}: {verdict} (rightmost pole {pole} 1/s)"


def linear_loop_poles(net: Netlist, plant: PlantParams, K_U: float, tau: float | None) -> np.ndarray:
    """Closed-loop poles of plant + wired controller + actuator, linearised about upright.

    Parameters
    ----------
    net : Netlist
        The patch; its controller is read back as wired (patchgen.patch.readback).
    plant : PlantParams
        The plant (eq. 2.28).
    K_U : float
        The actuator's gain (N/V).
    tau : float or None
        The actuator's lag (s); None for a pure gain.

    Returns
    -------
    numpy.ndarray
        The poles (1/s), complex.
    """
    law = wired_law(net)
    Ap, Bp = linear_matrices(plant)
    ks = np.zeros((len(law.inputs), 4))
    names = ["s", "theta", "s_dot", "theta_dot"]
    for r, sid in enumerate(law.inputs):
        sensor = next(s for s in net.sensors if s.id == sid)
        ks[r, names.index(sensor.quantity)] = sensor.volts_per_unit
    nc = law.Ac.shape[0]
    # u_c = Cc xc + Dc ks x
    if tau is None:
        A = np.zeros((4 + nc, 4 + nc))
        A[:4, :4] = Ap + Bp @ (K_U * law.Dc @ ks)
        A[:4, 4:] = Bp @ (K_U * law.Cc)
        A[4:, :4] = law.Bc @ ks
        A[4:, 4:] = law.Ac
    else:
        A = np.zeros((5 + nc, 5 + nc))
        A[:4, :4] = Ap
        A[:4, 4:5] = Bp
        A[4, :4] = (K_U * law.Dc @ ks)[0] / tau
        A[4, 4] = -1.0 / tau
        A[4, 5:] = (K_U * law.Cc)[0] / tau
        A[5:, :4] = law.Bc @ ks
        A[5:, 5:] = law.Ac
    return np.linalg.eigvals(A)


def diagnose(net: Netlist, plant: PlantParams, bench: BenchProfile) -> list[LoopPoles]:
    """The linearised loop with an ideal actuator and, when the bench has one, with its lag:
    why a patch holds on paper and not on the bench.

    Returns
    -------
    list of LoopPoles
        The ideal actuator first, then the bench's (a lag model with tau > 0).
    """
    act = bench.actuator
    out = [LoopPoles("ideal actuator (pure gain K_U)", linear_loop_poles(net, plant, act.K_U, None))]
    if act.model != "gain" and act.tau > 0:
        out.append(LoopPoles(f"bench actuator (lag {act.tau:g} s)", linear_loop_poles(net, plant, act.K_U, act.tau)))
    return out
