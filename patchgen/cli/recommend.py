"""`patchgen recommend SPEC -o DIR`: try every realisation that fits, simulate each on the bench,
write the patch of the best with the comparison on its sheet."""

from __future__ import annotations

import sys

import click

from patchgen.bench.prediction import STANDARD
from patchgen.pipeline.inputs import load_inputs, scenario_for
from patchgen.pipeline.recommend import RecommendPlan, run_recommend
from patchgen.profiles.bench import bench_scenarios
from patchgen.render.outputs import check_out_dir, write_files
from patchgen.render.recommend_view import print_recommendation, progress_bar
from patchgen.render.recommendation_files import RECOMMEND_FILES, recommendation_files
from patchgen.studies.recommend import RUNS

from . import cli
from .options import FORCE, MACHINE, bench_option, json_option, out_option, seed_option

NONE_CHOSEN_STATUS = 1  # the comparison is written, but no realisation holds on the bench


@cli.command("recommend")
@click.argument("spec")
@out_option("the recommended patch (as patchgen patch writes it), its spec and the comparison")
@click.option("--runs", default=RUNS, show_default=True, type=click.IntRange(1, 100000),
              help="The most Monte Carlo noise seeds per realisation and scenario.")
@click.option("--scenario", "scenario_paths", multiple=True, metavar="SCENARIO",
              help="A scenario every realisation must hold: a shipped name or a TOML file; repeat for more "
                   f"[default: the bench profile's scenarios, else every shipped one: {', '.join(STANDARD)}].")
@seed_option(None, "Base seed of every scenario (default: each scenario's own).")
@click.option("--all-runs", is_flag=True, help="Run every realisation --runs times on every scenario (no early "
              "stop once a realisation clearly holds or fails).")
@bench_option("when it states ranges for its parameters, every run draws its bench from them and the worst "
              "corner is checked.")
@MACHINE
@json_option("the comparison")
@FORCE
def recommend_cmd(spec, out_dir, runs, scenario_paths, seed, all_runs, bench_name, machine, as_json, force):
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
    inputs = load_inputs(spec, bench_name, "--bench", machine, command="recommend")
    if bench_name is not None:  # the recommended spec names the bench it was chosen on
        inputs = inputs._replace(spec=inputs.spec.model_copy(update={"bench": bench_name}))
    scenarios = tuple(scenario_for(p, inputs.spec, runs).judged()
                      for p in (scenario_paths or bench_scenarios(inputs.bench)))
    with progress_bar() as progress:
        report = run_recommend(inputs, scenarios, RecommendPlan(runs, seed, not all_runs), progress)
    files = recommendation_files(report, inputs.machine, inputs.bench)
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(files["recommendation.json"], nl=False)
    else:
        print_recommendation(report.recommendation, inputs.machine, inputs.spec.name, runs, written)
    if report.best is None:
        sys.exit(NONE_CHOSEN_STATUS)
