"""`patchgen spice SPEC --scenario X -o DIR`: the patch checked at the electrical level by ngspice."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import click
import numpy as np
from rich.console import Console
from rich.table import Table

from patchgen.bench.noise_drift import noise_and_drift
from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.patch.build import build_patch
from patchgen.render import plot_helper
from patchgen.render.outputs import check_out_dir, json_text, write_files
from patchgen.render.spice_plot import comparison_plot
from patchgen.spice.compare import compare
from patchgen.spice.deck import OPAMP_MODEL, SpiceSettings, spice_deck
from patchgen.spice.run import NgspiceError, NgspiceMissing, run_ngspice

from . import cli
from .inputs import check_spice_points, load_inputs, scenario_for
from .options import SCENARIO, FiniteFloat, out_option

SPICE_FILES = ("patch.cir", "patch.data", "comparison.json", "overlay.png", "overlay.svg")

NO_NGSPICE_STATUS = NgspiceMissing.exit_status
RECORD_EVERY_STEP_S = 1e-6  # a history interval below any engine step: the reference at every step
STATISTICAL = ("the deck draws its own noise, random-force and drift samples (the same levels, another "
               "realisation), so the runs differ by that; --ideal compares like with like")


class _Own:
    """patchgen's own run as a trajectory (t and named signals, SI and volts)."""

    def __init__(self, history: dict[str, np.ndarray]):
        self.t = history["t"]
        self.signals = {k: v for k, v in history.items() if k != "t"}


@cli.command("spice")
@click.argument("spec")
@SCENARIO
@out_option("the deck, ngspice's data, the comparison and its overlay plot")
@click.option("--ideal", is_flag=True, help="Noise and drift off and the actuator a pure gain, as patchgen "
              "simulate --ideal; the op-amp macromodels (finite gain, output limits) stay.")
@click.option("--step", "step_s", type=FiniteFloat(1e-5, 0.1), default=0.005, show_default=True,
              help="Output step of the transient (s).")
@click.option("--tolerance", type=FiniteFloat(0, 1), default=0.01, show_default=True,
              help="Agreement required, as a fraction of each signal's peak.")
@click.option("--svg", is_flag=True, help="Also write the overlay plot as overlay.svg (PNG only by default).")
@click.option("--json", "as_json", is_flag=True, help="Print the comparison as JSON.")
@click.option("--force", is_flag=True, help="Replace output files that already exist.")
def spice_cmd(spec, scenario_path, out_dir, ideal, step_s, tolerance, svg, as_json, force) -> None:
    """Export SPEC's patch and the bench as an ngspice deck, run it, and compare with patchgen's own
    simulation of the same scenario. Exit 0 when they agree within --tolerance, 1 when not,
    3 without ngspice (the deck is still written)."""
    check_out_dir(out_dir, SPICE_FILES, force)
    plot_helper.start()  # matplotlib loads on the other core while ngspice runs
    sp, machine, bench = load_inputs(spec)
    scenario = scenario_for(scenario_path, sp, 1, ideal)
    check_spice_points(scenario, step_s)
    d = design_on(sp, machine, bench)
    net = build_patch(d, machine)
    plant = plant_params(d.spec)
    levels = noise_and_drift([s.id for s in net.sensors], bench, machine, scenario, ideal)
    settings = SpiceSettings(duration_s=scenario.duration_s, step_s=step_s, x0=tuple(scenario.initial.vector()),
                             noise_and_drift=levels, actuator="ideal" if ideal else "bench",
                             seed=scenario.seed, disturbances=tuple(scenario.on_pendulum(plant).disturbances))
    deck = spice_deck(net, plant, bench, machine, settings)
    files: dict[str, str | bytes] = {"patch.cir": deck.text}
    for name, data in deck.files.items():
        files[name] = data
    try:
        with tempfile.TemporaryDirectory() as tmp:
            sp = run_ngspice(deck, tmp)
            data = Path(tmp, "patch.data")
            if data.exists():
                files["patch.data"] = data.read_bytes()
    except NgspiceMissing as exc:
        write_files(out_dir, files, force=force)
        click.echo(f"patchgen: {exc} (deck written to {Path(out_dir) / 'patch.cir'})", err=True)
        sys.exit(NO_NGSPICE_STATUS)
    except NgspiceError as exc:
        write_files(out_dir, files, force=force)
        click.echo(f"patchgen: ngspice failed: {exc}", err=True)
        sys.exit(NgspiceError.exit_status)
    # the reference at every step of patchgen's own integrator, evaluated at ngspice's time points
    every_step = scenario.model_copy(update={"record_dt_s": RECORD_EVERY_STEP_S})
    own = simulate(net, plant, bench, machine, every_step, ideal=ideal)
    cmp = compare(sp, _Own(own.history))
    plots = plot_helper.submit(comparison_plot, cmp, "overlay", f"{d.spec.name}: ngspice vs "
                               f"patchgen ({scenario.name}{', ideal' if ideal else ''})", "patchgen", svg)
    files.update(plots.result())
    report = {"design": d.spec.name, "scenario": scenario.name, "ideal": ideal, "tolerance": tolerance,
              "ngspice_run_time_s": sp.run_time_s, "compared_at": f"ngspice's {len(cmp.t)} time points",
              "opamp_model": OPAMP_MODEL, "statistical": not ideal,
              "signals": {k: {"rms_rel": v.rms_rel, "max_rel": v.max_rel, "peak": v.peak}
                          for k, v in cmp.signals.items()},
              "agrees": cmp.agrees(tolerance)}
    files["comparison.json"] = json_text(report)
    written = write_files(out_dir, files, force=force)
    if as_json:
        click.echo(json_text(report), nl=False)
    else:
        t = Table(title=f"ngspice against patchgen: {d.spec.name}, {scenario.name}"
                  + (" (ideal: noise, drift off; ideal actuator; op-amp macromodels)" if ideal else ""),
                  title_justify="left")
        for c in ("signal", "peak", "RMS difference", "largest difference"):
            t.add_column(c, justify="right" if c != "signal" else "left")
        for k, v in cmp.signals.items():
            t.add_row(k, f"{v.peak:.4g}", f"{100 * v.rms_rel:.3f} % of peak", f"{100 * v.max_rel:.3f} % of peak")
        console = Console()
        console.print(t)
        console.print(("[green]agree[/green]" if report["agrees"] else "[red]disagree[/red]")
                      + f" within {100 * tolerance:g} % of peak at ngspice's {len(cmp.t)} time points; "
                      f"ngspice ran {sp.run_time_s:.2f} s")
        console.print(f"op-amp model: {OPAMP_MODEL}")
        if not ideal:
            console.print(f"[yellow]not --ideal:[/yellow] {STATISTICAL}")
        console.print("wrote " + ", ".join(str(p) for p in written))
    if not report["agrees"]:
        sys.exit(1)
