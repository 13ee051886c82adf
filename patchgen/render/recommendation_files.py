"""A recommendation's comparison of its candidates: plain rows (terminal, --json), a Markdown
section, the sheet's 'Why this patch' table, and the files the recommend command writes."""

from __future__ import annotations

import math
from dataclasses import replace

from patchgen.inputs.spec_file import spec_toml
from patchgen.pipeline.recommend import RecommendReport
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.render.bench_sheet import predicted_patch_files
from patchgen.render.outputs import json_text
from patchgen.render.patchfiles import PATCH_FILES
from patchgen.render.sheet import SheetSection
from patchgen.studies.candidate import Recommendation
from patchgen.studies.departures import grouped, value_text
from patchgen.studies.ranking import ROUND_RUNS, TARGET
from patchgen.studies.recommend import CORNER_RUNS, chosen_spec
from patchgen.studies.robust import ALTERNATIVES, WHY_GAINS
from patchgen.studies.worst_case import CONFIRMED, EXACT_RANGES, SCREEN_RUNS

RECOMMENDED_SPEC = "recommended.toml"
RECOMMEND_FILES = PATCH_FILES + ("recommendation.md", "recommendation.json", RECOMMENDED_SPEC)  # what it may write


def table_rows(rec: Recommendation) -> list[dict]:
    """One plain row per candidate, ranked (for the terminal, the sheet and --json)."""
    rows = []
    for i, c in enumerate(rec.ranked, 1):
        m = c.margins
        w = c.weakest
        st = c.bench_study
        rows.append({
            "rank": i if c.simulated else None,
            "realisation": c.label,
            "estimator": c.estimator_detail,
            "bench_loop": c.bench_loop,
            "bench_loop_detail": c.bench_loop_line,
            "decision": c.decision,
            "fraction_ok": c.fraction_ok,
            "weakest_scenario": None if w is None else w.scenario,
            "interval_95": None if w is None else list(w.interval),
            "scenarios": [o.as_dict() for o in c.outcomes],
            "runs": c.runs,
            "lower_gm_db": None if m is None or not m.stable else m.lower_gm_db,
            "upper_gm_db": None if m is None or not m.stable else m.upper_gm_db,
            "pm_deg": c.pm_deg,
            "worst_swing_V": c.worst_swing_V,
            "units": None if c.netlist is None else c.netlist.units,
            "amplifiers": c.amplifiers,
            "pots": c.pots,
            "error": c.error,
            "worst_corner": None if st is None or st.worst_corner is None else st.worst_corner.as_dict(),
            "weakest_parameter": None if st is None or st.weakest_parameter is None else st.weakest_parameter.as_dict(),
            "robust": c.robust_note or None,
            "variant": c.variant or None,
            "departures": [d.as_dict() for d in c.departures],
        })
    return rows


def fmt_figure(x: float | None, fmt: str, none: str = "-") -> str:
    """A figure of the table: ``none`` when there is none, "inf" when infinite."""
    return none if x is None else (fmt.format(x) if math.isfinite(x) else "inf")


def gm_cell(row: dict, sep: str = " / ") -> str:
    """A row's gain limits on the bench, lower then upper, dB ("none" and "inf" when there is no
    limit; "-" when the wired loop is not stable)."""
    if row["pm_deg"] is None and row["lower_gm_db"] is None and row["upper_gm_db"] is None:
        return "-"
    return f"{fmt_figure(row['lower_gm_db'], '{:+.1f}', 'none')}{sep}{fmt_figure(row['upper_gm_db'], '{:+.1f}', 'inf')}"


def held_cell(row: dict) -> str:
    """The weakest scenario's held fraction, its 95 % interval and the scenario."""
    lo, hi = row["interval_95"]
    return f"{row['fraction_ok']:.1%} [{lo:.1%}, {hi:.1%}] {row['weakest_scenario']}"


def corner_cell(row: dict, ranges: dict[str, tuple[float, float]] | None = None) -> str:
    """The held fraction at the worst corner of the bench's ranges, and the weakest parameter's end
    ("-" when the bench states no ranges or the candidate was not run at its corners). Past
    EXACT_RANGES ranges, given them, a value at an end of its range is named by that end ("K_U
    low"), so nine ranges fit a table's cell; the values themselves are in the JSON."""
    w, p = row.get("worst_corner"), row.get("weakest_parameter")
    if w is None:
        return "-"
    short = ranges is not None and len(ranges) > EXACT_RANGES

    def value(k: str, v: float) -> str:
        lo, hi = ranges[k] if short and k in ranges else (None, None)
        return f"{k} {'low' if v == lo else 'high' if v == hi else f'{v:g}'}"

    corner = ", ".join(value(k, v) for k, v in w["values"].items())
    weak = "" if p is None else "; weakest: " + ", ".join(value(k, v) for k, v in p["values"].items())
    return f"{w['held']}/{w['runs']} at {corner}{weak}"


