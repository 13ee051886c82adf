"""patchgen recommend on the terminal: a progress bar while the candidates run, then the ranked
comparison, the chosen patch's pot table and notes, the verdict and the spec's departures."""

from __future__ import annotations

import contextlib
import re
import time

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from patchgen.profiles.machine import MachineProfile
from patchgen.render.pottable import pot_table
from patchgen.render.recommendation_files import corner_cell, fmt_figure, gm_cell, held_cell, table_rows, verdict_text
from patchgen.studies.departures import grouped
from patchgen.studies.recommend import Recommendation

PLAIN_EVERY_S = 5.0  # piped, a progress line at most this often while the work is the same


@contextlib.contextmanager
def progress_bar():
    """What recommend is doing and how far, on stderr, and the callback recommend reports to (what
    runs, runs done and runs in all; 0 in all: not known yet): a bar in a terminal; piped, a line
    when the work changes and at most every PLAIN_EVERY_S seconds."""
    console = Console(stderr=True)
    if not console.is_terminal:
        yield _PlainProgress(console)
        return
    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=console, transient=True) as bar:
        task = bar.add_task("recommend", total=None)
        yield lambda label, done, total: bar.update(task, description=escape(label), completed=done,
                                                    total=total or None)


class _PlainProgress:
    """Progress as plain lines, for a log or a pipe."""

    def __init__(self, console: Console):
        self.console, self.last, self.at, self.start = console, None, 0.0, time.monotonic()

    def __call__(self, label: str, done: int, total: int) -> None:
        now = time.monotonic()
        work = re.sub(r", batch \d+ of \d+$", "", label)  # a new batch of the same work is no news
        if work == self.last and now - self.at < PLAIN_EVERY_S:
            return
        self.last, self.at = work, now
        runs = f", {done} of {total} runs" if total else ""
        elapsed = int(now - self.start)
        self.console.print(f"recommend [{elapsed // 60}:{elapsed % 60:02d}]: {label}{runs}", markup=False,
                           highlight=False, soft_wrap=True)


def print_recommendation(rec: Recommendation, machine: MachineProfile, name: str, runs: int, written: list,
                         console: Console | None = None) -> None:
    """The comparison, the chosen patch (its pots and notes), the verdict, the departures, the files."""
    console = console or Console()
    best = rec.best
    _print_table(console, rec, name, runs)
    if best is not None:
        console.print(pot_table(best.netlist, machine.procedure.pot_setting))
        for n in best.netlist.notes:
            console.print(f"[yellow]note:[/yellow] {n}")
    console.print(("[bold]" if best else "[bold red]") + escape(verdict_text(rec)) + "[/]")
    if best is not None and best.departures:
        console.print(f"[bold yellow]departs from {escape(name)}:[/bold yellow]")
        for line in grouped(best.departures):
            console.print(f"  {escape(line)}")
    console.print("wrote " + ", ".join(str(p) for p in written))


def _print_table(console: Console, rec, name: str, runs: int) -> None:
    """The ranked comparison as a terminal table."""
    t = Table(title=f"{name}: realisations on the bench ({', '.join(sc.name for sc in rec.scenarios)}; "
              f"up to {runs} seeds each)", title_justify="left")
    cols = ["rank", "realisation", "estimator", "loop on bench", "verdict", "held: weakest scenario [95 %]",
            "GM lo/up dB", "PM", "swing V", "amps/pots"]
    if rec.ranges:
        cols.insert(6, "worst corner of the ranges")
    for col in cols:
        left = col in ("realisation", "estimator", "verdict", "loop on bench")
        t.add_column(col, justify="left" if left else "right")
    for r in table_rows(rec):
        if r["error"]:
            t.add_row("-", r["realisation"], r["estimator"], "", f"[red]{escape(r['error'])}[/red]",
                      *[""] * (len(cols) - 5))
            continue
        loop = r["bench_loop"] if r["bench_loop"] == "stable" else f"[red]{r['bench_loop']}[/red]"
        verdict = {"holds": "[green]holds[/green]", "fails": "[red]fails[/red]"}.get(r["decision"], r["decision"])
        cells = [str(r["rank"]), r["realisation"], r["estimator"], loop, verdict, held_cell(r), gm_cell(r, "/"),
                 fmt_figure(r["pm_deg"], "{:.1f}"), f"{r['worst_swing_V']:.2f}", f"{r['amplifiers']}/{r['pots']}"]
        if rec.ranges:
            cells.insert(6, escape(corner_cell(r)))
        t.add_row(*cells)
    Console(width=max(160, console.width), stderr=console.stderr).print(t)
