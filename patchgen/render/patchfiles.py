"""The files of a patch, rendered in memory: netlist, pot table, wiring diagram and patch sheets.

Every command that writes a patch (patch, recommend, swingup) writes this set, through the
all-or-nothing writer (patchgen.render.outputs.write_files); the sheet's extra sections (the bench
prediction, why this patch, a pump-up schedule) come from the caller.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from patchgen.design.lqg import Design
from patchgen.inputs.resources import is_shipped_file, shipped
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.as_patched import AsPatched, as_patched
from patchgen.patch.netlist import Netlist
from patchgen.patch.sign_check import SignStep, sign_check
from patchgen.patch.static_check import StaticCheck, static_check, static_check_csv
from patchgen.profiles.machine import MachineProfile
from patchgen.render.diagram import wiring_diagram
from patchgen.render.diagram_pages import diagram_pages
from patchgen.render.margins_view import margin_cells, margins_json
from patchgen.render.pottable import pots_csv
from patchgen.render.sheet import SheetSection, SheetSummary, render_sheet

PATCH_FILES = ("netlist.json", "margins.json", "pots.csv", "static-check.csv", "wiring.svg", "patch-sheet.html",
               "patch-sheet.md")


def sheet_summary(d: Design, sections: Sequence[SheetSection] = (), judged: AsPatched | None = None,
                  signs: tuple[SignStep, ...] = (), static: SheetSection | None = None) -> SheetSummary:
    """The design as the patch sheet summarises it: gains, poles, margins, estimator.

    Parameters
    ----------
    d : Design
        The design the patch realises.
    sections : sequence of SheetSection, or a callable returning one
        Extra tables for the sheet, in order; a callable is called once the rest of the patch is
        rendered (a bench prediction still being computed is waited for only then).
    judged : AsPatched, optional
        The patch judged as patched: its loops beside the design's ('Margins as patched').
    signs : tuple of SignStep
        The sign check (patchgen.patch.sign_check).
    static : SheetSection, optional
        The static check (:func:`static_section`).

    Returns
    -------
    SheetSummary
        What :func:`patchgen.render.sheet.render_sheet` shows beside the netlist.
    """
    margins = {"LQR (state feedback)": margin_cells(d.lqr_margins)}
    if d.estimator is not None and d.lqg_margins is not None and judged is None:  # else beside the patch's
        margins[f"as designed ({d.estimator.kind})"] = margin_cells(d.lqg_margins)
    kind = "none (all states measured)" if d.estimator is None else d.estimator.kind
    if d.estimator is not None and d.estimator.rolloff_s:
        kind += f", roll-off {d.estimator.rolloff_s:g} s"
    return SheetSummary(design=design_label(d.spec), description=d.spec.description, states=list(d.states),
                        K=[float(k) for k in d.K[0]], poles=list(d.closed_loop_poles), margins=margins,
                        estimator=kind, sections=list(sections), K_spread=[float(u) for u in d.spread.K[0]],
                        judged=judged, signs=signs, static=static, plant=d.spec.plant_model)


def design_label(spec: DesignSpec) -> str:
    """The design as the sheet names it: its name, and the file it was read from when that name is
    a shipped design's but the file is not the shipped one ("bench-recommended (from my-copy.toml)")."""
    if spec.name in shipped("design") and Path(spec.path).is_file() and not is_shipped_file("design", spec.name,
                                                                                              spec.path):
        return f"{spec.name} (from {spec.path})"
    return spec.name


def static_section(check: StaticCheck, net: Netlist) -> SheetSection:
    """The static check on the sheet: one row per amplifier (and u_c), a column per condition,
    each cell the expected reading and its tolerance; the conditions (with where each test voltage
    and IC comes from) and what the check leaves out in the note (static-check.csv has a row per
    reading, with what each isolates)."""
    names = [c.name for c in check.conditions]
    cells = {(r.condition, r.point): f"{r.expected_V:+.3f} ± {r.tolerance_V:.3f}".replace("-", "−")
             for r in check.readings}
    points = [a.id for a in net.amplifiers] + ["u_c"]
    rows = [[p if p != "u_c" else f"u_c ({net.output.source})", *(cells[(c, p)] for c in names)] for p in points]
    setups = " ".join(_setup_lines(check))
    left = (" Not seen by DC readings: " + "; ".join(check.unchecked) + ".") if check.unchecked else ""
    note = (f"Expected reading ± tolerance (V). {setups}{left} Fill measured_V in static-check.csv, then "
            "patchgen check SPEC --readings static-check.csv names the likeliest wrong pot, cord or sign.")
    return SheetSection("Static check", ["amp", *names], rows, note)


def _setup_lines(check: StaticCheck) -> list[str]:
    """The conditions' set-ups, the one-sensor conditions in one sentence."""
    out, single = [], [c for c in check.conditions if c.name.endswith(" only")]
    for c in check.conditions:
        if c in single[1:]:
            continue
        if c is (single[0] if single else None) and len(single) > 1:
            volts = ", ".join(f"{next(iter(x.sensors_V.values())):g}" for x in single)
            names = ", ".join(x.name.removesuffix(" only") for x in single)
            out.append(f"{names} only: IC mode, integrators at 0, the other sensor inputs grounded, that input at "
                       f"{volts} V ({'; '.join(x.source for x in single)}).")
            continue
        out.append(f"{c.name}: {c.setup}.")
    return out


def patch_files(d: Design, machine: MachineProfile, net: Netlist,
                sections: Sequence[SheetSection] | Callable[[], Sequence[SheetSection]] = (),
                judged: AsPatched | None = None) -> dict[str, str]:
    """Every file of a patch (PATCH_FILES), rendered in memory; nothing is written.

    Parameters
    ----------
    d : Design
        The design the patch realises.
    machine : MachineProfile
        The machine the patch is allocated on.
    net : Netlist
        The patch.
    sections : sequence of SheetSection, or a callable returning one
        Extra tables for the sheet, in order; a callable is called once the rest of the patch is
        rendered (a bench prediction still being computed is waited for only then).
    judged : AsPatched, optional
        The patch judged as patched, on the bench too (patchgen.bench.diagnosis.as_patched_on_bench);
        by default on the design model alone.

    Returns
    -------
    dict
        File name -> text, for :func:`patchgen.render.outputs.write_files`.
    """
    judged = judged if judged is not None else as_patched(d, net, machine)
    check = static_check(net, machine)
    files = {"netlist.json": net.to_json(), "margins.json": margins_json(judged, net.design), "pots.csv": pots_csv(net),
             "static-check.csv": static_check_csv(check)}
    whole = wiring_diagram(net)
    svg, pages, signs = whole.svg, diagram_pages(net, whole), sign_check(net, machine, d.spec.plant_model)
    sections = sections() if callable(sections) else sections  # late: after what does not need them
    summary = sheet_summary(d, sections, judged, signs, static_section(check, net))
    html, md = render_sheet(net, summary, pages, machine.procedure)
    files.update({"wiring.svg": svg, "patch-sheet.html": html, "patch-sheet.md": md})
    return files
