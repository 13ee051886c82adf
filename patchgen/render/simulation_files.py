"""A simulation's files, rendered to bytes for the all-or-nothing writer
(patchgen.render.outputs.write_files): history.csv (first run), runs.csv (one line per run),
summary.json (sorted keys) and the history.png plot (and history.svg), every line in it named.
The same result gives the same bytes. The plot is drawn in the plot helper process when one was started
(patchgen.render.plot_helper), while this one writes the tables."""

from __future__ import annotations

import csv
import io
import math

import numpy as np

from patchgen.bench.results import SimResult
from patchgen.plant.plant_model import CART, PLANT_MODELS, PlantModel
from patchgen.render import plot_helper
from patchgen.render.outputs import json_text

FONT_SIZE = 8  # points: the plot's text, small enough for a panel 1.5 inches high


def _units(pm: PlantModel) -> dict[str, str]:
    """A history column name's unit, by channel (the amplifiers' are volts)."""
    units = {"t": "s", **{q: u.replace("/", "_per_") for q, u in pm.units.items()},
             f"{pm.position}_ref": pm.units[pm.position], "u_c": "V"}
    units["force" if pm is CART else pm.input] = pm.input_unit
    return units


def output_files(result: SimResult, svg: bool = False, summary: dict | None = None) -> dict[str, bytes]:
    """The simulation's files by name, in the order they are listed.

    Parameters
    ----------
    result : SimResult
        The simulation; without a history, only runs.csv and summary.json.
    svg : bool
        Also history.svg (PNG only by default).
    summary : dict, optional
        summary.json's content when a command's report says more than the runs (its linear
        verdicts, the corners of the bench's ranges); default: the runs' own summary.

    Returns
    -------
    dict of str to bytes
        history.csv, runs.csv, summary.json, history.png, history.svg, those there are.
    """
    plot = plot_helper.submit(_plot, result, svg) if result.history is not None else None
    files = {}
    if result.history is not None:
        files["history.csv"] = _history_csv(result.history, PLANT_MODELS[result.settings.plant]).encode()
    files["runs.csv"] = _runs_csv(result).encode()
    files["summary.json"] = json_text(result.summary() if summary is None else summary).encode()
    if plot is not None:
        files.update(plot.result())
    return files


def _history_csv(history: dict[str, np.ndarray], pm: PlantModel = CART) -> str:
    """The history's channels as columns, named with their units."""
    names = list(history)
    units = _units(pm)
    header = [f"{n}_{units.get(n, 'V')}" for n in names]
    cols = np.column_stack([history[n] for n in names])
    buf = io.StringIO()
    buf.write(",".join(header) + "\n")
    if np.isnan(cols).any():
        for row in cols:
            buf.write(",".join(_num(v) for v in row) + "\n")
    else:  # one %-format per row: the same text as _num, four times faster
        line = ",".join(["%.9g"] * len(names)) + "\n"
        buf.writelines(line % tuple(row) for row in cols.tolist())
    return buf.getvalue()


def _runs_csv(result: SimResult) -> str:
    """One line per run: held, trip and fall times, maxima, RMS theta, overloads, and what the run
    drew (plant parameters with --spread, the bench's ranges with --bench-spread)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    drawn = [name for name, _ in result.runs[0].drawn] if result.runs else []
    pm = PLANT_MODELS[result.settings.plant]
    position = "s_m" if pm is CART else f"{pm.position}_{pm.units[pm.position]}"
    drive = "force_N" if pm is CART else f"{pm.input}_{pm.input_unit}"
    w.writerow(["run", "held", "limit_switch_tripped", "trip_time_s", "fallen",
                "fall_time_s", "max_abs_theta_deg", f"max_abs_{position}", "rms_theta_deg",
                "max_abs_u_c_V", f"max_abs_{drive}", "overloads", "actuator_limit_time_s"]
               + [f"drawn {n}" for n in drawn])
    for r in result.runs:
        w.writerow([r.run, int(r.held), int(r.limit_switch_tripped), _num(r.trip_time_s),
                    int(r.fallen), _num(r.fall_time_s), _num(r.max_abs_theta_deg),
                    _num(r.max_abs_s_m), _num(r.rms_theta_deg), _num(r.max_abs_u_c_V),
                    _num(r.max_abs_force_N),
                    " ".join(f"{o.amplifier}@{_num(o.first_time_s)}" for o in r.overloads),
                    _num(r.actuator_limit_time_s)]
                   + [_num(v) for _, v in r.drawn])
    return buf.getvalue()


def _num(v: float | None) -> str:
    return "" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.9g}"


def _plot(result: SimResult, svg: bool = False) -> dict[str, bytes]:
    """history.png (and history.svg) by name: :func:`history_figure` rendered."""
    import matplotlib

    from patchgen.render import plotting

    with matplotlib.rc_context({"font.size": FONT_SIZE}):
        return plotting.rendered(history_figure(result), "history", svg)


def _amp_label(result: SimResult, amp: str) -> str:
    """An amplifier's panel label: its id and the signal it carries (``A5: −dθ/dt (V)``)."""
    from patchgen.render.diagram_symbols import signed_label  # the diagram's names (loads schemdraw)

    if amp not in result.carries:
        return f"{amp} (V)"
    polarity, quantity = result.carries[amp]
    return f"{amp}: {signed_label(polarity, quantity)} (V)"


