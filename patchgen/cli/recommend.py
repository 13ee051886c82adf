"""`patchgen recommend SPEC -o DIR`: try every realisation that fits, simulate each on the bench,
write the patch of the best with the comparison on its sheet."""

from __future__ import annotations

import json
import math

import click
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import load_scenario
from patchgen.render.outputs import check_out_dir, write_files
from patchgen.render.pottable import pot_table
from patchgen.render.sheet import SheetSection
from patchgen.studies.recommend import Recommendation, evaluate, prepare, table_markdown, table_rows

from . import cli
from .inputs import load_inputs, scenario_for
from .options import SEED
from .patch import PATCH_FILES, patch_files

RECOMMEND_FILES = PATCH_FILES + ("recommendation.md", "recommendation.json")


def why_section(rec: Recommendation, machine) -> SheetSection:
    """The comparison table for the sheet: why the chosen realisation."""
    header = ["rank", "realisation", "held", "fallen", "tripped", "overloaded", "GM lower/upper (dB)", "PM (deg)",
              "worst swing (V)", "amps/pots"]
    rows = []
    misfits = []
    for r in table_rows(rec):
        if r["error"]:
            rows.append(["-", r["realisation"], "does not fit", "", "", "", "", "", "", ""])
            misfits.append(f"{r['realisation']}: {r['error']}")
            continue
        rows.append([str(r["rank"]), f"{r['realisation']} ({r['estimator']})", f"{r['fraction_ok']:.1%}",
                     f"{r['fraction_fallen']:.1%}", f"{r['fraction_tripped']:.1%}", f"{r['fraction_overloaded']:.1%}",
                     f"{_fmt(r['lower_gm_db'], '{:+.1f}', 'none')} / {_fmt(r['upper_gm_db'], '{:+.1f}', 'inf')}",
                     _fmt(r["pm_deg"], "{:.1f}"), f"{r['worst_swing_V']:.2f} of {machine.reference_V:g}",
                     f"{r['amplifiers']}/{r['pots']}"])
    note = (f"Bench Monte Carlo: {rec.scenario.name}, {rec.runs} seeds from {rec.seed}, bench actuator, noise and "
            "drift. Ranked by runs held (up, inside the switches, no overload), then gain margin, phase margin, "
            "worst swing." + (" Not fitting: " + "; ".join(misfits) + "." if misfits else ""))
    return SheetSection("Why this patch", header, rows, note)


def _fmt(x, fmt, none="-"):
    return none if x is None else (fmt.format(x) if math.isfinite(x) else "inf")


@cli.command("recommend")
@click.argument("spec")
@click.option("-o", "--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Directory for the recommended patch (as patchgen patch writes it).")
@click.option("--runs", default=200, show_default=True, type=click.IntRange(1, 100000),
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
    cands = prepare(sp, machine)
    fit = [c for c in cands if c.netlist is not None]
    done = []
    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=Console(stderr=True), transient=True) as bar:
        task = bar.add_task("Monte Carlo", total=runs * len(fit))
        base = 0
        for c in cands:
            if c.netlist is None:
                done.append(c)
                continue
            bar.update(task, description=f"Monte Carlo: {c.label}")
            done.append(evaluate(c, bench, machine, scenario, runs, seed,
                                 lambda n, b=base: bar.update(task, completed=b + n)))
            base += runs
    order = {c.label: i for i, c in enumerate(done)}
    rec = Recommendation(sp, scenario, runs, scenario.seed if seed is None else seed,
                         tuple(sorted(done, key=lambda c: c.rank_key(order[c.label]))))
    best = rec.best
    if best is None:
        raise InputError(sp.path, "estimator", "no realisation fits the machine: "
                         + "; ".join(f"{c.label}: {c.error}" for c in rec.ranked))
    md = table_markdown(rec, machine.reference_V)
    # the sheet's 120 s hold is the first seeds of this Monte Carlo when it ran that scenario
    same_hold = scenario == load_scenario("hold-120s") and rec.seed == scenario.seed
    done = {"hold-120s": list(best.results)} if same_hold else None
    files = patch_files(best.design, machine, best.netlist, extra_sections=[why_section(rec, machine)], done=done)
    files["recommendation.md"] = f"# Why this patch\n\n{md}"
    rows = table_rows(rec)
    files["recommendation.json"] = json.dumps({"spec": sp.name, "scenario": scenario.name, "runs": runs,
                                               "seed": rec.seed, "chosen": best.label, "candidates": rows},
                                              indent=2, sort_keys=True, allow_nan=False) + "\n"
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(files["recommendation.json"], nl=False)
        return
    t = Table(title=f"{sp.name}: realisations on the bench ({scenario.name}, {runs} seeds)", title_justify="left")
    for col in ("rank", "realisation", "estimator", "held", "fallen", "tripped", "overload", "GM lo/up dB",
                "PM", "swing V", "amps/pots"):
        t.add_column(col, justify="left" if col in ("realisation", "estimator") else "right")
    for r in rows:
        if r["error"]:
            t.add_row("-", r["realisation"], r["estimator"], f"[red]{r['error']}[/red]", *[""] * 7)
            continue
        t.add_row(str(r["rank"]), r["realisation"], r["estimator"], f"{r['fraction_ok']:.1%}",
                  f"{r['fraction_fallen']:.1%}", f"{r['fraction_tripped']:.1%}", f"{r['fraction_overloaded']:.1%}",
                  f"{_fmt(r['lower_gm_db'], '{:+.1f}', 'none')}/{_fmt(r['upper_gm_db'], '{:+.1f}', 'inf')}",
                  _fmt(r["pm_deg"], "{:.1f}"), f"{r['worst_swing_V']:.2f}", f"{r['amplifiers']}/{r['pots']}")
    Console(width=max(150, console.width)).print(t)
    console.print(f"chosen: [bold]{best.label}[/bold]")
    console.print(pot_table(best.netlist))
    for n in best.netlist.notes:
        console.print(f"[yellow]note:[/yellow] {n}")
    console.print("wrote " + ", ".join(str(p) for p in written))
