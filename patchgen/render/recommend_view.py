"""patchgen recommend on the terminal: a progress bar while the candidates run, then the ranked
comparison (a candidate in a few lines at 80 columns; those not run one line per kind of refusal),
the chosen patch's pot table and notes, the verdict and the spec's departures."""

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
from patchgen.render.recommendation_files import corner_cell, fmt_figure, gm_cell, table_rows, verdict_text
from patchgen.render.refusals import summary
from patchgen.render.terminal import add_row, figure, number, show, table, text
from patchgen.studies.departures import grouped
from patchgen.studies.recommend import Recommendation

PLAIN_EVERY_S = 5.0  # piped, a progress line at most this often while the work is the same
MOST_SHOWN = 10  # candidates run that the table shows, best first; those ranked below are counted by kind


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
    rows = table_rows(rec)
    ran = [r for r in rows if not r["error"]]
    shown = ran if len(ran) <= MOST_SHOWN + 2 else ran[:MOST_SHOWN]  # never "2 more" for two rows
    show(console, comparison_table(rec, shown, name, runs))
    below = ranked_below(ran[len(shown):])
    refused = summary([(r["realisation"], r["error"]) for r in rows if r["error"]])
    for line in ([below] if below else []) + refused:
        console.print(escape(line), style="yellow", highlight=False)
    if below or refused:
        console.print("(each candidate in full: recommendation.md and --json)", highlight=False)
    if best is not None:
        show(console, pot_table(best.netlist, machine.procedure.pot_setting))
        for n in best.netlist.notes:
            console.print(f"[yellow]note:[/yellow] {n}")
    console.print(("[bold]" if best else "[bold red]") + escape(verdict_text(rec)) + "[/]")
    if best is not None and best.departures:
        console.print(f"[bold yellow]departs from {escape(name)}:[/bold yellow]")
        for line in grouped(best.departures):
            console.print(f"  {escape(line)}")
    console.print("wrote " + ", ".join(str(p) for p in written))


def ranked_below(rows: list[dict]) -> str:
    """The candidates run but not shown, in one line: how many, by verdict and wired loop on the bench."""
    if not rows:
        return ""
    kinds: dict[tuple[str, str], int] = {}
    for r in rows:
        kinds[r["decision"], r["bench_loop"]] = kinds.get((r["decision"], r["bench_loop"]), 0) + 1
    verb = {"holds": "hold", "fails": "fail"}
    parts = [f"{n} {verb.get(decision, decision)} ({loop})" for (decision, loop), n in
             sorted(kinds.items(), key=lambda k: -k[1])]
    return f"{len(rows)} more ranked below, by verdict (wired loop on the bench): " + ", ".join(parts)


def comparison_table(rec, rows: list[dict], name: str, runs: int) -> Table:
    """The candidates in ``rows`` that were run, ranked, each in a few lines: its realisation and estimator
    (and, on a bench with ranges, its worst corner), verdict over the wired loop on the bench, the
    weakest scenario's held fraction over its 95 % interval, margins, the largest swing over the
    amplifiers and pots it takes."""
    t = table(f"{name}: realisations on the bench ({', '.join(sc.name for sc in rec.scenarios)}; up to {runs} "
              "seeds each)", number("#"), text("realisation"), text("verdict\nbench loop"),
              number("held\n95 % interval\nweakest"), number("GM (dB)\nPM (deg)"),
              number("swing (V)\namps/pots"), lines=True)
    for r in rows:
        if r["error"]:
            continue
        what = escape(r["realisation"]) + (f"\n[dim]{escape(r['estimator'])}[/dim]" if r["estimator"] else "")
        if rec.ranges:
            what += f"\nworst corner: {escape(corner_cell(r, rec.ranges))}"
        loop = r["bench_loop"] if r["bench_loop"] == "stable" else f"[red]{r['bench_loop']}[/red]"
        verdict = {"holds": "[green]holds[/green]", "fails": "[red]fails[/red]"}.get(r["decision"], r["decision"])
        held = "-" if r["interval_95"] is None else (
            f"{100 * r['fraction_ok']:.1f} %\n{100 * r['interval_95'][0]:.1f}-{100 * r['interval_95'][1]:.1f} %\n"
            + escape(r["weakest_scenario"]))
        add_row(t, str(r["rank"]), what, f"{verdict}\n{loop}", held,
                f"{gm_cell(r, '/')}\n{fmt_figure(r['pm_deg'], '{:.1f}')}",
                f"{figure(r['worst_swing_V'], '{:.2f}')}\n{r['amplifiers']}/{r['pots']}")
    return t
