"""patchgen spice's files and terminal view: the deck (and its noise table), ngspice's data, the
overlay plot and comparison.json from the pipeline's report; the agreement table and, with noise,
the statistical verdict's figures beside the Monte Carlo's envelope."""

from __future__ import annotations

from rich.console import Console

from patchgen.pipeline.spice import SpiceJob, SpiceReport
from patchgen.render import plot_helper
from patchgen.render.outputs import json_text
from patchgen.render.spice_plot import comparison_plot
from patchgen.render.terminal import add_row, number, show, table, text
from patchgen.spice.deck import OPAMP_MODEL
from patchgen.spice.verdict import FIGURE_TEXT, StatisticalVerdict, method_text

STATISTICAL = ("the deck draws its own noise, random-force and drift samples (the same levels, another "
               "realisation): the verdict is statistical and the differences from the Monte Carlo's first run "
               "above are information only; --ideal compares like with like, point by point")


def deck_files(job: SpiceJob) -> dict[str, str | bytes]:
    """The deck and the files it reads (written even where ngspice is missing)."""
    return {"patch.cir": job.deck.text, **job.deck.files}


def spice_files(report: SpiceReport, svg: bool) -> dict[str, str | bytes]:
    """Every file of the command: the deck, ngspice's data, the overlay plot, comparison.json."""
    job = report.job
    files = deck_files(job)
    if report.data is not None:
        files["patch.data"] = report.data
    title = f"{job.design.spec.name}: ngspice vs patchgen ({job.scenario.name}{', ideal' if job.plan.ideal else ''})"
    note, own = "", "patchgen"
    if report.statistical is not None:
        title += "\n" + _verdict_text(report.statistical)
        note, own = " (information only)", "patchgen, Monte Carlo run 0"
    files.update(plot_helper.submit(comparison_plot, report.comparison, "overlay", title, own, svg,
                                    note).result())
    files["comparison.json"] = json_text(report.summary())
    return files


def _verdict_text(v: StatisticalVerdict) -> str:
    """The statistical verdict and each figure beside its envelope, a line each (the plot's title)."""
    held = "held" if v.held else "did not hold"
    head = (f"statistical verdict: {'agree' if v.agrees else 'disagree'}; ngspice {held},"
            f" Monte Carlo held {100 * v.fraction_held:.0f} % of {v.runs}")
    return "\n".join([head] + [f"{FIGURE_TEXT[e.name]}: ngspice {e.value:.4g}, envelope [{e.low:.4g}, {e.high:.4g}]"
                                for e in v.envelopes.values()])


def print_statistical(v: StatisticalVerdict, console: Console) -> None:
    """Each figure of ngspice's run beside the Monte Carlo's percentiles and envelope, the held
    outcomes and the statistical verdict with its reasons."""
    t = table(f"ngspice's run against patchgen's Monte Carlo ({v.runs} runs)", text("figure"), number("ngspice"),
              number("MC 5 %"), number("MC 50 %"), number("MC 95 %"), text("envelope"), text("inside"))
    for e in v.envelopes.values():
        add_row(t, FIGURE_TEXT[e.name], f"{e.value:.4g}", f"{e.p5:.4g}", f"{e.p50:.4g}", f"{e.p95:.4g}",
                f"[{e.low:.4g}, {e.high:.4g}]", "yes" if e.inside else "no")
    show(console, t)
    console.print(f"held: ngspice {'yes' if v.held else 'no'}, Monte Carlo {100 * v.fraction_held:.1f} % of runs")
    console.print(("[green]agree[/green]" if v.agrees else "[red]disagree[/red]")
                  + f" (statistical verdict: {method_text()})")
    for reason in v.reasons():
        console.print(f"  {reason}")


def print_spice(report: SpiceReport, written: list, console: Console | None = None) -> None:
    """The agreement per signal, the verdict (with noise: the statistical one, the per-signal
    differences as information), the op-amp model and the files written."""
    console = console or Console()
    job, cmp = report.job, report.comparison
    ideal, tolerance = job.plan.ideal, job.plan.tolerance
    t = table(f"ngspice against patchgen: {job.design.spec.name}, {job.scenario.name}"
              + (" (ideal: noise, drift off; ideal actuator; op-amp macromodels)" if ideal else ""),
              text("signal"), number("peak"), number("RMS difference"), number("largest difference"))
    for k, v in cmp.signals.items():
        add_row(t, k, f"{v.peak:.4g}", f"{100 * v.rms_rel:.3f} % of peak", f"{100 * v.max_rel:.3f} % of peak")
    show(console, t)
    if report.statistical is None:
        console.print(("[green]agree[/green]" if cmp.agrees(tolerance) else "[red]disagree[/red]")
                      + f" within {100 * tolerance:g} % of peak at {report.compared_at}; "
                      f"ngspice ran {report.run_time_s:.2f} s")
    else:
        console.print(f"differences from the Monte Carlo's run 0 at {report.compared_at} (information only); "
                      f"ngspice ran {report.run_time_s:.2f} s")
        print_statistical(report.statistical, console)
    console.print(f"op-amp model: {OPAMP_MODEL}")
    if not ideal:
        console.print(f"[yellow]not --ideal:[/yellow] {STATISTICAL}")
    console.print("wrote " + ", ".join(str(p) for p in written))
