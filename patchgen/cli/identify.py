"""`patchgen identify RECORDINGS... -o DIR`: a bench profile and the plant's figures from
recordings of the standard tests."""

from __future__ import annotations

import click

from . import cli
from .options import FORCE, json_option, out_option


@cli.command("identify")
@click.argument("recordings", nargs=-1, required=True, metavar="RECORDINGS...")
@out_option("bench.toml, plant.toml, report.md, report.json and the fit plots")
@click.option("--base", default=None,
              help="Bench profile for what the recordings do not give (force limit, track, random forces, a "
                   "motor's figures, encoders' counts, and any sensor constant or noise level not recorded), "
                   "and with which a recording in counts is read (default: the bench the recordings name, "
                   "'# bench = <id>', else uw-1991).")
@click.option("--id", "bench_id", default="identified", show_default=True, help="The new bench profile's id.")
@click.option("--name", default=None, help="The new bench profile's name (default: from the recordings).")
@json_option("the report")
@FORCE
def identify_cmd(recordings, out_dir, base, bench_id, name, as_json, force) -> None:
    """Fit a bench profile and the plant's figures to recordings of the standard tests.

    RECORDINGS are CSV recordings and TOML test figures, or folders of them (docs/identify.md says
    what to record). A cart's bench gives its actuator, friction and pendulum; a rotary pendulum's
    (a base profile with plant = "rotary-pendulum") its motor, the arm's and pendulum's damping and
    the pendulum's inertia. Writes DIR/bench.toml (a bench profile every command takes through a
    spec's bench = "DIR/bench.toml"; a rotary bench's holds the plant as identified in
    [measured_plant]), DIR/plant.toml (a [plant] table for a spec), DIR/report.md, DIR/report.json
    and a fit plot per recording.
    """
    from patchgen.inputs.errors import InputError
    from patchgen.pipeline.identify import run_identify
    from patchgen.profiles.bench import load_bench
    from patchgen.render.identify_files import FIXED, identify_files, print_identification
    from patchgen.render.outputs import check_out_dir, write_files

    if not bench_id.strip():
        raise InputError("--id", "", "empty: name the profile")
    check_out_dir(out_dir, FIXED, force)
    report = run_identify(list(recordings), None if base is None else load_bench(base, "--base", ""))
    files, result = list(report.files), report.result
    title = name or f"identified from {len(files)} recordings"
    outputs = identify_files(result, files, result.profile, bench_id, title)
    written = write_files(out_dir, outputs, force=force)
    if as_json:
        click.echo(outputs["report.json"].decode(), nl=False)
    else:
        print_identification(result, written, out_dir)
