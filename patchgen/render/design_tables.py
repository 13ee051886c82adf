"""The design report on the terminal (thesis section 4.5 style): gains, poles, zeros, estimator and
margins as rich tables, from the design (its data: patchgen.design.report)."""

from __future__ import annotations

from rich.console import Console
from rich.table import Table

from patchgen.design.lqg import Design
from patchgen.design.margins import Margins
from patchgen.design.precision import gain_text, significant_digits
from patchgen.design.report import design_notes
from patchgen.render.terminal import add_row, figure, number, show, table, text

REPORT_DIGITS = 7  # significant digits of a gain in the report (the thesis prints -249.4119)
SMALL_POLE = 1e-3  # 1/s: a pole nearer the origin than this prints in significant digits, not four decimals
REAL_POLE = 1e-9  # 1/s: an imaginary part below this is rounding; the pole prints as real


def _f(x: float | None, fmt: str = ".4g") -> str:
    return "inf" if x is None else figure(x, "{:" + fmt + "}")


def _poles(ps) -> str:
    def num(x: float) -> str:
        return f"{x:.4f}" if abs(x) >= SMALL_POLE or x == 0 else f"{x:.2g}"

    out = []
    for p in ps:
        if abs(p.imag) < REAL_POLE:
            out.append(num(p.real))
        elif p.imag > 0:
            out.append(f"{num(p.real)} ± {p.imag:.4f}i")
    return ", ".join(out)


def margins_table(rows: list[tuple[str, Margins | None]], title: str = "Loop margins at the plant input") -> Table:
    """One row per named loop (those without margins left out) for the terminal; a gain margin
    as the factor over its value in dB."""
    t = table(title, text("loop"), number("lower GM"), number("upper GM"), number("PM (deg)"),
              number("at (rad/s)"), number("delay (s)"))
    for name, m in rows:
        if m is None:
            continue
        if not m.stable:
            add_row(t, name, "unstable", "", "", "", "")
            continue
        low = "none" if m.lower_gm is None else f"{m.lower_gm:.4f}\n{m.lower_gm_db:+.2f} dB"
        up = "inf" if m.upper_gm is None else f"{m.upper_gm:.4f}\n{m.upper_gm_db:+.2f} dB"
        add_row(t, name, low, up, _f(m.pm_deg, ".2f"), _f(m.pm_freq, ".3g"), _f(m.delay_margin_s, ".4f"))
    return t


def print_design(d: Design, console: Console | None = None) -> None:
    """The design report on the terminal: gains, poles, zeros, estimator, margins."""
    console = console or Console()
    spec = d.spec
    console.print(f"[bold]{spec.name}[/bold]  {spec.description}")
    if spec.source:
        console.print(f"source: {spec.source}")
    plant = spec.plant_model
    console.print(f"actuator model (design): {spec.actuator.model}, K_U = {spec.actuator.K_U} {plant.input_unit}/V"
                  + (f", tau = {spec.actuator.tau} s" if spec.actuator.model != "gain" else ""))
    for note in design_notes(d):
        console.print(f"[yellow]note:[/yellow] {note}")
    g = table(f"LQR gain (u = -K x, {plant.input_noun} in {plant.input_unit})", text("state"), number("Q"),
              number("K"))
    cut = []
    for i, s in enumerate(d.states):
        gain, flagged = gain_text(float(d.K[0, i]), float(d.spread.K[0, i]), REPORT_DIGITS)
        add_row(g, s, f"{d.Q[i, i]:g}", gain + (" *" if flagged else ""))
        if flagged:
            n = significant_digits(float(d.K[0, i]), float(d.spread.K[0, i]))
            cut.append(f"{s} to {n} significant digits" if n else f"{s} not beyond its size")
    show(console, g)
    if cut:
        console.print(f"[yellow]*[/yellow] the Riccati equation fixes {'; '.join(cut)} (a nearly uncontrollable "
                      f"mode), fewer than the {REPORT_DIGITS} printed elsewhere: further digits would follow the "
                      "machine's arithmetic, not the design")
    console.print(f"R = {d.R[0, 0]:g}")
    p = table("Poles and zeros", text(""), text("values"))
    add_row(p, "open loop", _poles(d.open_loop_poles))
    add_row(p, "closed loop (A - B K)", _poles(d.closed_loop_poles))
    for k, v in d.zeros.items():
        add_row(p, f"zeros of {k}", _poles(v))
    if d.estimator is not None:
        add_row(p, f"estimator ({d.estimator.kind.replace('_', ' ')})", _poles(d.estimator.poles))
    show(console, p)
    e = d.estimator
    if e is not None and e.kind == "kalman":
        L = table(f"Kalman gain L (rho = {e.rho:g}); columns s, theta, s_dot", text("state"),
                  *(number(m) for m in d.model.measured))
        for i, s in enumerate(e.states):
            add_row(L, s, *(f"{v:.4f}" for v in e.L[i]))
        show(console, L)
        if len(e.rho_tries) > 1 or spec.estimator.rho == "auto":
            r = table("Loop transfer recovery: rho tries (within 1 dB / 5 deg of LQR?)",
                      *(number(c) for c in ("rho", "lower GM (dB)", "upper GM (dB)", "PM (deg)", "accepted")))
            for t in e.rho_tries:
                m = t.margins
                add_row(r, f"{t.rho:g}", _f(m.lower_gm_db, ".2f"), _f(m.upper_gm_db, ".2f"), _f(m.pm_deg, ".2f"),
                        "yes" if t.accepted else "no")
            show(console, r)
    rows = [("LQR", d.lqr_margins)]
    if e is not None and e.kind == "kalman":
        rows.append(("LQG (rho = 1)", e.margins_rho1))
        rows.append((f"LQG + LTR (rho = {e.rho:g})", d.lqg_margins))
    elif e is not None:
        rows.append((f"differentiator (roll-off {e.rolloff_s:g} s)", d.lqg_margins))
    show(console, margins_table(rows))
