"""`patchgen patch SPEC -o DIR`: netlist, pot table, patch sheet and wiring diagram."""

from __future__ import annotations

import click
from rich.console import Console

from ..outputs import write_files
from ..patch import build_patch
from ..pottable import pot_table, pots_csv
from . import cli
from .design import design_from_path


def patch_files(d, machine, net, extra_sections=()) -> dict[str, str]:
    """Every file of a patch, rendered in memory (nothing is written until all are ready)."""
    files = {"netlist.json": net.to_json(), "pots.csv": pots_csv(net)}
    try:
        from ..diagram import wiring_svg
        from ..sheet import render_sheet, summary_from_design
    except ImportError:  # drawing and sheet stages not present
        return files
    svg = wiring_svg(net)
    html, md = render_sheet(net, summary_from_design(d, extra_sections), svg)
    files.update({"wiring.svg": svg, "patch-sheet.html": html, "patch-sheet.md": md})
    return files


@cli.command("patch")
@click.argument("spec", type=click.Path(dir_okay=False))
@click.option("-o", "--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Directory for netlist.json, pots.csv, patch-sheet.html/.md and wiring.svg.")
@click.option("--force", is_flag=True, help="Replace output files that already exist.")
def patch_cmd(spec: str, out_dir: str, force: bool) -> None:
    """Scale SPEC's gains, allocate the machine and write the patch."""
    d, machine = design_from_path(spec)
    net = build_patch(d, machine)
    written = write_files(out_dir, patch_files(d, machine, net), force=force)
    console = Console()
    console.print(pot_table(net))
    for n in net.notes:
        console.print(f"[yellow]note:[/yellow] {n}")
    console.print("wrote " + ", ".join(str(p) for p in written))
