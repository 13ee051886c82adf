"""`patchgen bench-test SPEC -o DIR`: recordings of every standard test for the spec's plant on a bench."""

from __future__ import annotations

import click

from . import cli
from .options import SEED, out_option


@cli.command("bench-test")
@click.argument("spec")
@out_option("the recordings (CSV) and test figures (TOML)")
@click.option("--bench", "bench_name", default=None,
              help="Bench profile to record on (default: the spec's bench).")
@click.option("--seed", type=SEED, default=0, show_default=True, help="Noise seed: the same seed, the same bytes.")
@click.option("--force", is_flag=True, help="Replace output files that already exist.")
def bench_test_cmd(spec, out_dir, bench_name, seed, force) -> None:
    """Record every standard bench test of SPEC's plant on its bench (noise and random forces as the
    profile says), for practice and to check identify against known values.

    Writes masses.toml, calibration.csv, actuator-step.csv, actuator-ramp.csv, coast-down-1.csv,
    coast-down-2.csv, incline.toml (not for a cart a DC motor drives), free-swing.csv, quiet.csv and
    integrator-drift.csv into DIR; encoders in counts, a motor with its back-EMF and rotor, as the
    bench profile states them. `patchgen identify DIR -o OUT` takes the folder whole.
    """
    from patchgen.design.model import plant_params
    from patchgen.identify.benchtest import FILES, bench_test_files
    from patchgen.profiles.bench import load_bench
    from patchgen.render.outputs import check_out_dir, write_files

    from .inputs import load_inputs

    check_out_dir(out_dir, FILES, force)
    sp, machine, bench = load_inputs(spec)
    if bench_name is not None:
        bench = load_bench(bench_name, "--bench", "")
    files = bench_test_files(plant_params(sp), bench, machine, seed, label=f"{sp.name} on bench {bench.id}")
    written = write_files(out_dir, files, force=force)
    click.echo(f"wrote {len(written)} recordings of {sp.name} on bench {bench.id} (seed {seed}) into {out_dir}; "
               f"next: patchgen identify {out_dir} -o OUT")
