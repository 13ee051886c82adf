"""patchgen sweep on the terminal: the LQR gain, the margins and the nominal patch's outcome, and
the pots that would change, per plant with one parameter off (patchgen.studies.sweep's rows), in
tables that fit 80 columns, a plant a line or two in each (--json has every pot)."""

from __future__ import annotations

from rich.console import Console

from patchgen.design.lqg import Design
from patchgen.render.terminal import add_row, figure, number, show, table, text
from patchgen.studies.sweep import SweepRow

POTS_SHOWN = 4  # pots named per plant: those whose setting moves most
GAIN_DIGITS = 4  # decimals of a gain, as thesis tables 4.1 and 4.2 print them
COLUMN_GAP = 2  # spaces between the columns of a table (patchgen.render.terminal.table)


def print_sweep(d: Design, rows: list[SweepRow], by: float, console: Console | None = None) -> None:
    """The sweep's rows as three tables: the gains (the nominal design's states as columns, split
    in two when they would not fit the console), the margins and the nominal patch on each plant,
    and the pots that would change."""
    console = console or Console()
    states = list(d.states)
    gains = [[f"{k:.{GAIN_DIGITS}f}" for k in r.K] for r in rows]
    for part in _split(states, gains, [r.label for r in rows], console.width):
        t = table(f"{d.spec.name}: LQR gain K (u = -K x) with parameters off by {by:.0%}", text("case"),
                  *(number(states[i]) for i in part))
        for r, g in zip(rows, gains):
            add_row(t, r.label, *(g[i] for i in part))
        show(console, t)
    show(console, _margins_table(d, rows))
    pots = table("Pots that would change (nominal setting → this plant's; those that move most)", text("case"),
                 number("pots changed", justify="left"))
    room = console.width - COLUMN_GAP - max(len(x) for x in ["case", *(r.label for r in rows)])
    for r in rows:
        add_row(pots, r.label, "does not patch (below)" if r.patch_error else _pots(r.pot_changes, room))
    show(console, pots)
    errors: dict[str, list[str]] = {}
    for r in rows:
        if r.patch_error:
            errors.setdefault(r.patch_error, []).append(r.label)
    for message, labels in errors.items():
        console.print(f"does not patch ({', '.join(labels)}): {message}", style="yellow", highlight=False)


def _margins_table(d: Design, rows: list[SweepRow]):
    """Per plant: the LQR margins, the loop's with the estimator, and the nominal patch on that plant."""
    cols = [text("case"), number("LQR GM\n(dB)"), number("PM\n(deg)")]
    if d.estimator is not None:
        cols += [number("loop GM (dB)\nlower..upper"), number("PM\n(deg)")]
    cols += [text("nominal patch:\nloop on bench"), number("held"), number("max |θ|\n(deg)")]
    t = table("Margins, and the nominal patch (as wired) on each plant", *cols)
    for r in rows:
        cells = [r.label, _db(r.lqr_margins.lower_gm_db), figure(r.lqr_margins.pm_deg, "{:.1f}")]
        if d.estimator is not None:
            m = r.lqg_margins
            cells += (["unstable", ""] if not m.stable else
                      [f"{_db(m.lower_gm_db)}..{_db(m.upper_gm_db)}", figure(m.pm_deg, "{:.1f}")])
        o = r.outcome
        cells += (["-", "-", "-"] if o is None else
                  [o["bench_loop"], f"{100 * o['fraction_held']:.0f} %", f"{o['max_abs_theta_deg']:.1f}"])
        add_row(t, *cells)
    return t


def _db(x: float | None) -> str:
    return "inf" if x is None else figure(x, "{:+.2f}")


def _pots(changes: dict[str, tuple[float, float]], width: int) -> str:
    """The pots whose setting moves most, in the patch's order, as many a line as ``width`` takes
    (a pot never parted from its settings), and how many more move."""
    if not changes:
        return "none"
    top = sorted(changes, key=lambda p: -abs(changes[p][1] - changes[p][0]))[:POTS_SHOWN]
    shown = [f"{p} {a:.3f}→{b:.3f}" for p, (a, b) in changes.items() if p in top]
    more = len(changes) - len(top)
    if more:
        shown.append(f"and {more} more")
    per_line = max(1, (width + 2) // (max(map(len, shown)) + 2))
    return ",\n".join(", ".join(shown[i:i + per_line]) for i in range(0, len(shown), per_line))


def _split(states: list[str], gains: list[list[str]], labels: list[str], width: int) -> list[list[int]]:
    """The gain columns in as few consecutive groups as fit ``width`` beside the case column."""
    case = max(len(x) for x in ["case", *labels])
    wide = [max(len(states[i]), *(len(g[i]) for g in gains)) for i in range(len(states))]
    parts: list[list[int]] = [[]]
    used = case
    for i, w in enumerate(wide):
        if parts[-1] and used + COLUMN_GAP + w > width:
            parts.append([])
            used = case
        parts[-1].append(i)
        used += COLUMN_GAP + w
    return parts
