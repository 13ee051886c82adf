"""One fit plot per recording: the measured trace and the fitted one, then what the fit leaves
(residuals or innovations), drawn through patchgen.render.plotting (PNG bytes, no date, the same
bytes every time)."""

from __future__ import annotations

from pathlib import Path

from patchgen.identify.estimate import TestFit
from patchgen.render import plotting

WIDTH_IN, PANEL_IN = 8.0, 2.0
MEASURED, FITTED = "#1f77b4", "#d62728"


def plot_name(source: str, taken: set[str]) -> str:
    """fit-<file stem>.png, numbered when two recordings share a stem."""
    stem = f"fit-{Path(source).stem}"
    name, k = f"{stem}.png", 2
    while name in taken:
        name, k = f"{stem}-{k}.png", k + 1
    taken.add(name)
    return name


def fit_plot(fit: TestFit, stem: str) -> dict[str, bytes]:
    """The fit's panels (:func:`fit_figure`) as ``<stem>.png`` (name -> bytes); nothing for a fit
    without panels."""
    if not fit.panels:
        return {}
    return plotting.rendered(fit_figure(fit), stem)


def fit_figure(fit: TestFit):
    """One panel per fit panel, measured and fitted named in a legend above the panel's right end
    (outside the data: it covers no trace), the recording's name and test above the first, left."""
    n = len(fit.panels)
    height = PANEL_IN * n + 0.6
    fig = plotting.figure(WIDTH_IN, height)
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    fig.subplots_adjust(left=0.1, right=0.98, top=1 - 0.45 / height, bottom=0.5 / height, hspace=0.6)
    cols = plotting.columns(fig)
    for ax, p in zip(axes, fit.panels):
        if p.points:
            ax.plot(p.x, p.measured, ".", color=MEASURED, markersize=3, label="measured")
        else:
            ax.plot(*plotting.envelope(p.x, p.measured, cols), color=MEASURED, linewidth=0.7, label="measured")
        if p.fitted is not None:
            ax.plot(p.x if p.fitted_x is None else p.fitted_x, p.fitted, color=FITTED, linewidth=0.9, label="fitted")
            plotting.legend_above(ax)
        ax.set_ylabel(p.ylabel, fontsize=8)
        ax.set_xlabel(p.xlabel, fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(True, linewidth=0.3, alpha=0.5)
    axes[0].set_title(f"{Path(fit.source).name}: {fit.title or fit.test}", fontsize=9, loc="left")
    return fig
