"""patchgen check on the terminal: whether the static check's readings agree with the patch and,
when not, the single faults that explain them best (patchgen.patch.fault_finding's verdict)."""

from __future__ import annotations

from rich.console import Console
from rich.markup import escape

from patchgen.patch.fault_finding import Verdict
from patchgen.patch.netlist import Netlist
from patchgen.patch.static_check import StaticCheck
from patchgen.render.terminal import add_row, number, show, table, text


def print_verdict(net: Netlist, check: StaticCheck, verdict: Verdict, console: Console | None = None) -> None:
    """The verdict in words and, for readings that disagree, the ranked faults."""
    console = console or Console()
    if verdict.agree:
        console.print(f"[green]all {len(check.readings)} readings agree[/green] with {net.design}'s patch "
                      "within their tolerances")
    else:
        console.print(f"[red]{len(verdict.mismatched)} of {len(check.readings)} readings disagree[/red]: "
                      + escape(", ".join(verdict.mismatched)))
        t = table("Likeliest faults (one at a time), best first", number("rank"), text("fault"),
                  number("explains"), number("chi-square"))
        for k, f in enumerate(verdict.faults, 1):
            add_row(t, str(k), escape(f.description), f"{f.explained} of {f.of}", f"{f.score:.3g}")
        show(console, t)
        if sum(f.consistent for f in verdict.faults) > 1:
            console.print("[yellow]more than one fault explains every reading:[/yellow] the static check cannot "
                          "tell them apart; check each in turn")
