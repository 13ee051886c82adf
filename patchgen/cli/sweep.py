"""`patchgen sweep SPEC --vary M,m,l,b_VF,c --by 10%`: gains, margins and pots per perturbed plant."""

from __future__ import annotations

import click
from rich.console import Console
from rich.table import Table

from patchgen.design.lqg import design_on
from patchgen.plant.cart_pendulum import UNCERTAIN
from patchgen.render.outputs import json_text
from patchgen.studies.sweep import sweep

from . import cli
from .inputs import load_inputs, scenario_for
from .options import parse_by, parse_vary


def _db(x):
    return "inf" if x is None else f"{x:+.2f}"


@cli.command("sweep")
@click.argument("spec")
@click.option("--vary", default=",".join(UNCERTAIN), show_default=True,
              help="Parameters to vary, comma-separated.")
@click.option("--by", "by_text", default="10%", show_default=True, help="Relative change, e.g. 10%.")
@click.option("--workers", default=0, type=click.IntRange(0, 64), help="Processes (0: one per core).")
@click.option("--scenario", "scenario_path", default="offset-10deg", show_default=True,
              help="Scenario (shipped name or TOML file) for the nominal patch's predicted outcome.")
@click.option("--runs", type=click.IntRange(1, 10000), default=1, show_default=True,
              help="Noise seeds per row for the predicted outcome.")
@click.option("--json", "as_json", is_flag=True, help="Print the rows as JSON.")
def sweep_cmd(spec: str, vary: str, by_text: str, workers: int, scenario_path: str, runs: int, as_json: bool) -> None:
    """Re-design SPEC with each plant parameter off by --by (thesis tables 4.1, 4.2): the gains, the
    margins, the pots that would change, and how the nominal patch (as wired) does on that plant."""
    names, by = parse_vary(vary), parse_by(by_text)
    sp, machine, bench = load_inputs(spec)
    scenario = scenario_for(scenario_path, sp, runs)  # a bad scenario fails here, in one line
    d = design_on(sp, machine, bench)
    rows = sweep(d.spec, machine, names, by, workers, scenario, runs, bench=bench)
    states = list(d.states)
    if as_json:
        click.echo(json_text([r.as_dict() for r in rows]), nl=False)
        return
    t = Table(title=f"{d.spec.name}: LQR gain K (u = -K x) with parameters off by {by:.0%}", title_justify="left")
    t.add_column("case")
    for s in states:
        t.add_column(s, justify="right")
    t.add_column("LQR GM/PM", justify="right")
    if d.estimator is not None:
        t.add_column("loop GM/PM", justify="right")
    t.add_column("pots changed")
    t.add_column("nominal patch on this plant")
    for r in rows:
        cells = [r.label] + [f"{k:.4f}" for k in r.K]
        cells.append(f"{_db(r.lqr_margins.lower_gm_db)} dB / {r.lqr_margins.pm_deg:.1f}°")
        if d.estimator is not None:
            m = r.lqg_margins
            cells.append("unstable" if not m.stable else f"{_db(m.lower_gm_db)}..{_db(m.upper_gm_db)} dB / "
                         f"{m.pm_deg:.1f}°")
        if r.patch_error:
            cells.append("does not patch")
        else:
            cells.append(", ".join(f"{p} {a:.3f}→{b:.3f}" for p, (a, b) in sorted(r.pot_changes.items())) or "none")
        o = r.outcome
        cells.append("-" if o is None else
                     f"loop {o['bench_loop']}, held {100 * o['fraction_held']:.0f} %, "
                     f"max |θ| {o['max_abs_theta_deg']:.1f}°")
        t.add_row(*cells)
    Console(width=max(160, Console().width)).print(t)
