"""`patchgen sweep SPEC --vary M,m,l,b_VF,c --by 10%`: gains, margins and pots per perturbed plant."""

from __future__ import annotations

import click

from patchgen.pipeline.inputs import load_inputs, scenario_for
from patchgen.pipeline.sweep import SweepPlan, run_sweep
from patchgen.plant.cart_pendulum import UNCERTAIN
from patchgen.render.outputs import json_text
from patchgen.render.sweep_view import print_sweep

from . import cli
from .options import MACHINE, json_option, parse_by, parse_vary


@cli.command("sweep")
@click.argument("spec")
@click.option("--vary", default=None, help="Parameters to vary, comma-separated (default: the plant's that a "
              "bench may have wrong: " + ",".join(UNCERTAIN) + " for a cart).")
@click.option("--by", "by_text", default="10%", show_default=True, help="Relative change, e.g. 10%.")
@click.option("--workers", default=0, type=click.IntRange(0, 64), help="Processes (0: one per core).")
@click.option("--scenario", "scenario_path", default="offset-10deg", show_default=True,
              help="Scenario (shipped name or TOML file) for the nominal patch's predicted outcome.")
@click.option("--runs", type=click.IntRange(1, 10000), default=1, show_default=True,
              help="Noise seeds per row for the predicted outcome.")
@MACHINE
@json_option("the rows")
def sweep_cmd(spec: str, vary: str, by_text: str, workers: int, scenario_path: str, runs: int,
              machine: str | None, as_json: bool) -> None:
    """Re-design SPEC with each plant parameter off by --by (thesis tables 4.1, 4.2): the gains, the
    margins, the pots that would change, and how the nominal patch (as wired) does on that plant."""
    by = parse_by(by_text)
    inputs = load_inputs(spec, machine=machine, command="sweep")
    plan = SweepPlan(tuple(parse_vary(vary, plant=inputs.spec.plant_model)), by, workers, runs)
    scenario = scenario_for(scenario_path, inputs.spec, runs)  # a bad scenario fails here, in one line
    report = run_sweep(inputs, scenario, plan)
    if as_json:
        click.echo(json_text(report.summary()), nl=False)
        return
    print_sweep(report.design, list(report.rows), plan.by)
