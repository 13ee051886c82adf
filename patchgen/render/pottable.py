"""The pot-setting table: CSV for files, a rich table for the terminal."""

from __future__ import annotations

import csv
import io
import re

from rich.console import Console
from rich.table import Table

from patchgen.patch.netlist import Netlist
from patchgen.patch.snr_scaling import dial_limits
from patchgen.profiles.machine import MachineProfile, the_machine
from patchgen.render.terminal import add_row, number, show, table, text

COLUMNS = ("pot", "setting", "signal", "amplifier", "input", "weight", "coefficient", "realized", "error_pct",
           "step_limits", "note")


def print_patch(net: Netlist, machine: MachineProfile, written: list, console: Console | None = None) -> None:
    """The patch on the terminal: its pot table (set as the machine's procedure says), its notes,
    and the files written."""
    console = console or Console()
    show(console, pot_table(net, machine.procedure.pot_setting))
    for n in net.notes:
        console.print(f"[yellow]note:[/yellow] {n}")
    console.print("wrote " + ", ".join(str(p) for p in written))


def pot_rows(net: Netlist) -> list[dict]:
    """One plain row per pot: setting, signal, where it goes, coefficient wanted and realised."""
    rows = []
    for p in net.pots:
        err = p.error
        rows.append({"pot": p.id, "setting": f"{p.setting:.3f}", "signal": p.signal, "amplifier": p.amplifier,
                     "input": p.jack, "weight": p.weight, "coefficient": f"{p.coefficient:.6g}",
                     "realized": f"{p.realized:.6g}",
                     "error_pct": "inf" if err == float("inf") else f"{100 * err:+.3f}",
                     "step_limits": "yes" if dial_limits(p.setting, net.pot_resolution) else "", "note": p.note})
    return rows


def pots_csv(net: Netlist) -> str:
    """The pot table as CSV (pots.csv)."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    w.writeheader()
    w.writerows(pot_rows(net))
    return buf.getvalue()


def pot_table(net: Netlist, pot_setting: str) -> Table:
    """The pot table for the terminal, a row a line at 80 columns; ``pot_setting`` says how the
    machine's pots are set (its profile's procedure.pot_setting); a setting whose dial step limits
    its coefficient (patchgen.patch.snr_scaling.dial_limits) is marked *."""
    t = table(f"Pot settings for {net.design} on {the_machine(net.machine_name)} ({pot_setting})",
              text("pot"), number("setting"), text("signal"), text("into"), number("coefficient"),
              number("realised"), number("error"))
    for r in pot_rows(net):  # a setting the dial limits (its step over DIAL_SHARE of it) marked *
        add_row(t, r["pot"], r["setting"] + (" *" if r["step_limits"] else ""), r["signal"],
                _into(r["amplifier"], r["input"], r["weight"]),
                r["coefficient"], r["realized"], "n/a" if r["error_pct"] == "inf" else _error(float(r["error_pct"])))
    return t


def _into(amplifier: str, jack: str, weight: int) -> str:
    """The amplifier and jack, with the input's weight when the jack's name does not say it (x10a does)."""
    return f"{amplifier} {jack}" + ("" if re.fullmatch(rf"x{weight}\D*", jack) else f" (x{weight})")


def _error(pct: float) -> str:
    """A pot's error in per cent, three decimals, or three significant digits from 100 % up (pots.csv
    keeps every decimal)."""
    return (f"{pct:+.3f}" if abs(pct) < 100 else f"{pct:+.3g}") + " %"
