"""patchgen swingup's files and terminal view, from the pipeline's report: the patch with its
pump-up schedule on the sheet, the pump-up's and the manoeuvre's plots, manoeuvre.json; the
switching table, the hand-off and the hold, the schedule's sensitivity and the strategies compared."""

from __future__ import annotations

from rich.console import Console

from patchgen.pipeline.swingup import RotarySwingupReport, SwingupReport
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.render import plot_helper
from patchgen.render.bench_sheet import predicted_patch_files
from patchgen.render.manoeuvre_plot import plot_manoeuvre
from patchgen.render.outputs import json_text
from patchgen.render.sheet import SheetSection
from patchgen.render.simulation_files import output_files as output_files_of_hold
from patchgen.render.swingup_files import compact_schedule_rows, output_files, patch_sheet_rows
from patchgen.render.terminal import add_row, number, show, table, text
from patchgen.swingup.rotary_energy import SWITCHING


def swingup_files(report: SwingupReport, machine: MachineProfile, bench: BenchProfile,
                  svg: bool) -> dict[str, bytes | str]:
    """Every file of the command: the patch and its sheet with the pump-up schedule and the bench
    prediction, the plots, and manoeuvre.json (the report's summary)."""
    d, m, F, strategy = report.design, report.manoeuvre, report.force_limit_N, report.plan.strategy
    p = m.pump
    kept = report.schedule_note
    heading = f"Pump-up schedule ({strategy}, {F:g} N)" + (": the optimiser kept its seed" if kept else "")
    section = SheetSection(heading, *compact_schedule_rows(p), (f"{kept[0].upper()}{kept[1:]}. " if kept else "")
                           + "Switch times for the operator or a sequencer, from hanging at rest; hand off (IC -> OP) "
                           "when the pendulum is in the zone. Computed for this design's plant model: an open-loop "
                           "schedule is fragile, the supervisory logic re-times itself on the measured states.")
    title = (f"{d.spec.name}: {strategy} pump-up, hand-off at {p.handoff_time or float('nan'):.2f} s, "
             "patched hold")
    job = plot_helper.submit(pump_and_manoeuvre_files, p, m, title, svg)
    files = predicted_patch_files(d, machine, bench, report.netlist, report.prediction, report.judged, [section])
    files.update(job.result())
    files["manoeuvre.json"] = json_text(report.summary())
    return files


def pump_and_manoeuvre_files(p, m, title: str, svg: bool) -> dict[str, bytes]:
    """The pump-up's files and the manoeuvre plot, as file name -> bytes (drawn by the plot helper)."""
    return {**output_files(p, svg=svg), **plot_manoeuvre(m, "manoeuvre", title, svg)}


def comparing():
    """A note on stderr while the strategies are compared (it takes about a minute)."""
    return Console(stderr=True).status("comparing the three strategies on the nominal and +/-10% plants")


