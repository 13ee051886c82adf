"""`patchgen patch SPEC -o DIR`: netlist, pot table, patch sheet and wiring diagram."""

from __future__ import annotations

import json

import click
from rich.console import Console

from patchgen.design.model import plant_params
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import load_bench
from patchgen.render.diagram import wiring_svg
from patchgen.render.outputs import check_out_dir, write_files
from patchgen.render.pottable import pot_rows, pot_table, pots_csv
from patchgen.render.sheet import SheetSection, SheetSummary, render_sheet

from . import cli
from .design import design_from_path


def sheet_summary(d, sections=()) -> SheetSummary:
    """The design as the patch sheet summarises it."""
    margins = {"LQR (state feedback)": _margin_cells(d.lqr_margins)}
    if d.estimator is not None and d.lqg_margins is not None:
        margins[f"as patched ({d.estimator.kind})"] = _margin_cells(d.lqg_margins)
    kind = "none (all states measured)" if d.estimator is None else d.estimator.kind
    if d.estimator is not None and d.estimator.rolloff_s:
        kind += f", roll-off {d.estimator.rolloff_s:g} s"
    return SheetSummary(design=d.spec.name, description=d.spec.description, states=list(d.states),
                        K=[float(k) for k in d.K[0]], poles=list(d.closed_loop_poles), margins=margins,
                        estimator=kind, sections=list(sections))


def _margin_cells(m) -> dict[str, str]:
    if not m.stable:
        return {"stable": "no"}
    return {"lower GM": "none" if m.lower_gm is None else f"{m.lower_gm:.4f} ({m.lower_gm_db:+.2f} dB)",
            "upper GM": "inf" if m.upper_gm is None else f"{m.upper_gm:.4f} ({m.upper_gm_db:+.2f} dB)",
            "PM": "-" if m.pm_deg is None else f"{m.pm_deg:.2f} deg",
            "delay margin": "-" if m.delay_margin_s is None else f"{m.delay_margin_s * 1000:.1f} ms"}


def bench_section(d, machine, net, runs_hold: int, done=None) -> SheetSection:
    """'Predicted on the bench' from the standard scenarios (``done``: see prediction.predict)."""
    from patchgen.bench.prediction import (  # the simulator: numba, only here
        diagnosis_note,
        predict,
        prediction_rows,
    )

    bench = load_bench(d.spec.bench, d.spec.path)
    plant = plant_params(d.spec)
    header, rows = prediction_rows(predict(net, plant, bench, machine, runs_hold=runs_hold, done=done))
    note = (f"From this netlist on the {bench.id} bench: actuator {bench.actuator.model} {bench.actuator.tau:g} s, "
            f"dead zone +/-{bench.actuator.dead_zone_V:g} V, {bench.actuator.force_limit_N:g} N; sensor noise; drift "
            f"{1000 * machine.integrator_drift_V_per_s():.1f} mV/s (profile default, no GP-6 figure published); "
            f"rails +/-{machine.imperfections.saturation_V:g} V; switches at +/-{d.spec.plant.d / 2:g} m. "
            + diagnosis_note(net, plant, bench))
    return SheetSection("Predicted on the bench", header, rows, note)


PATCH_FILES = ("netlist.json", "pots.csv", "wiring.svg", "patch-sheet.html", "patch-sheet.md")


def patch_files(d, machine, net, extra_sections=(), runs_hold: int = 20, predict_bench: bool = True,
                done=None) -> dict[str, str]:
    """Every file of a patch, rendered in memory (nothing is written until all are ready)."""
    files = {"netlist.json": net.to_json(), "pots.csv": pots_csv(net)}
    sections = list(extra_sections)
    if predict_bench:
        sections.insert(0, bench_section(d, machine, net, runs_hold, done))
    svg = wiring_svg(net)
    html, md = render_sheet(net, sheet_summary(d, sections), svg)
    files.update({"wiring.svg": svg, "patch-sheet.html": html, "patch-sheet.md": md})
    return files


@cli.command("patch")
@click.argument("spec")
@click.option("-o", "--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Directory for netlist.json, pots.csv, patch-sheet.html/.md and wiring.svg.")
@click.option("--force", is_flag=True, help="Replace output files that already exist.")
@click.option("--runs", "runs_hold", default=20, show_default=True, type=click.IntRange(1, 10000),
              help="Noise seeds for the 120 s hold in the sheet's bench prediction.")
@click.option("--no-predict", is_flag=True, help="Leave the bench prediction off the sheet (faster).")
@click.option("--json", "as_json", is_flag=True, help="Print the pot table, amplifiers and notes as JSON.")
def patch_cmd(spec: str, out_dir: str, force: bool, runs_hold: int, no_predict: bool, as_json: bool) -> None:
    """Scale SPEC's gains, allocate the machine and write the patch: netlist.json, pots.csv,
    patch-sheet.html, patch-sheet.md (with the bench prediction) and wiring.svg."""
    check_out_dir(out_dir, PATCH_FILES, force)
    d, machine = design_from_path(spec)
    net = build_patch(d, machine)
    written = write_files(out_dir, patch_files(d, machine, net, runs_hold=runs_hold,
                                               predict_bench=not no_predict), force=force)
    if as_json:
        click.echo(json.dumps({"design": net.design, "machine": net.machine, "units": net.units,
                               "pots": pot_rows(net), "amplifiers": [{"id": a.id, "role": a.role,
                                                                      "carries": a.carries.model_dump()}
                                                                     for a in net.amplifiers],
                               "notes": net.notes, "written": [str(p) for p in written]},
                              indent=2, sort_keys=True, allow_nan=False))
        return
    console = Console()
    console.print(pot_table(net))
    for n in net.notes:
        console.print(f"[yellow]note:[/yellow] {n}")
    console.print("wrote " + ", ".join(str(p) for p in written))
