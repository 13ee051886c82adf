"""ngspice against patchgen's own simulation, at ngspice's own time points: each signal's
difference relative to its peak, and an overlay plot.

ngspice writes its solution at the time points it chose; patchgen's reference (recorded at every
step of its own integrator by ``patchgen spice``) is evaluated there. The plant states s and theta
are interpolated by cubic Hermite with their own derivatives (s_dot, theta_dot, recorded beside
them): the error is at most h^4/384 max|d4y/dt4|, below 1e-6 of the peak at the simulator's 10 ms
ideal step for the loop's motions (up to about 10 rad/s), so what the comparison reports is the
difference between the two circuits, not the interpolation. Other signals are interpolated linearly.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from patchgen.plant.cart_pendulum import RATE_OF, STATE_UNITS


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
DERIVATIVE = RATE_OF
PLOT_POINTS = 2001  # the overlay plot's points (the comparison itself uses every ngspice point)


def compare(spice_result: Trajectory, own_result: Trajectory, names: Sequence[str] = ("theta", "s")) -> Comparison:
    """Measure the RMS and largest difference of each named signal at ngspice's own time points
    (within the span both runs cover), relative to its peak magnitude in ``own_result``.

    Parameters
    ----------
    spice_result : Trajectory
        ngspice's run (its own time points).
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


PLOT_DPI = 120  # the overlay is a small figure: screen resolution is enough
_UNITS = {**{q: (u.replace("rad", "deg"), 180.0 / math.pi) if u.startswith("rad") else (u, 1.0)
             for q, u in STATE_UNITS.items()}, "u_c": ("V", 1.0)}  # plotted: angles in degrees


def comparison_plot(cmp: Comparison, stem: str, title: str = "", own_label: str = "patchgen",
                    svg: bool = False) -> dict[str, bytes]:
    """Overlay plot of each compared signal (ngspice dashed over patchgen's), as ``<stem>.png``
    (and a deterministic ``<stem>.svg`` with ``svg``), file name -> bytes."""
    from patchgen.render import plotting

    names = list(cmp.signals)
    pick = np.unique(np.linspace(0, len(cmp.t) - 1, min(PLOT_POINTS, len(cmp.t))).round().astype(int))
    cmp = Comparison(cmp.t[pick], {k: v[pick] for k, v in cmp.spice.items()},
                     {k: v[pick] for k, v in cmp.own.items()}, cmp.signals)
    height = 2.4 * len(names)
    fig, axes = plotting.stacked(7.0, height, len(names), top_in=0.6 if title else 0.35, left_in=0.85,
                                 hspace=0.35 * 2.4 / 1.9)
    cols = plotting.columns(fig, dpi=PLOT_DPI)
    for ax, name in zip(axes, names):
        unit, scale = _UNITS.get(name, ("", 1.0))
        a = cmp.signals[name]
        ax.plot(*plotting.envelope(cmp.t, cmp.own[name] * scale, cols), color="tab:blue", lw=1.6, label=own_label)
        ax.plot(*plotting.envelope(cmp.t, cmp.spice[name] * scale, cols), color="tab:orange", lw=1.2, ls="--",
                label="ngspice")
        ax.set_ylabel(f"{name} ({unit})" if unit else name)
        ax.set_title(f"{name}: RMS diff {100 * a.rms_rel:.3f} %, max diff {100 * a.max_rel:.3f} % "
                     f"of peak", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time (s)")
    if title:
        fig.suptitle(title, fontsize=10)
    return plotting.rendered(fig, stem, svg, dpi=PLOT_DPI)
