"""patchgen spice's files and terminal view: the deck (and its noise table), ngspice's data, the
overlay plot and comparison.json from the pipeline's report; the agreement table."""

from __future__ import annotations

from rich.console import Console

from patchgen.pipeline.spice import SpiceJob, SpiceReport
from patchgen.render import plot_helper
from patchgen.render.outputs import json_text
from patchgen.render.spice_plot import comparison_plot
from patchgen.render.terminal import add_row, number, show, table, text
from patchgen.spice.deck import OPAMP_MODEL

STATISTICAL = ("the deck draws its own noise, random-force and drift samples (the same levels, another "
               "realisation), so the runs differ by that; --ideal compares like with like")


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
    files.update(plot_helper.submit(comparison_plot, report.comparison, "overlay", title, "patchgen", svg).result())
    files["comparison.json"] = json_text(report.summary())
    return files


def print_spice(report: SpiceReport, written: list, console: Console | None = None) -> None:
    """The agreement per signal, the verdict, the op-amp model and the files written."""
    console = console or Console()
    job, cmp = report.job, report.comparison
    ideal, tolerance = job.plan.ideal, job.plan.tolerance
    t = table(f"ngspice against patchgen: {job.design.spec.name}, {job.scenario.name}"
              + (" (ideal: noise, drift off; ideal actuator; op-amp macromodels)" if ideal else ""),
              text("signal"), number("peak"), number("RMS difference"), number("largest difference"))
    for k, v in cmp.signals.items():
        add_row(t, k, f"{v.peak:.4g}", f"{100 * v.rms_rel:.3f} % of peak", f"{100 * v.max_rel:.3f} % of peak")
    show(console, t)
    console.print(("[green]agree[/green]" if cmp.agrees(tolerance) else "[red]disagree[/red]")
                  + f" within {100 * tolerance:g} % of peak at {report.compared_at}; "
                  f"ngspice ran {report.run_time_s:.2f} s")
    console.print(f"op-amp model: {OPAMP_MODEL}")
    if not ideal:
        console.print(f"[yellow]not --ideal:[/yellow] {STATISTICAL}")
    console.print("wrote " + ", ".join(str(p) for p in written))