def robust_text(rec: Recommendation) -> str:
    """Which answer to the dead zone and lag the chosen patch uses, and why not the others ("" when
    the bench states no ranges)."""
    if not rec.ranges:
        return ""
    b = rec.best
    if b is not None and b.robust_note:
        used = (f"Against the dead zone and lag, the chosen patch's gains were chosen over the corners of the bench's "
                f"ranges ({WHY_GAINS}): {b.robust_note}.")
    elif b is not None:
        used = ("The chosen patch keeps the spec's gains: they held at the worst corner of the bench's ranges, "
                "so no gains were chosen over the corners.")
    else:
        used = "No candidate held at the worst corner of the bench's ranges."
    return used + " Not used: " + "; ".join(ALTERNATIVES) + "."


def _verdict_words(row: dict) -> str:
    return {"holds": "holds", "fails": "fails", "undecided": "undecided"}[row["decision"]]


def method_text(rec: Recommendation) -> str:
    """How the candidates were judged, in a paragraph."""
    names = ", ".join(f"{sc.name} (seed {rec.seed_of(sc)})" for sc in rec.scenarios)
    return (f"Each realisation that fits the machine was designed, allocated and run on the bench (actuator lag, dead "
            f"zone and limit, sensor noise, random forces on the plant, integrator drift) in every scenario: {names}. "
            f"'held' counts runs where the pendulum stayed up, {rec.spec.plant_model.kept_inside} and every amplifier "
            f"inside the rails for the whole scenario; the table gives the weakest scenario, with its 95 % Wilson "
            f"interval. Runs went in rounds of {ROUND_RUNS} per scenario, up to {rec.max_runs}: a realisation stopped "
            f"once every scenario's interval was above {TARGET:.0%} (holds) or one was below it (fails). A wired loop "
            f"that is not stable on the bench (linearised with its actuator lag and pots as dialled) ranks below every "
            f"stable one and is never chosen; then by holds / undecided / fails, the weakest held fraction (when not "
            f"clearly holding), the wired loop's gain margin on the bench (nearer limit), its phase margin, then "
            f"hardware (units, amplifiers, pots)." + _ranges_text(rec) + _variants_text(rec))


def _variants_text(rec: Recommendation) -> str:
    """Which of the spec's variants were tried, and why ("" when its own realisations sufficed)."""
    if not rec.variants:
        return ""
    left = [f"{n} gave a patch already run" for n in (rec.repeated,) if n]
    left += [f"{n} did not design or fit the machine" for n in (rec.unfit,) if n]
    return (" None of the spec's own realisations held, so its variants were tried, nearest first, each with "
            "every realisation above, stopping after the first tier in which one held: "
            + "; ".join(rec.variants) + ". A variant's realisation is named after its changes, and every field "
            "it changes of the spec is listed with why (its departures)."
            + (" Of the variants' realisations, " + " and ".join(left) + "; those are not listed." if left else ""))


def _ranges_text(rec: Recommendation) -> str:
    """How the bench's ranges entered the ranking ("" when it states none)."""
    if not rec.ranges:
        return ""
    ranges = ", ".join(f"{k} {lo:g} to {hi:g}" for k, (lo, hi) in rec.ranges.items())
    return (f" The bench states ranges ({rec.distribution}: {ranges}): every run drew its bench from them, so "
            f"the held fractions are over that uncertainty. Each stable realisation was also run at the corners "
            f"of the ranges and at each end of each range (the others at the profile's values), {CORNER_RUNS} "
            f"seeds each, in its weakest scenario ({_corners_how(len(rec.ranges))}): the worst corner's held "
            f"fraction ranks right after the verdict, a realisation is chosen only if it held in at least "
            f"{TARGET:.0%} of the runs at its worst corner, and the end held least (ties: the one taking the cart "
            f"furthest) names its weakest parameter. When none holds there, gains chosen over the corners join "
            f"the realisations.")


def _corners_how(k: int) -> str:
    """How the corners of k ranges are run, in words."""
    if k <= EXACT_RANGES:
        return f"every one of the {2 ** k} corners"
    return (f"{k} ranges have {2 ** k} corners, so the worst is searched for: the linearised loop at every corner, "
            f"each end of each range and a descent over the corners screened with {SCREEN_RUNS} seeds, the "
            f"{CONFIRMED} harshest run again with {CORNER_RUNS}; the ends at {SCREEN_RUNS} seeds")


