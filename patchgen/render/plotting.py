"""Plots as a screen or a page shows them: at most two points per pixel column, PNG by default.

A 120 s history has 12,001 samples per trace; a plot 8 inches wide at 100 dpi has 800 pixel
columns. :func:`envelope` keeps, of each column's samples, the smallest and the largest (in time
order), so the line drawn through them covers every pixel the full trace would, spikes included,
at an eighth of the points. :func:`save` writes the PNG, and the SVG copy only when asked for.
matplotlib is imported here, by the commands that plot, never at start-up.
"""

from __future__ import annotations

import numpy as np

PNG_DPI = 100
SVG_RC = {"svg.fonttype": "path"}  # glyphs as paths: the same bytes on every machine
LEGEND_PT = 7  # a legend's text, points
# theta, in every plot: degrees wrapped to -180..180, 0 upright (+/-180 hanging), as the axis says
THETA_LABEL = "theta (deg)\n±180, 0 upright"


def columns(fig, dpi: float = PNG_DPI) -> int:
    """Pixel columns across the figure at ``dpi``."""
    return int(round(fig.get_figwidth() * dpi))


def envelope(t: np.ndarray, y: np.ndarray, cols: int) -> tuple[np.ndarray, np.ndarray]:
    """(t, y) reduced to the first and last sample and, of each of ``cols`` runs of consecutive
    samples, the smallest and the largest, in time order. Short traces are returned as they are."""
    t, y = np.asarray(t), np.asarray(y)
    n = y.size
    if n <= 2 * cols:
        return t, y
    per = -(-n // cols)  # samples per column, the last column padded with the last sample
    cols = -(-n // per)
    blocks = np.concatenate([y, np.full(per * cols - n, y[-1])]).reshape(cols, per)
    start = np.arange(cols) * per
    ok = np.isfinite(blocks)  # a NaN or inf sample is kept as it is (a gap or a clip in the line)
    keep = np.concatenate([[0, n - 1], start + np.where(ok, blocks, np.inf).argmin(axis=1),
                           start + np.where(ok, blocks, -np.inf).argmax(axis=1), np.flatnonzero(~np.isfinite(y))])
    idx = np.unique(np.minimum(keep, n - 1))
    return t[idx], y[idx]


def figure(width_in: float, height_in: float):
    """A matplotlib Figure on the Agg canvas (no pyplot, no global state)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width_in, height_in))


def stacked(width_in: float, height_in: float, n: int, top_in: float = 0.4, bottom_in: float = 0.45,
            left_in: float = 0.8, right_in: float = 0.15, hspace: float = 0.25):
    """A figure of ``n`` panels one above the other sharing the time axis, with fixed margins in
    inches (a layout engine would draw the figure several times to find them). Returns (fig, axes)."""
    fig = figure(width_in, height_in)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    fig.subplots_adjust(left=left_in / width_in, right=1 - right_in / width_in, top=1 - top_in / height_in,
                        bottom=bottom_in / height_in, hspace=hspace)
    return fig, axes


def legend_above(ax, fontsize: float = LEGEND_PT):
    """The axes' labelled lines named in one row just above its top right corner: outside the
    data, so the legend covers no curve (``loc="best"`` still may, on a busy panel). Nothing when
    no line is labelled. Returns the legend (or None)."""
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return None
    return ax.legend(handles, labels, loc="lower right", bbox_to_anchor=(1.0, 1.0), ncols=len(handles),
                     fontsize=fontsize, frameon=False, borderaxespad=0.15, handlelength=1.8, columnspacing=1.2)


def theta_degrees(t: np.ndarray, theta_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """theta as :data:`THETA_LABEL` says, in degrees wrapped to -180..180 (0 upright), with a gap
    (NaN) where it wraps, so no line is drawn across the plot from +180 to -180."""
    t = np.asarray(t, dtype=float)
    deg = (np.degrees(np.asarray(theta_rad, dtype=float)) + 180.0) % 360.0 - 180.0
    jumps = np.flatnonzero(np.abs(np.diff(deg)) > 180.0) + 1
    return np.insert(t, jumps, (t[jumps - 1] + t[jumps]) / 2), np.insert(deg, jumps, np.nan)


def full_circle(ax) -> None:
    """A theta axis over the whole circle: -180 to 180 degrees, ticks every 90."""
    ax.set_ylim(-195.0, 195.0)
    ax.set_yticks([-180, -90, 0, 90, 180])


def rendered(fig, stem: str, svg: bool = False, dpi: float = PNG_DPI, salt: str = "patchgen") -> dict[str, bytes]:
    """The figure as ``<stem>.png`` (no software tag) and, with ``svg``, as a deterministic
    ``<stem>.svg`` (glyphs as paths, fixed hash salt, no date), as file name -> bytes for the
    all-or-nothing writer (patchgen.render.outputs)."""
    import io

    import matplotlib

    png = io.BytesIO()
    fig.savefig(png, format="png", dpi=dpi, metadata={"Software": None})
    files = {f"{stem}.png": png.getvalue()}
    if svg:
        text = io.BytesIO()
        with matplotlib.rc_context({**SVG_RC, "svg.hashsalt": salt}):
            fig.savefig(text, format="svg", metadata={"Date": None, "Creator": None})
        files[f"{stem}.svg"] = text.getvalue()
    return files
