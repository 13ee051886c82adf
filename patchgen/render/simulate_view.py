"""patchgen simulate on the terminal: the Monte Carlo's figures, the corners of the bench's ranges,
the linear verdicts and a progress bar while the runs go, from the pipeline's report."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console
from rich.table import Table

from patchgen.bench.results import SimResult
from patchgen.pipeline.simulate import SimulateReport
from patchgen.studies import bench_corners, worst_case


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
    """The first run's figures and, for a Monte Carlo, their distribution, as a rich table."""
    d = result.distribution
    r0 = result.runs[0]
    t = Table(title=f"{result.design} on the {result.bench} bench, scenario {result.scenario.name}"
              + (" (ideal)" if result.ideal else ""), title_justify="left")
    t.add_column("figure")
    t.add_column(f"run 0 (seed {result.seed})", justify="right")
    if d.runs > 1:
        t.add_column(f"{d.runs} runs", justify="right")

    def when(flag, time):
        return f"yes, at {time:.2f} s" if flag else "no"

    rows = [
        ("held (up, inside the switches)", "yes" if r0.held else "no", f"{100 * d.fraction_held:.1f} %"),
        ("limit switch tripped" if result.settings.watchdog_m is None else "switch or watchdog tripped",
         when(r0.limit_switch_tripped, r0.trip_time_s), f"{100 * d.fraction_tripped:.1f} %"),
        ("  when (s)", "", _p(d, "trip_time_s")),
        (f"pendulum fallen past {result.scenario.fall_angle_deg:g} deg", when(r0.fallen, r0.fall_time_s),
         f"{100 * d.fraction_fallen:.1f} %"),
        ("  when (s)", "", _p(d, "fall_time_s")),
        ("max |theta| (deg)", f"{r0.max_abs_theta_deg:.2f}", _p(d, "max_abs_theta_deg")),
        ("max |s| (m)", f"{r0.max_abs_s_m:.3f}", _p(d, "max_abs_s_m")),
        ("RMS theta (deg)", f"{r0.rms_theta_deg:.3f}", _p(d, "rms_theta_deg")),
        ("max |u_c| (V)", f"{r0.max_abs_u_c_V:.2f}", _p(d, "max_abs_u_c_V")),
        ("overloads (amplifier at time)", ", ".join(f"{o.amplifier} at {o.first_time_s:.2f} s" for o in r0.overloads)
         or "none", f"{100 * d.fraction_overloaded:.1f} %"),
        ("command at its limit (s)", f"{r0.actuator_limit_time_s:.2f}",
         f"{100 * d.fraction_at_actuator_limit:.1f} % of runs"),
    ]
    for row in rows:
        t.add_row(*(row if d.runs > 1 else row[:2]))
    return t


def corner_table(st: bench_corners.BenchStudy) -> Table:
    """The held fraction over drawn benches, at the corners of the ranges (every one, or the harshest
    the search found), and the worst corner."""
    ranges = ", ".join(f"{k} {lo:g}..{hi:g}" for k, (lo, hi) in st.ranges.items())
    t = Table(title=f"over the bench's ranges ({st.distribution}: {ranges}); held = up, inside the switches, "
              "no overload", title_justify="left")
    t.add_column("bench")
    t.add_column("held", justify="right")
    t.add_column("95 % interval", justify="right")

    def row(name, o):
        lo, hi = o.interval
        t.add_row(name, f"{o.held}/{o.runs} ({100 * o.fraction:.1f} %)", f"{100 * lo:.1f}-{100 * hi:.1f} %")

    if st.drawn is not None:
        row("drawn from the ranges", st.drawn)
    w = st.worst_corner
    for c in st.corners:
        row(("worst corner: " if c is w else "corner: ") + c.label(), c.outcome)
    if st.screened:
        t.add_row(f"searched: {st.screened} points screened with {worst_case.SCREEN_RUNS} seeds each", "", "")
    if st.at_nominal:
        t.add_row(f"at the profile's value in the corners (past {bench_corners.MAX_CORNER_PARAMETERS} ranges): "
                  + ", ".join(st.at_nominal), "", "")
    return t


def _p(d, key: str) -> str:
    p = d.percentiles.get(key)
    if not p or p.get("p50") is None:
        return "-"
    return f"{p['p50']:.3g} (5-95%: {p['p5']:.3g}-{p['p95']:.3g})"


def print_report(report: SimulateReport, written: list, console: Console | None = None) -> None:
    """The report on the terminal: the runs' table, the corners, the linear verdicts, their notes,
    and the files written."""
    console = console or Console()
    console.print(summary_table(report.result))
    if report.corners is not None:
        console.print(corner_table(report.corners))
    for lp in report.loops:
        console.print(("[green]" if lp.stable else "[red]") + lp.line() + ("[/green]" if lp.stable else "[/red]"))
    for note in report.notes():
        console.print(note)
    console.print("wrote " + ", ".join(str(Path(p)) for p in written))