def verdict_text(rec: Recommendation) -> str:
    """One sentence: what was chosen, or why nothing was."""
    best = rec.best
    if best is not None:
        w = best.weakest
        departs = (f" It departs from {rec.spec.name} in " + ", ".join(d.field for d in best.departures) + "."
                   if best.departures else "")
        lo, hi = w.interval
        how = ("holds in every scenario" if best.decision == "holds" else
               f"{best.decision}: its 95 % interval reaches below {TARGET:.0%} (more --runs would decide)")
        st = best.bench_study
        corner = "" if st is None or st.worst_corner is None else (
            f"; at the worst corner of the bench's ranges it held {st.worst_corner.held_text()}")
        return (f"Chosen: {best.label}: wired loop stable on the bench; {how}; its weakest scenario, {w.scenario}, "
                f"held in {w.held} of {w.runs} runs ({w.fraction:.1%}, 95 %: {lo:.1%} to {hi:.1%}){corner}.{departs}")
    n = len(rec.variants)
    tried = "" if not n else " (nor in its one variant tried)" if n == 1 else f" (nor in any of the {n} variants tried)"
    stable = [c for c in rec.ranked if c.simulated and c.bench_loop == "stable"]
    if not stable:
        return (f"None chosen: no realisation that fits the machine has a wired loop stable on the bench{tried} ("
                + "; ".join(f"{c.label}: {c.bench_loop}" for c in rec.ranked if c.simulated and not c.variant)
                + "). Design with the bench's actuator and weights that answer its dead zone, as the shipped "
                "design bench-recommended does.")
    b = stable[0]
    w = b.weakest
    corner = b.corner_fraction
    if corner is not None and corner < TARGET <= w.fraction:  # held on the nominal runs, not at a corner
        return (f"None chosen: the best realisation with a loop stable on the bench{tried}, {b.label}, held in only "
                f"{corner:.1%} of the runs at the worst corner of the bench's ranges (at least {TARGET:.0%} at every "
                "corner is needed).")
    return (f"None chosen: the best realisation with a loop stable on the bench{tried}, {b.label}, held in only "
            f"{w.fraction:.1%} of the runs of {w.scenario} (at least {TARGET:.0%} of every scenario is needed).")


def departures_section(rec: Recommendation) -> SheetSection | None:
    """The chosen patch's departures from the spec, for the sheet, with a banner at its top (None
    when it departs in nothing)."""
    b = rec.best
    if b is None or not b.departures:
        return None
    rows = [[d.field, value_text(d.was), value_text(d.now), d.why] for d in b.departures]
    return SheetSection("Departures from the spec", ["field", rec.spec.name, "this patch", "why"], rows,
                        f"Every field of recommended.toml that differs from {rec.spec.path}, and why.",
                        banner=f"Not {rec.spec.name} as written: this patch departs from it in {len(rows)} "
                               f"field{'s' * (len(rows) > 1)}; see 'Departures from the spec'.")


def departures_markdown(rec: Recommendation) -> str:
    """The chosen patch's departures as a Markdown table ("" when there are none)."""
    sec = departures_section(rec)
    if sec is None:
        return ""
    rows = ("| " + " | ".join(x.replace("|", "\\|") for x in row) + " |\n" for row in sec.rows)
    return (f"\n## {sec.title}\n\n{sec.note}\n\n| " + " | ".join(sec.header) + " |\n|---|---|---|---|\n"
            + "".join(rows))


