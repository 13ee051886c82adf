"""Files from a pump-up run: histories CSV, switching table (CSV, Markdown), plot (PNG; SVG on request).

Outputs are deterministic: fixed number formats, and the SVG has a fixed hash salt and no date.
"""

from __future__ import annotations

import csv
import io

import numpy as np

from patchgen.swingup.pumping import SwingUpResult
from patchgen.swingup.strategies import pendulum_energy, upright_energy

TABLE_COLUMNS = ("series", "phase", "phase_name", "force_N", "time_s", "reason")


def _fmt(v) -> str:
    if v is None:
        return ""
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.6g}"
    return str(v)


def patch_sheet_rows(result: SwingUpResult) -> list[list[str]]:
    """The switching table for the patch sheet: header row, then series/phase/force/time rows."""
    rows = [["Series", "Phase", "Force (N)", "Time (s)"]]
    for r in result.table_rows():
        if r["phase"] is None:
            rows.append(["hand-off to linear controller", "", "", f"{r['time_s']:.3f}"])
        else:
            rows.append([str(r["series"]), f"{r['phase']} ({r['phase_name']})", f"{r['force_N']:+.1f}",
                         f"{r['time_s']:.3f}"])
    return rows


def compact_schedule_rows(result: SwingUpResult) -> tuple[list[str], list[list[str]]]:
    """The switching table one series a row (push force and the three switch times), for the sheet."""
    header = ["series", "push (N)", "push at (s)", "reverse at (s)", "coast at (s)"]
    series: dict[int, dict[int, dict]] = {}
    rows: list[list[str]] = []
    for r in result.table_rows():
        if r["phase"] is None:
            continue
        series.setdefault(r["series"], {})[r["phase"]] = r
    for k in sorted(series):
        ph = series[k]
        push = ph.get(1)
        rows.append([str(k), "" if push is None else f"{push['force_N']:+.1f}",
                     *("" if ph.get(i) is None else f"{ph[i]['time_s']:.3f}" for i in (1, 2, 3))])
    if result.handoff_time is not None:
        rows.append(["hand-off", "", f"{result.handoff_time:.3f}", "", ""])
    return header, rows


def switching_table_markdown(result: SwingUpResult) -> str:
    """The switching table as a Markdown table."""
    rows = patch_sheet_rows(result)
    lines = ["| " + " | ".join(rows[0]) + " |", "|" + "---|" * len(rows[0])]
    lines += ["| " + " | ".join(r) + " |" for r in rows[1:]]
    return "\n".join(lines) + "\n"


def output_files(result: SwingUpResult, stem: str = "swingup", svg: bool = False) -> dict[str, bytes]:
    """A pump-up run's files: its history, switching table and plot.

    Parameters
    ----------
    result : SwingUpResult
        The run.
    stem, svg
        As for plot.

    Returns
    -------
    dict of str to bytes
        ``<stem>-history.csv``, ``<stem>-switching.csv`` and ``.md``, ``<stem>.png`` (and
        ``<stem>.svg``), for the all-or-nothing writer.
    """
    E = pendulum_energy(result.plant, result.x.T) / upright_energy(result.plant)
    hist = io.StringIO()
    w = csv.writer(hist, lineterminator="\n")
    w.writerow(["t_s", "s_m", "theta_rad", "s_dot_m_s", "theta_dot_rad_s", "force_N", "E_over_E0", "mode"])
    for i in range(result.t.size):
        w.writerow([f"{result.t[i]:.4f}"] + [f"{v:.6g}" for v in result.x[i]]
                   + [f"{result.u[i]:.6g}", f"{E[i]:.6g}", "hold" if result.holding[i] else "pump"])
    table = io.StringIO()
    w = csv.writer(table, lineterminator="\n")
    w.writerow(TABLE_COLUMNS)
    for r in result.table_rows():
        w.writerow([_fmt(r[c]) for c in TABLE_COLUMNS])
    files = {f"{stem}-history.csv": hist.getvalue().encode(), f"{stem}-switching.csv": table.getvalue().encode(),
             f"{stem}-switching.md": switching_table_markdown(result).encode()}
    files.update(plot(result, stem, svg))
    return files


def plot(result: SwingUpResult, stem: str, svg: bool = False) -> dict[str, bytes]:
    """:func:`pump_figure` as ``<stem>.png`` (and ``<stem>.svg``).

    Parameters
    ----------
    result : SwingUpResult
        The run.
    stem : str
        File name stem.
    svg : bool
        Also ``<stem>.svg``.

    Returns
    -------
    dict of str to bytes
        ``<stem>.png`` (and ``<stem>.svg``).
    """
    from patchgen.render import plotting

    return plotting.rendered(pump_figure(result), stem, svg, salt="patchgen-swingup")


def pump_figure(result: SwingUpResult):
    """States, force and energy against time, every line named in a legend above its panel: the
    limit switches, the hand-off, the upright pendulum's energy. theta as plotting.THETA_LABEL."""
    from patchgen.render import plotting

    t, x = result.t, result.x
    fig, ax = plotting.stacked(8, 10, 5, top_in=0.6, left_in=1.0, hspace=0.3)
    cols = plotting.columns(fig)
    env = lambda y: plotting.envelope(t, y, cols)
    half = result.plant.d / 2.0
    ax[0].plot(*env(x[:, 0]), color="C0", label="_s")
    for k, y in enumerate((-half, half)):
        ax[0].axhline(y, color="k", lw=0.8, ls="--", label="_" if k else f"limit switches ±{half:.3g} m")
    ax[0].set_ylabel("s (m)")
    ax[1].plot(*plotting.envelope(*plotting.theta_degrees(t, x[:, 1]), cols), color="C1", label="_theta")
    ax[1].set_ylabel(plotting.THETA_LABEL)
    plotting.full_circle(ax[1])
    ax[2].plot(*env(x[:, 2]), color="C2", label="s_dot (m/s)")
    ax[2].plot(*env(x[:, 3]), color="C3", label="theta_dot (rad/s)")
    ax[2].set_ylabel("rates")
    ax[3].step(*env(result.u), where="post", color="C4", label="_force")
    ax[3].set_ylabel("force (N)")
    ax[4].plot(*env(pendulum_energy(result.plant, x.T) / upright_energy(result.plant)), color="C5", label="_E")
    ax[4].axhline(1.0, color="k", lw=0.8, ls=":", label="upright at rest (E = E0)")
    ax[4].set_ylabel("E / E0")
    ax[4].set_xlabel("t (s)")
    for a in ax:
        if result.handoff_time is not None:
            a.axvline(result.handoff_time, color="k", lw=0.8, label=f"hand-off {result.handoff_time:.3f} s")
        plotting.legend_above(a, fontsize=8)
    title = f"pump-up ({result.strategy}), force limit {result.force_limit:g} N"
    if result.handoff_time is not None:
        title += f": hand-off at {result.handoff_time:.3f} s"
    fig.suptitle(title, y=1 - 0.12 / fig.get_figheight())
    return fig
