"""patchgen sweep on the terminal: the LQR gain, the margins, the pots that would change and the
nominal patch's outcome, per plant with one parameter off (patchgen.studies.sweep's rows)."""

from __future__ import annotations

from rich.console import Console
from rich.table import Table

from patchgen.design.lqg import Design
from patchgen.studies.sweep import SweepRow


def _db(x):
    return "inf" if x is None else f"{x:+.2f}"


def print_sweep(d: Design, rows: list[SweepRow], by: float) -> None:
    """The sweep's rows as one table (the nominal design's states as its gain columns)."""
    states = list(d.states)
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
