"""The files of a patch, rendered in memory: netlist, pot table, wiring diagram and patch sheets.

Every command that writes a patch (patch, recommend, swingup) writes this set, through the
all-or-nothing writer (patchgen.render.outputs.write_files); the sheet's extra sections (the bench
prediction, why this patch, a pump-up schedule) come from the caller.
"""

from __future__ import annotations

from collections.abc import Sequence

from patchgen.design.lqg import Design
from patchgen.design.margins import Margins
from patchgen.patch.netlist import Netlist
from patchgen.profiles.machine import MachineProfile
from patchgen.render.diagram import wiring_svg
from patchgen.render.pottable import pots_csv
from patchgen.render.sheet import SheetSection, SheetSummary, render_sheet

PATCH_FILES = ("netlist.json", "pots.csv", "wiring.svg", "patch-sheet.html", "patch-sheet.md")


def sheet_summary(d: Design, sections: Sequence[SheetSection] = ()) -> SheetSummary:
    """The design as the patch sheet summarises it: gains, poles, margins, estimator.

    Parameters
    ----------
    d : Design
        The design the patch realises.
    sections : sequence of SheetSection
        Extra tables for the sheet, in order.

    Returns
    -------
    SheetSummary
        What :func:`patchgen.render.sheet.render_sheet` shows beside the netlist.
    """
    margins = {"LQR (state feedback)": _margin_cells(d.lqr_margins)}
    if d.estimator is not None and d.lqg_margins is not None:
        margins[f"as patched ({d.estimator.kind})"] = _margin_cells(d.lqg_margins)
    kind = "none (all states measured)" if d.estimator is None else d.estimator.kind
    if d.estimator is not None and d.estimator.rolloff_s:
        kind += f", roll-off {d.estimator.rolloff_s:g} s"
    return SheetSummary(design=d.spec.name, description=d.spec.description, states=list(d.states),
                        K=[float(k) for k in d.K[0]], poles=list(d.closed_loop_poles), margins=margins,
                        estimator=kind, sections=list(sections))


def _margin_cells(m: Margins) -> dict[str, str]:
    if not m.stable:
        return {"stable": "no"}
    return {"lower GM": "none" if m.lower_gm is None else f"{m.lower_gm:.4f} ({m.lower_gm_db:+.2f} dB)",
            "upper GM": "inf" if m.upper_gm is None else f"{m.upper_gm:.4f} ({m.upper_gm_db:+.2f} dB)",
            "PM": "-" if m.pm_deg is None else f"{m.pm_deg:.2f} deg",
            "delay margin": "-" if m.delay_margin_s is None else f"{m.delay_margin_s * 1000:.1f} ms"}


def patch_files(d: Design, machine: MachineProfile, net: Netlist,
                sections: Sequence[SheetSection] = ()) -> dict[str, str]:
    """Every file of a patch (PATCH_FILES), rendered in memory; nothing is written.

    Parameters
    ----------
    d : Design
        The design the patch realises.
    machine : MachineProfile
        The machine the patch is allocated on.
    net : Netlist
        The patch.
    sections : sequence of SheetSection
        Extra tables for the sheet, in order.

    Returns
    -------
    dict
        File name -> text, for :func:`patchgen.render.outputs.write_files`.
    """
    files = {"netlist.json": net.to_json(), "pots.csv": pots_csv(net)}
    svg = wiring_svg(net)
    html, md = render_sheet(net, sheet_summary(d, sections), svg, machine.procedure)
    files.update({"wiring.svg": svg, "patch-sheet.html": html, "patch-sheet.md": md})
    return files
