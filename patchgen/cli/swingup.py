"""`patchgen swingup SPEC -o DIR`: pump up from hanging, hand off to the patched controller, hold."""

from __future__ import annotations

import click
from rich.console import Console
from rich.table import Table

from patchgen.pipeline.swingup import SwingupPlan, run_swingup
from patchgen.render import plot_helper
from patchgen.render.bench_sheet import predicted_patch_files
from patchgen.render.manoeuvre_plot import plot_manoeuvre
from patchgen.render.outputs import check_out_dir, json_text, write_files
from patchgen.render.patchfiles import PATCH_FILES
from patchgen.render.sheet import SheetSection
from patchgen.render.swingup_files import compact_schedule_rows, output_files, patch_sheet_rows
from patchgen.swingup.manoeuvre import BENCH_HOLD_S
from patchgen.swingup.strategies import STRATEGIES

from . import cli
from .inputs import load_inputs
from .options import SEED, FiniteFloat, out_option

SWINGUP_FILES = PATCH_FILES + ("swingup-history.csv", "swingup-switching.csv", "swingup-switching.md", "swingup.png",
                               "swingup.svg", "manoeuvre.png", "manoeuvre.svg", "manoeuvre.json")
SHEET_HOLD_RUNS = 10  # seeds of the sheet's 120 s hold: fewer than patchgen patch's, as the manoeuvre runs too


@cli.command("swingup")
@click.argument("spec")
@out_option("the manoeuvre's histories, switching table, plots and the patch with the schedule")
@click.option("--strategy", type=click.Choice(STRATEGIES), default="supervisory", show_default=True,
              help="supervisory: section 3.3's three-phase logic on measured states; schedule: optimised "
              "open-loop switching times; energy: Astrom-Furuta energy control.")
@click.option("--force-limit", type=FiniteFloat(0.1, 1000), default=None,
              help="Largest force (N) for the pump-up (default: the bench actuator's limit).")
@click.option("--hold", "hold_s", type=FiniteFloat(0.1, 3600), default=BENCH_HOLD_S, show_default=True,
              help="Seconds the patched controller must hold after the hand-off (at most an hour).")
@click.option("--seed", type=SEED, default=0, show_default=True, help="Noise seed of the hold.")
@click.option("--compare", is_flag=True, help="Also compare the three strategies (time to the zone, cart "
              "excursion, success on plants off by +/-10%); takes about a minute.")
@click.option("--svg", is_flag=True, help="Also write the plots as SVG (PNG only by default).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--force", is_flag=True, help="Replace output files that already exist.")
def swingup_cmd(spec, out_dir, strategy, force_limit, hold_s, seed, compare, svg, as_json, force) -> None:
    """Pump SPEC's pendulum up from hanging at rest, hand it to the patched controller when the state
    enters the zone of the linear design, and hold it on the bench (actuator lag and dead zone,
    noise, drift)."""
    check_out_dir(out_dir, SWINGUP_FILES, force)
    plot_helper.start()  # matplotlib loads on the other core while this one computes
    sp, machine, bench = load_inputs(spec)
    plan = SwingupPlan(strategy=strategy, force_limit_N=force_limit, hold_s=hold_s, seed=seed, compare=compare)
    report = run_swingup(sp, machine, bench, plan, comparing=lambda: Console(stderr=True).status(
        "comparing the three strategies on the nominal and +/-10% plants"))
    d, net, plant, m, F = report.design, report.netlist, report.plant, report.manoeuvre, report.force_limit_N
    p = m.pump
    rows = patch_sheet_rows(p)
    section = SheetSection(f"Pump-up schedule ({strategy}, {F:g} N)", *compact_schedule_rows(p),
                           "Switch times for the operator or a sequencer, from hanging at rest; hand off (IC -> OP) "
                           "when the pendulum is in the zone. Computed for this design's plant model: an open-loop "
                           "schedule is fragile, the supervisory logic re-times itself on the measured states.")
    title = (f"{d.spec.name}: {strategy} pump-up, hand-off at {p.handoff_time or float('nan'):.2f} s, "
             "patched hold")
    job = plot_helper.submit(pump_and_manoeuvre_files, p, m, title, svg)
    files = predicted_patch_files(d, machine, bench, net, [section], runs_hold=SHEET_HOLD_RUNS)
    files.update(job.result())
    comparison = report.comparison
    files["manoeuvre.json"] = json_text(report.summary())
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(files["manoeuvre.json"], nl=False)
        return
    console = Console()
    t = Table(title=f"Switching table: {strategy}, {F:g} N", title_justify="left")
    for c in rows[0]:
        t.add_column(c)
    for r in rows[1:]:
        t.add_row(*r)
    console.print(t)
    if p.reached:
        console.print(f"hand-off zone reached at {p.handoff_time:.2f} s, max |s| during pump-up "
                      f"{p.max_abs_s_pump:.3f} m (switches at +/-{plant.d / 2:.3f} m)")
        h = m.hold.runs[0]
        console.print(("[green]" if m.held else "[red]") + f"patched controller on the bench for {hold_s:g} s: "
                      + ("held" if m.held else "lost it") + f" (max |theta| {h.max_abs_theta_deg:.2f} deg, "
                      f"max |s| {h.max_abs_s_m:.3f} m)" + ("[/green]" if m.held else "[/red]"))
    else:
        console.print("[red]the hand-off zone was not reached[/red]")
    if m.sensitivity:
        s = Table(title="The open-loop schedule replayed on plants with one parameter off by 10%",
                  title_justify="left")
        for col in ("parameter", "factor", "reaches the zone", "at (s)", "max |s| (m)", "on the track"):
            s.add_column(col, justify="left" if col == "parameter" else "right")
        for r in m.sensitivity:
            s.add_row(r.parameter, f"{r.factor:.2f}", "yes" if r.reached else "no", _num(r.time_to_zone_s, "{:.3f}"),
                      f"{r.max_abs_s_m:.3f}", "yes" if r.on_track else "no")
        console.print(s)
    if comparison:
        c = Table(title=f"Strategies compared ({F:g} N, zone of the patched controller; success on the "
                  "10 plants with one parameter off by +/-10%)", title_justify="left")
        for col in ("strategy", "time to zone (s)", "max |s| (m)", "E/E0 at hand-off", "held (state feedback)",
                    "robust", "worst time (s)"):
            c.add_column(col, justify="left" if col == "strategy" else "right")
        for r in comparison:
            c.add_row(r.strategy, _num(r.time_to_zone_s, "{:.3f}"), f"{r.max_abs_s_m:.3f}",
                      _num(r.energy_ratio, "{:.3f}"), "yes" if r.held else "no",
                      f"{r.robust_reached}/{r.robust_total}", _num(r.worst_time_s, "{:.2f}"))
        console.print(c)
    console.print("wrote " + ", ".join(str(x) for x in written))


def pump_and_manoeuvre_files(p, m, title: str, svg: bool) -> dict[str, bytes]:
    """The pump-up's files and the manoeuvre plot, as file name -> bytes (drawn by the plot helper)."""
    return {**output_files(p, svg=svg), **plot_manoeuvre(m, "manoeuvre", title, svg)}


def _num(x, fmt: str) -> str:
    return "-" if x is None else fmt.format(x)
