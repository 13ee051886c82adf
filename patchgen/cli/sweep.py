"""`patchgen sweep SPEC --vary M,m,l,b_VF,c --by 10%`: gains, margins and pots per perturbed plant."""

from __future__ import annotations

import click

from patchgen.design.lqg import design_on
from patchgen.plant.cart_pendulum import UNCERTAIN
from patchgen.render.outputs import json_text
from patchgen.render.sweep_view import print_sweep
from patchgen.studies.sweep import sweep

from . import cli
from .inputs import load_inputs, scenario_for
from .options import parse_by, parse_vary


@cli.command("sweep")
@click.argument("spec")
@click.option("--vary", default=",".join(UNCERTAIN), show_default=True,
              help="Parameters to vary, comma-separated.")
@click.option("--by", "by_text", default="10%", show_default=True, help="Relative change, e.g. 10%.")
@click.option("--workers", default=0, type=click.IntRange(0, 64), help="Processes (0: one per core).")
@click.option("--scenario", "scenario_path", default="offset-10deg", show_default=True,
              help="Scenario (shipped name or TOML file) for the nominal patch's predicted outcome.")
@click.option("--runs", type=click.IntRange(1, 10000), default=1, show_default=True,
              help="Noise seeds per row for the predicted outcome.")
@click.option("--json", "as_json", is_flag=True, help="Print the rows as JSON.")
def sweep_cmd(spec: str, vary: str, by_text: str, workers: int, scenario_path: str, runs: int, as_json: bool) -> None:
    """Re-design SPEC with each plant parameter off by --by (thesis tables 4.1, 4.2): the gains, the
    margins, the pots that would change, and how the nominal patch (as wired) does on that plant."""
    names, by = parse_vary(vary), parse_by(by_text)
    sp, machine, bench = load_inputs(spec)
    scenario = scenario_for(scenario_path, sp, runs)  # a bad scenario fails here, in one line
    d = design_on(sp, machine, bench)
    rows = sweep(d.spec, machine, names, by, workers, scenario, runs, bench=bench)
    if as_json:
        click.echo(json_text([r.as_dict() for r in rows]), nl=False)
        return
    print_sweep(d, rows, by)
