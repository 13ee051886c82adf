"""`patchgen simulate SPEC --scenario X -o DIR`: the patched circuit on the bench."""

from __future__ import annotations

import click

from patchgen.pipeline.inputs import load_inputs, scenario_for
from patchgen.pipeline.simulate import SimulatePlan, run_simulate
from patchgen.render import plot_helper
from patchgen.render.outputs import check_out_dir, json_text, write_files
from patchgen.render.simulate_view import print_report, progress_bar
from patchgen.render.simulation_files import output_files

from . import cli
from .options import FORCE, MACHINE, SCENARIO, bench_option, json_option, out_option, seed_option, svg_option

SIMULATE_FILES = ("history.csv", "runs.csv", "summary.json", "history.png", "history.svg", "netlist.json")


@cli.command("simulate")
@click.argument("spec")
@SCENARIO
@out_option("history.csv, runs.csv, summary.json and the plots")
@seed_option(None, "Noise seed (default: the scenario's).")
@click.option("--runs", type=click.IntRange(1, 1_000_000), default=1, show_default=True,
              help="Monte Carlo runs over noise seeds.")
@click.option("--ideal", is_flag=True, help="Every imperfection off (noise, drift, saturation, actuator lag "
              "and dead zone): the patch as the design imagines it.")
@click.option("--spread", "spread_text", default=None, metavar="PCT",
              help="Monte Carlo over the plant too: each run draws M, m, l, b_VF, c uniformly within this "
              "fraction of the spec's values (e.g. 10%).")
@click.option("--vary", default="M,m,l,b_VF,c", show_default=True, help="Parameters --spread draws.")
@bench_option()
@MACHINE
@click.option("--bench-spread", is_flag=True, help="Monte Carlo over the bench too: each run draws the bench's "
              "parameters from the profile's [uncertainty] ranges; the summary adds the corners of the ranges "
              "and the worst (searched for past three ranges).")
@click.option("--corner-runs", type=click.IntRange(1, 100_000), default=None,
              help="Runs at each corner of the bench's ranges with --bench-spread [default: --runs].")
@svg_option("the plot (history.svg)")
@json_option("the summary (summary.json)")
@FORCE
def simulate_cmd(spec, scenario_path, out_dir, seed, runs, ideal, spread_text, vary, bench_name, machine,
                 bench_spread, corner_runs, svg, as_json, force) -> None:
    """Simulate SPEC's patched circuit (built from its netlist) on the bench."""
    spread = None
    if spread_text is not None:
        from .options import parse_by, parse_vary

        frac = parse_by(spread_text, "--spread")
        spread = {name: frac for name in parse_vary(vary)}
    check_out_dir(out_dir, SIMULATE_FILES, force)
    plot_helper.start()  # matplotlib loads on the other core while this one simulates
    inputs = load_inputs(spec, bench_name, "--bench", machine, command="simulate")
    scenario = scenario_for(scenario_path, inputs.spec, runs, ideal)
    plan = SimulatePlan(runs=runs, seed=seed, ideal=ideal, spread=spread, bench_spread=bench_spread,
                        corner_runs=corner_runs)
    with progress_bar(scenario.name, runs, as_json) as progress:
        report = run_simulate(inputs, scenario, plan, progress)
    summary = report.summary()
    files = output_files(report.result, svg, summary)
    files["netlist.json"] = report.netlist.to_json().encode()
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(json_text(summary), nl=False)
        return
    print_report(report, written)
