"""`patchgen recommend SPEC -o DIR`: try every realisation that fits, simulate each on the bench,
write the patch of the best with the comparison on its sheet."""

from __future__ import annotations

import sys

import click

from patchgen.bench.prediction import STANDARD
from patchgen.profiles.bench import bench_scenarios
from patchgen.render.outputs import check_out_dir, write_files
from patchgen.render.patchfiles import PATCH_FILES
from patchgen.render.recommend_view import print_recommendation, progress_bar
from patchgen.render.recommendation_files import (
    RECOMMENDED_SPEC,
    recommendation_files,
)
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
    with progress_bar() as progress:
        rec = recommend(sp, machine, bench, scenarios, runs, seed, early_stop=not all_runs, progress=progress)
    best = rec.best
    files = recommendation_files(rec, machine, bench)
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(files["recommendation.json"], nl=False)
    else:
        print_recommendation(rec, machine, sp.name, runs, written)
    if best is None:
        sys.exit(NONE_CHOSEN_STATUS)
