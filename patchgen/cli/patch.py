"""`patchgen patch SPEC -o DIR`: netlist, pot table, patch sheet and wiring diagram."""

from __future__ import annotations

import click

from patchgen.pipeline.inputs import load_inputs
from patchgen.pipeline.patch import PatchPlan, run_patch
from patchgen.pipeline.prediction import HOLD_RUNS
from patchgen.render.bench_sheet import patch_report_files
from patchgen.render.outputs import check_out_dir, json_text, write_files
from patchgen.render.patchfiles import PATCH_FILES
from patchgen.render.pottable import pot_rows, print_patch

from . import cli
from .options import FORCE, MACHINE, json_option, out_option


@cli.command("patch")
@click.argument("spec")
@out_option("netlist.json, margins.json, pots.csv, patch-sheet.html/.md, wiring.svg and static-check.csv")
@FORCE
@click.option("--runs", "runs_hold", default=HOLD_RUNS, show_default=True, type=click.IntRange(1, 10000),
              help="Noise seeds for the 120 s hold in the sheet's bench prediction.")
@click.option("--no-predict", is_flag=True, help="Leave the bench prediction off the sheet (faster).")
@MACHINE
@json_option("the pot table, amplifiers, notes, margins and bench prediction")
def patch_cmd(spec: str, out_dir: str, force: bool, runs_hold: int, no_predict: bool, machine: str | None,
              as_json: bool) -> None:
    """Scale SPEC's gains, allocate the machine and write the patch: netlist.json, margins.json (the
    loop as patched beside the design's), pots.csv, patch-sheet.html, patch-sheet.md (with the bench
    prediction), wiring.svg and static-check.csv (the readings for patchgen check)."""
    check_out_dir(out_dir, PATCH_FILES, force)
    inputs = load_inputs(spec, machine=machine, command="patch")
    report = run_patch(inputs, PatchPlan(runs_hold=runs_hold, predict=not no_predict))
    written = write_files(out_dir, patch_report_files(report, inputs.machine, inputs.bench), force=force)
    if as_json:
        click.echo(json_text({**report.summary(), "pots": pot_rows(report.netlist),
                              "written": [str(p) for p in written]}), nl=False)
        return
    print_patch(report.netlist, inputs.machine, written)
