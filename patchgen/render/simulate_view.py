"""patchgen simulate on the terminal: the Monte Carlo's figures, the corners of the bench's ranges,
the linear verdicts and a progress bar while the runs go, from the pipeline's report."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console
from rich.table import Table

from patchgen.bench.results import SimResult
from patchgen.pipeline.simulate import SimulateReport
from patchgen.plant.plant_model import CART, PLANT_MODELS
from patchgen.render.terminal import add_row, number, show, table, text, tidy
from patchgen.studies import bench_corners, worst_case

OVERLOADS_SHOWN = 3  # amplifiers named in the overloads' cell, one a line


def progress_bar(name: str, runs: int, quiet: bool):
    """A progress bar on stderr for a Monte Carlo of more than one run (none when ``quiet``): the
    context and the callback the pipeline reports its runs to."""
    import contextlib

    if runs <= 1 or quiet:
        return contextlib.nullcontext(None)
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    @contextlib.contextmanager
    def bar():
        cols = (TextColumn("[progress.description]{task.description}"), BarColumn(), MofNCompleteColumn(),
                TimeElapsedColumn())
        with Progress(*cols, console=Console(stderr=True), transient=True) as prog:
            task = prog.add_task(f"{name}: Monte Carlo", total=runs)
            yield lambda done: prog.update(task, completed=done)

    return bar()


def summary_table(result: SimResult) -> Table:
    """The first run's figures and, for a Monte Carlo, their distribution (the share of runs, or
    the median and the 5th to 95th percentiles), as a rich table."""
    d = result.distribution
    r0 = result.runs[0]
    many = d.runs > 1
    t = table(f"{result.design} on the {result.bench} bench, scenario {result.scenario.name}"
              + (" (ideal)" if result.ideal else "")
              + (f"; {d.runs} runs: the share of runs, or the median and 5 to 95 %" if many else ""),
              text("figure"), number(f"run 0\nseed {result.seed}"),
              *((number(f"{d.runs} runs"), number("5 to 95 %")) if many else ()))

    def when(flag, time):
        return f"yes, at {time:.2f} s" if flag else "no"

    def share(x):
        return (f"{100 * x:.1f} %", "")

    over = [f"{o.amplifier} at {o.first_time_s:.2f} s" for o in r0.overloads]
    pm = PLANT_MODELS[result.settings.plant]
    rows = [
        ("held (up, inside the switches)" if pm is CART else f"held (up, not {pm.limit_event})",
         "yes" if r0.held else "no", *share(d.fraction_held)),
        (pm.limit_event if pm is not CART else "limit switch tripped"
         if result.settings.watchdog_m is None else "switch or watchdog tripped",
         when(r0.limit_switch_tripped, r0.trip_time_s), *share(d.fraction_tripped)),
        ("  when (s)", "", *_p(d, "trip_time_s")),
        (f"pendulum fallen past {result.scenario.fall_angle_deg:g} deg", when(r0.fallen, r0.fall_time_s),
         *share(d.fraction_fallen)),
        ("  when (s)", "", *_p(d, "fall_time_s")),
        ("max |theta| (deg)", f"{r0.max_abs_theta_deg:.2f}", *_p(d, "max_abs_theta_deg")),
        (pm.position_heading(), f"{r0.max_abs_s_m:.3f}", *_p(d, "max_abs_s_m")),
        ("RMS theta (deg)", f"{r0.rms_theta_deg:.3f}", *_p(d, "rms_theta_deg")),
        ("max |u_c| (V)", f"{r0.max_abs_u_c_V:.2f}", *_p(d, "max_abs_u_c_V")),
        ("overloads (amplifier at time)", _overloads(over), *share(d.fraction_overloaded)),
        ("command at its limit (s)", f"{r0.actuator_limit_time_s:.2f}",
         *share(d.fraction_at_actuator_limit)),
    ]
    for row in rows:
        add_row(t, *(row if many else row[:2]))
    return t


def corner_table(st: bench_corners.BenchStudy) -> Table:
    """The held fraction over drawn benches, at the corners of the ranges (every one, or the harshest
    the search found), and the worst corner."""
    ranges = ", ".join(f"{k} {lo:g}..{hi:g}" for k, (lo, hi) in st.ranges.items())
    t = table(f"over the bench's ranges ({st.distribution}: {ranges}); held = up, inside the switches, "
              "no overload", text("bench"), number("held"), number("95 % interval"))

    def row(name, o):
        lo, hi = o.interval
        add_row(t, name, f"{o.held}/{o.runs} ({100 * o.fraction:.1f} %)", f"{100 * lo:.1f}-{100 * hi:.1f} %")

    if st.drawn is not None:
        row("drawn from the ranges", st.drawn)
    w = st.worst_corner
    for c in st.corners:
        row(("worst corner: " if c is w else "corner: ") + c.label(), c.outcome)
    if st.screened:
        add_row(t, f"searched: {st.screened} points screened with {worst_case.SCREEN_RUNS} seeds each", "", "")
    if st.at_nominal:
        add_row(t, f"at the profile's value in the corners (past {bench_corners.MAX_CORNER_PARAMETERS} ranges): "
                + ", ".join(st.at_nominal), "", "")
    return t


def _overloads(over: list[str]) -> str:
    """The first overloads, one a line, and how many more (summary.json has them all)."""
    more = len(over) - OVERLOADS_SHOWN
    return "\n".join(over[:OVERLOADS_SHOWN] + ([f"and {more} more"] if more > 0 else [])) or "none"


def peaks_table(result: SimResult) -> Table:
    """Each amplifier's largest |output| over a run while the pendulum is up, as a share of the rails
    (before them: past 100 % is an overload), run 0's and, for a Monte Carlo, the median and the 5th
    to 95th percentiles: how much of its range a signal uses, so how far above the machine's noise
    and offsets it lives."""
    d, r0 = result.distribution, result.runs[0]
    many = d.runs > 1
    rails = result.settings.saturation_V
    t = table(f"amplifier peaks, % of the rails (+/-{rails:g} V)", text("amplifier"), number("run 0"),
              *((number(f"{d.runs} runs"), number("5 to 95 %")) if many else ()))
    for a in result.amplifiers:
        what = result.carries.get(a, (0, ""))[1]
        row = [f"{a} ({what})" if what else a, f"{100 * r0.amp_peak(a) / rails:.1f}"]
        p = d.amplifier_peak_V.get(a)
        if many and p:
            row += [f"{100 * p['p50'] / rails:.1f}", f"{100 * p['p5'] / rails:.1f}-{100 * p['p95'] / rails:.1f}"]
        elif many:
            row += ["-", ""]
        add_row(t, *row)
    return t


def _p(d, key: str) -> tuple[str, str]:
    """The median, and the 5th to 95th percentiles."""
    p = d.percentiles.get(key)
    if not p or p.get("p50") is None:
        return "-", ""
    return f"{p['p50']:.3g}", f"{p['p5']:.3g}-{p['p95']:.3g}"


def print_report(report: SimulateReport, written: list, console: Console | None = None) -> None:
    """The report on the terminal: the runs' table, the corners, the linear verdicts, their notes,
    and the files written."""
    console = console or Console()
    show(console, summary_table(report.result))
    if report.result.amplifiers:
        show(console, peaks_table(report.result))
    if report.corners is not None:
        show(console, corner_table(report.corners))
    for lp in report.loops:
        console.print(tidy(lp.line()), style="green" if lp.stable else "red")
    for note in report.notes():
        console.print(note)
    console.print("wrote " + ", ".join(str(Path(p)) for p in written))
