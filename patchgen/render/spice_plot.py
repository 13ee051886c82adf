"""ngspice's run over patchgen's drawn (patchgen.spice.compare computes the agreement)."""

from __future__ import annotations

import math

import numpy as np

from patchgen.plant.cart_pendulum import ANGLE, STATE_UNITS
from patchgen.spice.compare import PLOT_POINTS, Comparison

PLOT_DPI = 120  # the overlay is a small figure: screen resolution is enough
_UNITS = {**{q: (u.replace("rad", "deg"), 180.0 / math.pi) if u.startswith("rad") else (u, 1.0)
             for q, u in STATE_UNITS.items()}, "u_c": ("V", 1.0)}  # plotted: angles in degrees


def comparison_plot(cmp: Comparison, stem: str, title: str = "", own_label: str = "patchgen",
                    svg: bool = False, panel_note: str = "") -> dict[str, bytes]:
    """Overlay plot of each compared signal (ngspice dashed over patchgen's), as ``<stem>.png``
    (and a deterministic ``<stem>.svg`` with ``svg``), file name -> bytes. ``title`` may run over
    several lines; ``panel_note`` ends each panel's line of differences."""
    from patchgen.render import plotting

    names = list(cmp.signals)
    pick = np.unique(np.linspace(0, len(cmp.t) - 1, min(PLOT_POINTS, len(cmp.t))).round().astype(int))
    cmp = Comparison(cmp.t[pick], {k: v[pick] for k, v in cmp.spice.items()},
                     {k: v[pick] for k, v in cmp.own.items()}, cmp.signals)
    height = 2.4 * len(names)
    top = 0.35 + 0.25 * (title.count("\n") + 1) if title else 0.35  # a quarter inch a title line
    fig, axes = plotting.stacked(7.0, height, len(names), top_in=top, left_in=0.85,
                                 hspace=0.35 * 2.4 / 1.9)
    cols = plotting.columns(fig, dpi=PLOT_DPI)
    for ax, name in zip(axes, names):
        unit, scale = _UNITS.get(name, ("", 1.0))
        a = cmp.signals[name]
        for run, label, style in ((cmp.own, own_label, dict(color="tab:blue", lw=1.6)),
                                  (cmp.spice, "ngspice", dict(color="tab:orange", lw=1.2, ls="--"))):
            if name == ANGLE:
                ax.plot(*plotting.envelope(*plotting.theta_degrees(cmp.t, run[name]), cols), label=label, **style)
            else:
                ax.plot(*plotting.envelope(cmp.t, run[name] * scale, cols), label=label, **style)
        ax.set_ylabel(plotting.THETA_LABEL if name == ANGLE else f"{name} ({unit})" if unit else name)
        ax.set_title(f"{name}: RMS diff {100 * a.rms_rel:.3f} %, max diff {100 * a.max_rel:.3f} % "
                     f"of peak{panel_note}", fontsize=9, loc="left")
        ax.grid(True, alpha=0.3)
        plotting.legend_above(ax, fontsize=8)
    axes[-1].set_xlabel("time (s)")
    if title:
        fig.suptitle(title, fontsize=10)
    return plotting.rendered(fig, stem, svg, dpi=PLOT_DPI)
