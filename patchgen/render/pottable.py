"""The pot-setting table: CSV for files, a rich table for the terminal."""

from __future__ import annotations

import csv
import io

from rich.console import Console
from rich.table import Table

from patchgen.patch.netlist import Netlist
from patchgen.profiles.machine import MachineProfile, the_machine

COLUMNS = ("pot", "setting", "signal", "amplifier", "input", "weight", "coefficient", "realized", "error_pct", "note")


def print_patch(net: Netlist, machine: MachineProfile, written: list, console: Console | None = None) -> None:
    """The patch on the terminal: its pot table (set as the machine's procedure says), its notes,
    and the files written."""
    console = console or Console()
    console.print(pot_table(net, machine.procedure.pot_setting))
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
                     "error_pct": "inf" if err == float("inf") else f"{100 * err:+.3f}", "note": p.note})
    return rows


def pots_csv(net: Netlist) -> str:
    """The pot table as CSV (pots.csv)."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    w.writeheader()
    w.writerows(pot_rows(net))
    return buf.getvalue()


def pot_table(net: Netlist, pot_setting: str) -> Table:
    """The pot table for the terminal; ``pot_setting`` says how the machine's pots are set (its
    profile's procedure.pot_setting)."""
    t = Table(title=f"Pot settings for {net.design} on {the_machine(net.machine_name)} ({pot_setting})",
              title_justify="left")
    for c, j in (("pot", "left"), ("setting", "right"), ("signal", "left"), ("into", "left"),
                 ("coefficient", "right"), ("realised", "right"), ("error", "right")):
        t.add_column(c, justify=j)
    for r in pot_rows(net):
        t.add_row(r["pot"], r["setting"], r["signal"], f"{r['amplifier']} {r['input']} (x{r['weight']})",
                  r["coefficient"], r["realized"], r["error_pct"] + " %" if r["error_pct"] != "inf" else "n/a")
    return t