def table_markdown(rec: Recommendation, reference_V: float) -> str:
    """The comparison as a Markdown section body: why the first row was chosen."""
    corner_col = " worst corner of the bench's ranges |" if rec.ranges else ""
    head = ("| rank | realisation | estimator | wired loop on the bench | verdict | held (weakest scenario, 95 % "
            f"interval) |{corner_col} GM lower / upper (dB) | PM (deg) | worst swing (V) | units / amps / pots |\n"
            "|---|---|---|---|---|---|---|---|---|---|" + "---|" * bool(rec.ranges) + "\n")
    lines = []
    for r in table_rows(rec):
        if r["error"]:
            lines.append(f"| - | {r['realisation']} | {r['estimator']} | | not simulated: {r['error']} | | | | | |"
                         + " |" * bool(rec.ranges))
            continue
        corner = f" {corner_cell(r, rec.ranges)} |" if rec.ranges else ""
        lines.append(
            f"| {r['rank']} | {r['realisation']} | {r['estimator']} | {r['bench_loop']} | {_verdict_words(r)} | "
            f"{held_cell(r)} |{corner} {gm_cell(r)} | {fmt_figure(r['pm_deg'], '{:.1f}')} | "
            f"{r['worst_swing_V']:.2f} of {reference_V:g} | {r['units']} / {r['amplifiers']} / {r['pots']} |")
    names = [sc.name for sc in rec.scenarios]
    per = ("\n\nHeld per scenario (runs held of runs simulated):\n\n| realisation | " + " | ".join(names) + " |\n|---|"
           + "---|" * len(names) + "\n")
    for c in rec.ranked:
        if c.simulated:
            per += f"| {c.label} | " + " | ".join(f"{o.held} / {o.runs}" for o in c.outcomes) + " |\n"
    loops = "\n".join(f"- {c.label}: {c.bench_loop_line}" for c in rec.ranked if c.bench_loop_line)
    robust_words = robust_text(rec)
    return (method_text(rec) + "\n\n" + head + "\n".join(lines) + per + "\nLinearised on the bench:\n\n" + loops
            + (f"\n\n{robust_words}" if robust_words else "") + f"\n\n**{verdict_text(rec)}**\n")


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
    header = ["rank", "realisation", "loop on bench", "verdict", "held (weakest, 95 %)", "GM lower/upper (dB)",
              "PM (deg)", "worst swing (V)", "amps/pots"]
    if rec.ranges:
        header.insert(5, "worst corner of the ranges")
    rows = []
    misfits = []
    for r in table_rows(rec):
        if r["error"]:
            rows.append(["-", r["realisation"], "", "does not fit", "", "", "", "", ""] + [""] * bool(rec.ranges))
            misfits.append(f"{r['realisation']}: {r['error']}")
            continue
        row = [str(r["rank"]), f"{r['realisation']} ({r['estimator']})", r["bench_loop"], _verdict_words(r),
               held_cell(r), gm_cell(r), fmt_figure(r["pm_deg"], "{:.1f}"),
               f"{r['worst_swing_V']:.2f} of {reference_V:g}", f"{r['amplifiers']}/{r['pots']}"]
        if rec.ranges:
            row.insert(5, corner_cell(r, rec.ranges))
        rows.append(row)
    robust_words = robust_text(rec)
    note = (method_text(rec) + " " + verdict_text(rec) + (" " + robust_words if robust_words else "")
            + (" Not fitting: " + "; ".join(misfits) + "." if misfits else ""))
    return SheetSection("Why this patch", header, rows, note)


RESCALED = ("The chosen patch was ranked at its sensor constants; its signals were then scaled for signal-to-noise "
            "(its netlist's notes say which, by how much and why they stopped), and its bench prediction is of "
            "that patch, simulated again.")


def recommendation_files(report: RecommendReport, machine: MachineProfile, bench: BenchProfile) -> dict[str, str]:
    """The files recommend writes: recommendation.md and recommendation.json always; with a
    chosen candidate, its patch files (the bench prediction and 'Why this patch' on its sheet)
    and recommended.toml, its spec.

    Parameters
    ----------
    report : RecommendReport
        The ranked candidates, and the chosen one judged and predicted.
    machine, bench : MachineProfile, BenchProfile
        Those the recommendation was made on.

    Returns
    -------
    dict
        File name -> text.
    """
    rec, best = report.recommendation, report.best
    files: dict[str, str] = {}
    if best is not None:
        why = why_section(rec, machine.reference_V)
        if report.rescaled:
            why = replace(why, note=f"{why.note} {RESCALED}")
        sections = [s for s in (departures_section(rec), why) if s is not None]
        files.update(predicted_patch_files(best.design, machine, bench, best.netlist, report.prediction,
                                           report.judged, sections))
        departs = "".join(f"\n  {line}" for line in grouped(best.departures))
        files[RECOMMENDED_SPEC] = spec_toml(chosen_spec(rec), (
            f"{rec.spec.name}, as patchgen recommend chose it on the {bench.id} bench: {best.label}.\n"
            "Every patchgen command takes this file; see recommendation.md for why."
            + (f"\nIt departs from {rec.spec.name} in:{departs}" if departs else "")))
    files["recommendation.md"] = (f"# Why this patch\n\n{table_markdown(rec, machine.reference_V)}"
                                  + (f"\n{RESCALED}\n" if report.rescaled else "") + departures_markdown(rec))
    files["recommendation.json"] = json_text({
        "spec": rec.spec.name, "bench": bench.id, "machine": machine.id, "rescaled_after_ranking": report.rescaled,
        "scenarios": [{"name": sc.name, "seed": rec.seed_of(sc)} for sc in rec.scenarios],
        "max_runs": rec.max_runs, "target": TARGET, "chosen": None if best is None else best.label,
        "bench_ranges": {k: list(v) for k, v in rec.ranges.items()}, "bench_distribution": rec.distribution,
        "corner_runs": CORNER_RUNS if rec.ranges else None, "robust": robust_text(rec) or None,
        "verdict": verdict_text(rec), "variants": list(rec.variants),
        "departures": [] if best is None else [d.as_dict() for d in best.departures],
        "candidates": table_rows(rec),
        "prediction": None if report.prediction is None else report.prediction.summary()})
    return files