def print_swingup(report: SwingupReport, written: list, console: Console | None = None) -> None:
    """The report on the terminal."""
    console = console or Console()
    m, F, strategy, plant = report.manoeuvre, report.force_limit_N, report.plan.strategy, report.plant
    hold_s, comparison, p = report.plan.hold_s, report.comparison, report.manoeuvre.pump
    rows = patch_sheet_rows(p)
    t = table(f"Switching table: {strategy}, {F:g} N", text(rows[0][0]), text(rows[0][1]),
              *(number(c) for c in rows[0][2:]))
    for r in rows[1:]:
        add_row(t, *r)
    show(console, t)
    if report.schedule_note:
        console.print(f"[yellow]schedule: {report.schedule_note}[/yellow]")
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
        s = table("The open-loop schedule replayed on plants with one parameter off by 10%", text("parameter"),
                  *(number(c) for c in ("factor", "reaches the zone", "at (s)", "max |s| (m)", "on the track")))
        for r in m.sensitivity:
            add_row(s, r.parameter, f"{r.factor:.2f}", "yes" if r.reached else "no",
                    _num(r.time_to_zone_s, "{:.3f}"), f"{r.max_abs_s_m:.3f}", "yes" if r.on_track else "no")
        show(console, s)
    if comparison:
        c = table(f"Strategies compared ({F:g} N, zone of the patched controller; robust: of the 10 plants with "
                  "one parameter off by +/-10%, those on which it reaches the zone inside the switches)",
                  text("strategy"),
                  *(number(col) for col in ("time to\nzone (s)", "max |s|\n(m)", "E/E0 at\nhand-off",
                                            "held (state\nfeedback)", "robust", "worst\ntime (s)")))
        for r in comparison:
            add_row(c, r.strategy, _num(r.time_to_zone_s, "{:.3f}"), f"{r.max_abs_s_m:.3f}",
                    _num(r.energy_ratio, "{:.3f}"), "yes" if r.held else "no",
                    f"{r.robust_reached}/{r.robust_total}", _num(r.worst_time_s, "{:.2f}"))
        show(console, c)
    console.print("wrote " + ", ".join(str(x) for x in written))


def _num(x, fmt: str) -> str:
    return "-" if x is None else fmt.format(x)


ROTARY_HOLD_PREFIX = "hold-"  # the patched hold's simulation files, beside the patch's


def rotary_swingup_files(report: RotarySwingupReport, machine: MachineProfile, bench: BenchProfile,
                         svg: bool) -> dict[str, bytes | str]:
    """A rotary pendulum's manoeuvre files: the patch and its sheet with the switching table and the
    bench prediction, the patched hold's simulation files (hold-history.csv, ...), manoeuvre.json."""
    m = report.manoeuvre
    rows = [["When", "Law"]] + [[r.condition, r.law] for r in SWITCHING]
    section = SheetSection(f"Swing-up switching table (energy, {m.v_limit:g} V)", rows[0], rows[1:],
                           "From hanging at rest: the pump drives the motor until the pendulum is within the catch "
                           "zone, then the patch takes over (IC -> OP)" + (
                               f", here at {m.pump.handoff_time:.2f} s." if m.reached else
                               f"; in this design's plant model the pump came no nearer than {m.closest_deg:.0f} deg "
                               "to upright."))
    files = predicted_patch_files(report.design, machine, bench, report.netlist, report.prediction, report.judged,
                                  [section])
    if m.hold is not None:
        files.update({ROTARY_HOLD_PREFIX + k: v for k, v in output_files_of_hold(m.hold, svg).items()})
    files["manoeuvre.json"] = json_text(report.summary())
    return files


def print_rotary_swingup(report: RotarySwingupReport, written: list, console: Console | None = None) -> None:
    """The rotary manoeuvre in a few lines: reached, hand-off, hold."""
    console = console or Console()
    m = report.manoeuvre
    if not m.reached:
        console.print(f"[red]not reached[/red]: the energy pump at +/-{m.v_limit:g} V came no nearer than "
                      f"{m.closest_deg:.1f} deg to upright in {m.pump.t[-1]:.0f} s (the design's plant: its pendulum "
                      "damping D_p takes the energy the pump puts in)")
    else:
        console.print(f"pumped up by energy control at +/-{m.v_limit:g} V: hand-off to the patch at "
                      f"{m.pump.handoff_time:.2f} s, |alpha| at most {m.pump.max_abs_alpha:.2f} rad")
        run = m.hold.runs[0]
        console.print(("[green]held[/green]" if m.held else "[red]not held[/red]")
                      + f" by the patch on the bench for {m.hold_s:g} s: max |theta| {run.max_abs_theta_deg:.1f} deg, "
                      f"max |alpha| {run.max_abs_s_m:.2f} rad, max |u_c| {run.max_abs_u_c_V:.2f} V")
    console.print("wrote " + ", ".join(str(p) for p in written))
