"""`patchgen spice SPEC --scenario X -o DIR`: the patch checked at the electrical level by ngspice."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from patchgen.pipeline.inputs import check_spice_points, load_inputs, scenario_for
from patchgen.pipeline.spice import SpicePlan, run_spice, spice_job
from patchgen.render import plot_helper
from patchgen.render.outputs import check_out_dir, json_text, write_files
from patchgen.render.spice_view import deck_files, print_spice, spice_files
from patchgen.spice.run import NgspiceError, NgspiceMissing

from . import cli
from .options import FORCE, MACHINE, SCENARIO, FiniteFloat, json_option, out_option, svg_option

SPICE_FILES = ("patch.cir", "patch.data", "comparison.json", "overlay.png", "overlay.svg")

NO_NGSPICE_STATUS = NgspiceMissing.exit_status


@cli.command("spice")
@click.argument("spec")
@SCENARIO
@out_option("the deck, ngspice's data, the comparison and its overlay plot")
@click.option("--ideal", is_flag=True, help="Noise and drift off and the actuator a pure gain, as patchgen "
              "simulate --ideal; the op-amp macromodels (finite gain, output limits) stay.")
@click.option("--step", "step_s", type=FiniteFloat(1e-5, 0.1), default=0.005, show_default=True,
              help="Output step of the transient (s).")
@click.option("--tolerance", type=FiniteFloat(0, 1), default=0.01, show_default=True,
              help="With --ideal, the agreement required, as a fraction of each signal's peak. Without "
              "--ideal it is not used: the verdict is statistical (ngspice's run inside the envelope of "
              "patchgen's Monte Carlo) and the per-point differences are information only.")
@MACHINE
@svg_option("the overlay plot (overlay.svg)")
@json_option("the comparison")
@FORCE
def spice_cmd(spec, scenario_path, out_dir, ideal, step_s, tolerance, machine, svg, as_json, force) -> None:
    """Export SPEC's patch and the bench as an ngspice deck, run it, and compare with patchgen's own
    simulation of the same scenario. With --ideal the runs are compared point by point within
    --tolerance; without, ngspice draws its own noise, so its run is judged against patchgen's
    Monte Carlo of the scenario (each figure inside the runs' envelope, held as they mostly hold).
    Exit 0 when they agree, 1 when not, 3 without ngspice (the deck is still written)."""
    check_out_dir(out_dir, SPICE_FILES, force)
    plot_helper.start()  # matplotlib loads on the other core while ngspice runs
    inputs = load_inputs(spec, machine=machine, command="spice")
    scenario = scenario_for(scenario_path, inputs.spec, 1, ideal)
    check_spice_points(scenario, step_s)
    job = spice_job(inputs, scenario, SpicePlan(ideal=ideal, step_s=step_s, tolerance=tolerance))
    try:
        report = run_spice(job)
    except NgspiceMissing as exc:
        write_files(out_dir, deck_files(job), force=force)
        click.echo(f"patchgen: {exc} (deck written to {Path(out_dir) / 'patch.cir'})", err=True)
        sys.exit(NO_NGSPICE_STATUS)
    except NgspiceError as exc:
        write_files(out_dir, deck_files(job), force=force)
        click.echo(f"patchgen: ngspice failed: {exc}", err=True)
        sys.exit(NgspiceError.exit_status)
    written = write_files(out_dir, spice_files(report, svg), force=force)
    summary = report.summary()
    if as_json:
        click.echo(json_text(summary), nl=False)
    else:
        print_spice(report, written)
    if not report.agrees:
        sys.exit(1)
