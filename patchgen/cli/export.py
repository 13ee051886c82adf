"""`patchgen export SPEC --machine lucidac -o DIR`: the patch as the configuration a programmed machine loads."""

from __future__ import annotations

import click

from patchgen.inputs.resources import shipped
from patchgen.pipeline.export import ExportPlan, check_programmed, run_export
from patchgen.pipeline.inputs import load_inputs, scenario_for
from patchgen.render.bench_sheet import failure_banner
from patchgen.render.lucidac_files import EXPORT_FILES, export_files
from patchgen.render.outputs import check_out_dir, json_text, write_files

from . import cli
from .options import FORCE, MACHINE, json_option, out_option


@cli.command("export")
@click.argument("spec")
@MACHINE
@out_option("the configuration, the run script and the table of elements and coefficients")
@click.option("--scenario", "scenario_path", default=None, metavar="SCENARIO",
              help=f"Run for this scenario's duration ({', '.join(shipped('scenario'))}, or a TOML file); "
                   "without it the run script runs until stopped.")
@json_option("the placement")
@FORCE
def export_cmd(spec, machine, out_dir, scenario_path, as_json, force) -> None:
    """Export SPEC's patch for a programmed machine (the LUCIDAC): the configuration it loads,
    built and sanity-checked with its client library lucipy (pip install 'patchgen[lucidac]'), a
    script that loads and runs it, and a table of which element carries what."""
    check_out_dir(out_dir, EXPORT_FILES, force)
    inputs = load_inputs(spec, machine=machine, command="export")
    check_programmed(inputs)
    plan = ExportPlan()
    if scenario_path is not None:
        sc = scenario_for(scenario_path, inputs.spec)
        plan = ExportPlan(run_s=sc.duration_s, scenario=sc.name)
    report = run_export(inputs, plan)
    written = write_files(out_dir, export_files(report), force=force)
    if as_json:
        click.echo(json_text(report.summary()), nl=False)
        return
    lp = report.lanes
    click.echo(f"{report.netlist.design} on the LUCIDAC: {len(lp.elements)} elements, {len(lp.lanes)} of 32 lanes")
    for e in lp.elements:
        click.echo(f"  {e.name:4} {e.carries}")
    for s, acl in lp.sensor_acl.items():
        click.echo(f"  ACL_IN {acl}: {s}")
    click.echo(f"  ACL_OUT {lp.output_acl}: u_c")
    for w in report.warnings:
        click.echo(f"lucipy: {w}")
    pred, bench = report.prediction, inputs.bench.id
    banner = failure_banner(bench, pred) if pred is not None else ""
    click.echo(banner.replace("See 'Predicted on the bench'.", "(patchgen patch gives the figures)") if banner
               else f"predicted on the {bench} bench: held in every scenario, the wired loop stable")
    click.echo("wrote " + ", ".join(str(p) for p in written))
