"""ngspice against patchgen's own simulation, at the points ngspice wrote: each signal's
difference relative to its peak, and an overlay plot.

ngspice writes its solution at the time points it chose or, with noise on, at the output step
(patchgen.spice.deck); patchgen's reference (recorded at every step of its own integrator by
``patchgen spice``) is evaluated there. The plant states s and theta
are interpolated by cubic Hermite with their own derivatives (s_dot, theta_dot, recorded beside
them): the error is at most h^4/384 max|d4y/dt4|, below 1e-6 of the peak at the simulator's 10 ms
ideal step for the loop's motions (up to about 10 rad/s), so what the comparison reports is the
difference between the two circuits, not the interpolation. Other signals are interpolated linearly.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from patchgen.plant.plant_model import PLANT_MODELS


class Trajectory(Protocol):
    """Anything with a time vector and named signals (SpiceResult, patchgen's simulation result)."""

    t: np.ndarray
    signals: Mapping[str, np.ndarray]


@dataclass(frozen=True)
class SignalAgreement:
    """Difference of one signal between two runs, relative to its peak in the reference run."""

    name: str
    peak: float
    rms_diff: float
    max_diff: float

    @property
    def rms_rel(self) -> float:
        """RMS difference as a fraction of the peak (0 for a signal that stays at 0)."""
        return self.rms_diff / self.peak if self.peak > 0 else 0.0

    @property
    def max_rel(self) -> float:
        """Largest difference as a fraction of the peak (0 for a signal that stays at 0)."""
        return self.max_diff / self.peak if self.peak > 0 else 0.0


@dataclass(frozen=True)
class Comparison:
    """ngspice against patchgen's own simulation on a common time grid."""

    t: np.ndarray
    spice: dict[str, np.ndarray]
    own: dict[str, np.ndarray]
    signals: dict[str, SignalAgreement]

    def agrees(self, tolerance: float = 0.01) -> bool:
        """True when every compared signal's peak difference is within ``tolerance`` of its peak."""
        return all(a.max_rel <= tolerance for a in self.signals.values())

    def lines(self) -> list[str]:
        """One line of text per compared signal: its peak and differences in percent of it."""
        return [f"{a.name}: peak {a.peak:.4g}, RMS difference {100 * a.rms_rel:.3f} % of peak, "
                f"largest difference {100 * a.max_rel:.3f} % of peak" for a in self.signals.values()]


# a signal and its time derivative, both recorded by patchgen (for cubic Hermite interpolation)
DERIVATIVE = {k: v for pm in PLANT_MODELS.values() for k, v in pm.rate_of.items()}
PLOT_POINTS = 2001  # the overlay plot's points (the comparison itself uses every ngspice point)


def compare(spice_result: Trajectory, own_result: Trajectory, names: Sequence[str] = ("theta", "s")) -> Comparison:
    """Measure the RMS and largest difference of each named signal at the time points of
    ``spice_result`` (within the span both runs cover), relative to its peak magnitude in
    ``own_result``.

    Parameters
    ----------
    spice_result : Trajectory
        ngspice's run (its own time points, or its solution at the output step).
    own_result : Trajectory
        patchgen's run, interpolated at ngspice's points (cubic Hermite where DERIVATIVE names a
        recorded derivative, else linear).
    names : sequence of str
        The signals compared.

    Returns
    -------
    Comparison
        The time points, both runs' values there and each signal's agreement.
    """
    t_own, keep = np.unique(np.asarray(own_result.t, dtype=float), return_index=True)
    t_sp = np.asarray(spice_result.t, dtype=float)
    inside = (t_sp >= max(t_sp[0], t_own[0])) & (t_sp <= min(t_sp[-1], t_own[-1]))
    t = t_sp[inside]
    spice, own, out = {}, {}, {}
    for name in names:
        a = np.asarray(spice_result.signals[name], dtype=float)[inside]
        y = np.asarray(own_result.signals[name], dtype=float)[keep]
        d = DERIVATIVE.get(name)
        if d in own_result.signals and len(t_own) > 1:
            b = CubicHermiteSpline(t_own, y, np.asarray(own_result.signals[d], dtype=float)[keep])(t)
        else:
            b = np.interp(t, t_own, y)
        diff = a - b
        spice[name], own[name] = a, b
        out[name] = SignalAgreement(name, float(np.max(np.abs(y))), float(np.sqrt(np.mean(diff ** 2))),
                                    float(np.max(np.abs(diff))))
    return Comparison(t, spice, own, out)
