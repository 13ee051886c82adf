"""`patchgen recommend SPEC -o DIR`: try every realisation that fits, simulate each on the bench,
write the patch of the best with the comparison on its sheet."""

from __future__ import annotations

import sys

import click
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from patchgen.bench.prediction import STANDARD
from patchgen.profiles.bench import bench_scenarios
from patchgen.render.outputs import check_out_dir, write_files
from patchgen.render.patchfiles import PATCH_FILES
from patchgen.render.pottable import pot_table
from patchgen.render.recommendation_files import (
    RECOMMENDED_SPEC,
    corner_cell,
    fmt_figure,
    gm_cell,
    held_cell,
    recommendation_files,
    table_rows,
    verdict_text,
)
from patchgen.studies.departures import grouped
from patchgen.studies.recommend import RUNS, recommend

from . import cli
from .inputs import load_inputs, scenario_for
from .options import SEED, out_option

RECOMMEND_FILES = PATCH_FILES + ("recommendation.md", "recommendation.json", RECOMMENDED_SPEC)
NONE_CHOSEN_STATUS = 1  # the comparison is written, but no realisation holds on the bench


@cli.command("recommend")
@click.argument("spec")
@out_option("the recommended patch (as patchgen patch writes it), its spec and the comparison")
@click.option("--runs", default=RUNS, show_default=True, type=click.IntRange(1, 100000),
              help="The most Monte Carlo noise seeds per realisation and scenario.")
@click.option("--scenario", "scenario_paths", multiple=True, metavar="SCENARIO",
              help="A scenario every realisation must hold: a shipped name or a TOML file; repeat for more "
                   f"[default: the bench profile's scenarios, else every shipped one: {', '.join(STANDARD)}].")
@click.option("--seed", default=None, type=SEED, help="Base seed of every scenario (default: each scenario's own).")
@click.option("--all-runs", is_flag=True, help="Run every realisation --runs times on every scenario (no early "
              "stop once a realisation clearly holds or fails).")
@click.option("--bench", "bench_name", default=None, metavar="BENCH",
              help="Bench profile (a shipped id or a TOML file) instead of the spec's; when it states ranges for its "
                   "parameters, every run draws its bench from them and every corner is checked.")
@click.option("--json", "as_json", is_flag=True, help="Print the comparison as JSON.")
@click.option("--force", is_flag=True, help="Replace output files that already exist.")
def recommend_cmd(spec, out_dir, runs, scenario_paths, seed, all_runs, bench_name, as_json, force):
    """Run every realisation of SPEC on the bench in every scenario; write the best patch and its spec.

    The realisations: every estimator, and each again designed with the bench's actuator when
    SPEC's design model differs. When none holds, SPEC's variants too, nearest first: an integral
    state the force cannot move dropped, coefficients below the dial left out, theta weighted
    harder. The best is written with recommended.toml (its spec, which every command takes; each
    field it changes of SPEC named with why) and the comparison. Exit 1, with the comparison
    written, when no realisation with a wired loop stable on the bench holds in 95 % of the runs
    of every scenario, variants included.
    """
    check_out_dir(out_dir, RECOMMEND_FILES, force)
    sp, machine, bench = load_inputs(spec, bench_name)
    if bench_name is not None:
        sp = sp.model_copy(update={"bench": bench_name})
    scenarios = tuple(scenario_for(p, sp, runs).judged() for p in (scenario_paths or bench_scenarios(bench)))
    console = Console(stderr=as_json)
    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=Console(stderr=True), transient=True) as bar:
        task = bar.add_task("Monte Carlo", total=None)
        rec = recommend(sp, machine, bench, scenarios, runs, seed, early_stop=not all_runs,
                        progress=lambda label, done, total: bar.update(
                            task, description=f"Monte Carlo: {label}", completed=done, total=total))
    best = rec.best
    files = recommendation_files(rec, machine, bench)
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(files["recommendation.json"], nl=False)
    else:
        _print_table(console, rec, sp.name, runs)
        if best is not None:
            console.print(pot_table(best.netlist, machine.procedure.pot_setting))
            for n in best.netlist.notes:
                console.print(f"[yellow]note:[/yellow] {n}")
        console.print(("[bold]" if best else "[bold red]") + escape(verdict_text(rec)) + "[/]")
        if best is not None and best.departures:
            console.print(f"[bold yellow]departs from {escape(sp.name)}:[/bold yellow]")
            for line in grouped(best.departures):
                console.print(f"  {escape(line)}")
        console.print("wrote " + ", ".join(str(p) for p in written))
    if best is None:
        sys.exit(NONE_CHOSEN_STATUS)


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
