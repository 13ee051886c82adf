"""`patchgen recommend SPEC -o DIR`: try every realisation that fits, simulate each on the bench,
write the patch of the best with the comparison on its sheet."""

from __future__ import annotations

import click
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from patchgen.inputs.errors import InputError
from patchgen.render.outputs import check_out_dir, write_files
from patchgen.render.patchfiles import PATCH_FILES
from patchgen.render.pottable import pot_table
from patchgen.studies.comparison import fmt_figure, gm_cell, outcome_cells, recommendation_files, table_rows
from patchgen.studies.recommend import RUNS, recommend

from . import cli
from .inputs import load_inputs, scenario_for
from .options import SEED, out_option

RECOMMEND_FILES = PATCH_FILES + ("recommendation.md", "recommendation.json")


@cli.command("recommend")
@click.argument("spec")
@out_option("the recommended patch (as patchgen patch writes it)")
@click.option("--runs", default=RUNS, show_default=True, type=click.IntRange(1, 100000),
              help="Monte Carlo noise seeds per realisation.")
@click.option("--scenario", "scenario_path", default="hold-120s", show_default=True,
              help="Scenario: a shipped name or a TOML file.")
@click.option("--seed", default=None, type=SEED, help="Base seed (default: the scenario's).")
@click.option("--json", "as_json", is_flag=True, help="Print the comparison as JSON.")
@click.option("--force", is_flag=True, help="Replace output files that already exist.")
def recommend_cmd(spec, out_dir, runs, scenario_path, seed, as_json, force):
    """Design, allocate and simulate each realisation of SPEC's estimator; write the best patch."""
    check_out_dir(out_dir, RECOMMEND_FILES, force)
    sp, machine, bench = load_inputs(spec)
    scenario = scenario_for(scenario_path, sp, runs)
    console = Console(stderr=as_json)
    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=Console(stderr=True), transient=True) as bar:
        task = bar.add_task("Monte Carlo", total=None)
        rec = recommend(sp, machine, bench, scenario, runs, seed, progress=lambda label, done, total: bar.update(
            task, description=f"Monte Carlo: {label}", completed=done, total=total))
    best = rec.best
    if best is None:
        raise InputError(sp.path, "estimator", "no realisation fits the machine with a wired loop stable on the "
                         "bench: " + "; ".join(f"{c.label}: {c.error or f'wired loop {c.bench_loop} on the bench'}"
                                               for c in rec.ranked))
    files = recommendation_files(rec, machine, bench)
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(files["recommendation.json"], nl=False)
        return
    t = Table(title=f"{sp.name}: realisations on the bench ({scenario.name}, {runs} seeds)", title_justify="left")
    for col in ("rank", "realisation", "estimator", "held", "fallen", "tripped", "overload", "GM lo/up dB",
                "PM", "swing V", "amps/pots"):
        t.add_column(col, justify="left" if col in ("realisation", "estimator") else "right")
    for r in table_rows(rec):
        if r["error"]:
            t.add_row("-", r["realisation"], r["estimator"], f"[red]{r['error']}[/red]", *[""] * 7)
            continue
        t.add_row(str(r["rank"]), r["realisation"], r["estimator"], *outcome_cells(r), gm_cell(r, "/"),
                  fmt_figure(r["pm_deg"], "{:.1f}"), f"{r['worst_swing_V']:.2f}", f"{r['amplifiers']}/{r['pots']}")
    Console(width=max(150, console.width)).print(t)
    console.print(f"chosen: [bold]{best.label}[/bold]")
    console.print(pot_table(best.netlist, machine.procedure.pot_setting))
    for n in best.netlist.notes:
        console.print(f"[yellow]note:[/yellow] {n}")
    console.print("wrote " + ", ".join(str(p) for p in written))
