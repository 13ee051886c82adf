"""The whole swing-up manoeuvre drawn: s, theta and force from hanging to the patched hold, the
hand-off marked (patchgen.swingup.manoeuvre computes it)."""

from __future__ import annotations

import numpy as np

from patchgen.swingup.handoff import wrap_angle
from patchgen.swingup.manoeuvre import Manoeuvre


def plot_manoeuvre(m: Manoeuvre, stem: str, title: str, svg: bool = False) -> dict[str, bytes]:
    """s, theta and force over the whole manoeuvre, the hand-off marked.

    Parameters
    ----------
    m : Manoeuvre
        The manoeuvre.
    stem, title : str
        File name stem and the plot's title.
    svg : bool
        Also a deterministic ``<stem>.svg``.

    Returns
    -------
    dict of str to bytes
        ``<stem>.png`` (and ``<stem>.svg``), for the all-or-nothing writer.
    """
    from patchgen.render import plotting

    p = m.pump
    t0 = p.handoff_time if p.reached else p.t[-1]
    keep = p.t <= t0
    fig, ax = plotting.stacked(8, 7, 3)
    cols = plotting.columns(fig)
    env = lambda t, y: plotting.envelope(t, y, cols)
    ax[0].plot(*env(p.t[keep], p.x[keep, 0]), color="C0", label="pump-up")
    ax[1].plot(*env(p.t[keep], np.degrees(p.x[keep, 1])), color="C0")
    ax[2].plot(*env(p.t[keep], p.u[keep]), color="C0")
    if m.hold is not None:
        h = m.hold.history
        t = h["t"] + t0
        turns = 2 * np.pi * np.round((p.handoff_state[1] - wrap_angle(p.handoff_state[1])) / (2 * np.pi))
        ax[0].plot(*env(t, h["s"]), color="C1", label="patched controller (bench)")
        ax[1].plot(*env(t, np.degrees(h["theta"] + turns)), color="C1")
        ax[2].plot(*env(t, h["force"]), color="C1")
    half = p.plant.d / 2
    for a in ax:
        a.axvline(t0, color="k", lw=0.6, ls=":")
        a.grid(alpha=0.3)
    for v in (-half, half):
        ax[0].axhline(v, color="r", lw=0.6, ls="--")
    ax[0].set_ylabel("s (m)")
    ax[1].set_ylabel("theta (deg, 0 or 360 upright)")
    ax[2].set_ylabel("force (N)")
    ax[2].set_xlabel("t (s)")
    ax[0].legend(loc="upper right", fontsize=8)
    ax[0].set_title(title, fontsize=10)
    return plotting.rendered(fig, stem, svg)
