"""`patchgen bench-test SPEC -o DIR`: recordings of every standard test for the spec's plant on a bench."""

from __future__ import annotations

import click

from . import cli
from .options import FORCE, json_option, out_option, seed_option


@cli.command("bench-test")
@click.argument("spec")
@out_option("the recordings (CSV) and test figures (TOML)")
@click.option("--bench", "bench_name", default=None, metavar="BENCH",
              help="Bench profile to record on (a shipped id or a TOML file; default: the spec's bench).")
@seed_option(0, "Noise seed: the same seed, the same bytes.")
@json_option("the spec, bench, seed and files written")
@FORCE
def bench_test_cmd(spec, out_dir, bench_name, seed, as_json, force) -> None:
    """Record every standard bench test of SPEC's plant on its bench (noise and random forces as the
    profile says), for practice and to check identify against known values.

    Writes masses.toml, calibration.csv, actuator-step.csv, actuator-ramp.csv, coast-down-1.csv,
    coast-down-2.csv, incline.toml (not for a cart a DC motor drives), free-swing.csv, quiet.csv and
    integrator-drift.csv into DIR; encoders in counts, a motor with its back-EMF and rotor, as the
    bench profile states them. For a rotary pendulum: links.toml, calibration.csv, motor-step.csv,
    arm-coast-1.csv, arm-coast-2.csv, free-swing.csv and quiet.csv. `patchgen identify DIR -o OUT`
    takes the folder whole.
    """
    from patchgen.identify.benchtest import FILES
    from patchgen.identify.rotary_benchtest import ROTARY_FILES
    from patchgen.pipeline.identify import run_bench_test
    from patchgen.pipeline.inputs import load_inputs
    from patchgen.plant.plant_model import ROTARY
    from patchgen.profiles.bench import load_bench
    from patchgen.render.outputs import check_out_dir, json_text, write_files
    from patchgen.render.terminal import say

    inputs = load_inputs(spec, command="bench-test")
    check_out_dir(out_dir, ROTARY_FILES if inputs.spec.plant_model is ROTARY else FILES, force)
    if bench_name is not None:  # any bench: its sensors need not be those the spec's patch reads
        inputs = inputs._replace(bench=load_bench(bench_name, "--bench", ""))
    report = run_bench_test(inputs, seed)
    written = write_files(out_dir, report.recordings, force=force)
    if as_json:
        click.echo(json_text(report.summary(written)), nl=False)
        return
    say(f"wrote {len(written)} recordings of {report.spec} on bench {report.bench} (seed {seed}) into {out_dir}",
        f"next: patchgen identify {out_dir} -o OUT")
