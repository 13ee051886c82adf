"""`patchgen patch SPEC -o DIR`: netlist, pot table, patch sheet and wiring diagram."""

from __future__ import annotations

import click

from patchgen.bench.diagnosis import as_patched_on_bench
from patchgen.design.lqg import design_on
from patchgen.patch.build import build_patch
from patchgen.render.bench_sheet import HOLD_RUNS, predicted_patch_files
from patchgen.render.outputs import check_out_dir, json_text, write_files
from patchgen.render.patchfiles import PATCH_FILES, patch_files
from patchgen.render.pottable import pot_rows, print_patch

from . import cli
from .inputs import load_inputs
from .options import out_option


@cli.command("patch")
@click.argument("spec")
@out_option("netlist.json, pots.csv, patch-sheet.html/.md and wiring.svg")
@click.option("--force", is_flag=True, help="Replace output files that already exist.")
@click.option("--runs", "runs_hold", default=HOLD_RUNS, show_default=True, type=click.IntRange(1, 10000),
              help="Noise seeds for the 120 s hold in the sheet's bench prediction.")
@click.option("--no-predict", is_flag=True, help="Leave the bench prediction off the sheet (faster).")
@click.option("--json", "as_json", is_flag=True, help="Print the pot table, amplifiers and notes as JSON.")
def patch_cmd(spec: str, out_dir: str, force: bool, runs_hold: int, no_predict: bool, as_json: bool) -> None:
    """Scale SPEC's gains, allocate the machine and write the patch: netlist.json, pots.csv,
    patch-sheet.html, patch-sheet.md (with the bench prediction) and wiring.svg."""
    check_out_dir(out_dir, PATCH_FILES, force)
    sp, machine, bench = load_inputs(spec)
    d = design_on(sp, machine, bench)
    net = build_patch(d, machine)
    judged = as_patched_on_bench(d, net, machine, bench)
    files = (patch_files(d, machine, net, judged=judged) if no_predict
             else predicted_patch_files(d, machine, bench, net, runs_hold=runs_hold, judged=judged))
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(json_text({"design": net.design, "machine": net.machine, "units": net.units,
                              "pots": pot_rows(net), "amplifiers": [{"id": a.id, "role": a.role,
                                                                     "carries": a.carries.model_dump()}
                                                                    for a in net.amplifiers],
                              "notes": net.notes, "margins": judged.as_dict(),
                              "written": [str(p) for p in written]}), nl=False)
        return
    print_patch(net, machine, written)
