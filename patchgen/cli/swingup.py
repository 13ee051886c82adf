"""`patchgen swingup SPEC -o DIR`: pump up from hanging, hand off to the patched controller, hold."""

from __future__ import annotations

import click

from patchgen.pipeline.inputs import load_inputs
from patchgen.pipeline.swingup import SwingupPlan, run_swingup
from patchgen.plant.plant_model import CART
from patchgen.render import plot_helper
from patchgen.render.outputs import check_out_dir, write_files
from patchgen.render.patchfiles import PATCH_FILES
from patchgen.render.swingup_view import (
    ROTARY_HOLD_PREFIX,
    comparing,
    print_rotary_swingup,
    print_swingup,
    rotary_swingup_files,
    swingup_files,
)
from patchgen.swingup.manoeuvre import BENCH_HOLD_S
from patchgen.swingup.strategies import STRATEGIES

from . import cli
from .options import FORCE, MACHINE, FiniteFloat, json_option, out_option, seed_option, svg_option

SWINGUP_FILES = PATCH_FILES + ("swingup-history.csv", "swingup-switching.csv", "swingup-switching.md", "swingup.png",
                               "swingup.svg", "manoeuvre.png", "manoeuvre.svg", "manoeuvre.json") + tuple(
    ROTARY_HOLD_PREFIX + f for f in ("history.csv", "runs.csv", "summary.json", "history.png", "history.svg"))


@cli.command("swingup")
@click.argument("spec")
@out_option("the manoeuvre's histories, switching table, plots and the patch with the schedule")
@click.option("--strategy", type=click.Choice(STRATEGIES), default=None,
              help="supervisory (a cart's default): section 3.3's three-phase logic on measured states; schedule: "
              "optimised open-loop switching times; energy (a rotary pendulum's, its only one): Astrom-Furuta "
              "energy control.")
@click.option("--force-limit", type=FiniteFloat(0.1, 1000), default=None,
              help="Largest force (N) for the pump-up (default: the bench actuator's limit).")
@click.option("--hold", "hold_s", type=FiniteFloat(0.1, 3600), default=BENCH_HOLD_S, show_default=True,
              help="Seconds the patched controller must hold after the hand-off (at most an hour).")
@seed_option(0, "Noise seed of the hold.")
@click.option("--compare", is_flag=True, help="Also compare the three strategies (time to the zone, cart "
              "excursion, success on plants off by +/-10%); takes about a minute.")
@MACHINE
@svg_option("the plots")
@json_option("the summary (manoeuvre.json)")
@FORCE
def swingup_cmd(spec, out_dir, strategy, force_limit, hold_s, seed, compare, machine, svg, as_json, force) -> None:
    """Pump SPEC's pendulum up from hanging at rest, hand it to the patched controller when the state
    enters the zone of the linear design, and hold it on the bench (actuator lag and dead zone,
    noise, drift)."""
    check_out_dir(out_dir, SWINGUP_FILES, force)
    plot_helper.start()  # matplotlib loads on the other core while this one computes
    inputs = load_inputs(spec, machine=machine, command="swingup")
    rotary = inputs.spec.plant_model is not CART
    strategy = strategy or ("energy" if rotary else "supervisory")
    plan = SwingupPlan(strategy=strategy, force_limit_N=force_limit, hold_s=hold_s, seed=seed, compare=compare)
    report = run_swingup(inputs, plan, comparing=comparing)
    files = (rotary_swingup_files if rotary else swingup_files)(report, inputs.machine, inputs.bench, svg)
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(files["manoeuvre.json"], nl=False)
        return
    (print_rotary_swingup if rotary else print_swingup)(report, written)