def history_figure(result: SimResult):
    """The first run's histories, a panel each, every line named: u_c shares the panel of the
    amplifier that makes it (the same trace); each amplifier's panel says the signal it carries;
    the rails, the limit switch's trip and the fall are named in each panel's legend, above it
    (outside the data). Draw inside a ``matplotlib.rc_context`` for the font size."""
    from patchgen.render import plotting

    h = result.history
    t = h["t"]
    first = result.runs[0]
    sat = result.settings.saturation_V
    out_amp = [a for a in result.amplifiers if np.array_equal(h[a], h["u_c"])][:1]
    pm = PLANT_MODELS[result.settings.plant]
    pos, ref, drive = pm.position, f"{pm.position}_ref", "force" if pm is CART else pm.input
    event = "limit switch" if pm is CART else pm.limit_event
    panels = [(f"{pos} ({pm.units[pos]})", [(pos, h[pos]), (ref, h[ref])], None),
              (plotting.THETA_LABEL, [("theta", h["theta"])], None),
              (f"u_c = {out_amp[0]} (V)" if out_amp else "u_c (V)", [("u_c", h["u_c"])], sat if out_amp else None),
              (f"{drive} ({pm.input_unit})", [(drive, h[drive])], None)]
    panels += [(_amp_label(result, a), [(a, h[a])], sat) for a in result.amplifiers if a not in out_amp]
    fig, axes = plotting.stacked(8.0, 1.5 * len(panels) + 0.8, len(panels), top_in=0.65)
    cols = plotting.columns(fig)
    for ax, (label, lines, rail) in zip(axes, panels):
        for name, y in lines:
            tt, yy = plotting.theta_degrees(t, y) if name == "theta" else (t, y)
            ax.plot(*plotting.envelope(tt, yy, cols), lw=0.8, label=name if len(lines) > 1 else "_" + name)
        if rail is not None:
            ax.axhline(rail, color="tab:red", lw=0.6, ls="--", label=f"rails ±{rail:g} V")
            ax.axhline(-rail, color="tab:red", lw=0.6, ls="--")
        if first.trip_time_s is not None:
            ax.axvline(first.trip_time_s, color="black", lw=0.6, ls=":",
                       label=f"{event} {first.trip_time_s:.2f} s")
        if first.fall_time_s is not None:
            ax.axvline(first.fall_time_s, color="tab:purple", lw=0.6, ls=":", label=f"fallen {first.fall_time_s:.2f} s")
        ax.set_ylabel(label)
        ax.grid(True, lw=0.3)
        plotting.legend_above(ax)
    axes[-1].set_xlabel("t (s)")
    mode = "ideal" if result.ideal else f"bench {result.bench}"
    events = []
    if first.trip_time_s is not None:
        events.append(f"{event} at {first.trip_time_s:.2f} s")
    if first.fall_time_s is not None:
        events.append(f"fallen at {first.fall_time_s:.2f} s")
    fig.suptitle(f"{result.design} / {result.scenario.name} / {mode} / seed {result.seed}: "
                 + (", ".join(events) if events else "held"), y=1 - 0.12 / fig.get_figheight())
    return fig
