"""A recommendation's comparison of its candidates: plain rows (terminal, --json), a Markdown
section, the sheet's 'Why this patch' table, and the files the recommend command writes."""

from __future__ import annotations

import json
import math

from patchgen.inputs.scenario import load_scenario
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.render.sheet import SheetSection
from patchgen.studies.bench_sheet import predicted_patch_files
from patchgen.studies.recommend import Recommendation

SHEET_HOLD = "hold-120s"  # the sheet's long hold (patchgen.bench.prediction.STANDARD)


def table_rows(rec: Recommendation) -> list[dict]:
    """One plain row per candidate, ranked (for the terminal, the sheet and --json)."""
    rows = []
    for i, c in enumerate(rec.ranked, 1):
        m = c.design.lqg_margins if c.design is not None else None
        rows.append({
            "rank": i if c.fraction_ok is not None else None,
            "realisation": c.label,
            "estimator": c.estimator_detail,
            "fraction_ok": c.fraction_ok,
            "fraction_fallen": c.fraction_fallen,
            "fraction_tripped": c.fraction_tripped,
            "fraction_overloaded": c.fraction_overloaded,
            "lower_gm_db": None if m is None or not m.stable else m.lower_gm_db,
            "upper_gm_db": None if m is None or not m.stable else m.upper_gm_db,
            "pm_deg": c.pm_deg,
            "loop_stable": None if m is None else m.stable,
            "bench_loop": c.bench_loop,
            "worst_swing_V": c.worst_swing_V,
            "amplifiers": c.amplifiers,
            "pots": c.pots,
            "error": c.error,
        })
    return rows


def fmt_figure(x: float | None, fmt: str, none: str = "-") -> str:
    """A figure of the table: ``none`` when there is none, "inf" when infinite."""
    return none if x is None else (fmt.format(x) if math.isfinite(x) else "inf")


def gm_cell(row: dict, sep: str = " / ") -> str:
    """A row's gain limits, lower then upper, dB ("none" and "inf" when there is no limit)."""
    return f"{fmt_figure(row['lower_gm_db'], '{:+.1f}', 'none')}{sep}{fmt_figure(row['upper_gm_db'], '{:+.1f}', 'inf')}"


def outcome_cells(row: dict) -> list[str]:
    """A simulated row's fractions of runs held, fallen, tripped and overloaded, in percent."""
    return [f"{row[k]:.1%}" for k in ("fraction_ok", "fraction_fallen", "fraction_tripped", "fraction_overloaded")]


def table_markdown(rec: Recommendation, reference_V: float) -> str:
    """The comparison as a Markdown section body: why the first row was chosen."""
    head = ("| rank | realisation | estimator | held (of runs) | fallen | tripped | overloaded | "
            "GM lower / upper (dB) | PM (deg) | worst swing (V) | amps / pots |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in table_rows(rec):
        if r["error"]:
            lines.append(f"| - | {r['realisation']} | {r['estimator']} | not simulated: {r['error']} "
                         "| | | | | | | |")
            continue
        lines.append(
            f"| {r['rank']} | {r['realisation']} | {r['estimator']} | {' | '.join(outcome_cells(r))} | {gm_cell(r)} | "
            f"{fmt_figure(r['pm_deg'], '{:.1f}')} | {r['worst_swing_V']:.2f} of {reference_V:g} | "
            f"{r['amplifiers']} / {r['pots']} |")
    best = rec.best
    intro = (f"Each way of getting theta_dot (and the actuator state) that fits the machine was designed, "
             f"allocated and simulated on the bench ({rec.scenario.name}: {rec.scenario.description}), "
             f"{rec.runs} noise seeds from seed {rec.seed}, with the bench actuator, sensor noise and "
             "integrator drift. 'held' counts runs where the pendulum stayed up, the cart stayed inside "
             "the limit switches and no amplifier left the rails for the whole scenario. A wired loop that is "
             "not stable on the bench (linearised with its actuator lag) ranks below every stable one and is "
             "never chosen; then ranked by runs held, the loop's gain margin (nearer limit), phase margin, "
             "and worst amplifier swing.\n\n")
    tail = (f"\nChosen: **{best.label}**.\n" if best else
            "\nNone chosen: no candidate's wired loop is stable on the bench.\n")
    return intro + head + "\n".join(lines) + "\n" + tail


def why_section(rec: Recommendation, reference_V: float) -> SheetSection:
    """The comparison table for the sheet: why the chosen realisation.

    Parameters
    ----------
    rec : Recommendation
        The ranked candidates.
    reference_V : float
        The machine's reference voltage, for the swing column.

    Returns
    -------
    SheetSection
        One row per candidate, ranked; those that do not fit listed in the note with their error.
    """
    header = ["rank", "realisation", "held", "fallen", "tripped", "overloaded", "GM lower/upper (dB)", "PM (deg)",
              "worst swing (V)", "amps/pots"]
    rows = []
    misfits = []
    for r in table_rows(rec):
        if r["error"]:
            rows.append(["-", r["realisation"], "does not fit", "", "", "", "", "", "", ""])
            misfits.append(f"{r['realisation']}: {r['error']}")
            continue
        rows.append([str(r["rank"]), f"{r['realisation']} ({r['estimator']})", *outcome_cells(r), gm_cell(r),
                     fmt_figure(r["pm_deg"], "{:.1f}"), f"{r['worst_swing_V']:.2f} of {reference_V:g}",
                     f"{r['amplifiers']}/{r['pots']}"])
    note = (f"Bench Monte Carlo: {rec.scenario.name}, {rec.runs} seeds from {rec.seed}, bench actuator, noise and "
            "drift. A wired loop not stable on the bench ranks last and is never chosen; then ranked by runs held "
            "(up, inside the switches, no overload), gain margin, phase margin, worst swing."
            + (" Not fitting: " + "; ".join(misfits) + "." if misfits else ""))
    return SheetSection("Why this patch", header, rows, note)


def recommendation_files(rec: Recommendation, machine: MachineProfile, bench: BenchProfile) -> dict[str, str]:
    """The best candidate's patch files, with the bench prediction and 'Why this patch' on its
    sheet, plus recommendation.md and recommendation.json.

    The sheet's 120 s hold reuses the first runs of the recommendation's Monte Carlo when that ran
    the same scenario from the same seed (run i depends on its seed alone).

    Parameters
    ----------
    rec : Recommendation
        Its best candidate must exist (``rec.best``).
    machine, bench : MachineProfile, BenchProfile
        Those the recommendation was made on.

    Returns
    -------
    dict
        File name -> text.
    """
    best = rec.best
    same_hold = rec.scenario == load_scenario(SHEET_HOLD) and rec.seed == rec.scenario.seed
    done = {SHEET_HOLD: list(best.results)} if same_hold else None
    files = predicted_patch_files(best.design, machine, bench, best.netlist, [why_section(rec, machine.reference_V)],
                                  done=done)
    files["recommendation.md"] = f"# Why this patch\n\n{table_markdown(rec, machine.reference_V)}"
    files["recommendation.json"] = json.dumps({"spec": rec.spec.name, "scenario": rec.scenario.name, "runs": rec.runs,
                                               "seed": rec.seed, "chosen": best.label, "candidates": table_rows(rec)},
                                              indent=2, sort_keys=True, allow_nan=False) + "\n"
    return files
