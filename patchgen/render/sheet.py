"""The patch sheet: what a lab needs to wire, set and run a patch, as HTML and Markdown.

Rendered from the jinja2 templates shipped in the package (templates/ in the repository,
patchgen.templates when installed). The HTML sheet is printable on A4 and on Letter alike: its
page is the area common to both (210 mm x 279 mm) with margins, so nothing is wider than 186 mm
or taller than 250 mm. Everything shown is computed from the netlist and the design summary, so
the same inputs give the same bytes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import jinja2

from patchgen.design.precision import gain_text, significant_digits
from patchgen.patch.as_patched import AsPatched
from patchgen.patch.netlist import Amplifier, Netlist, Pot, wire_list
from patchgen.patch.parts import fmt_value
from patchgen.patch.sign_check import SignStep
from patchgen.patch.snr_scaling import dial_limits
from patchgen.plant.plant_model import CART, PlantModel
from patchgen.profiles.machine import Procedure
from patchgen.render.diagram_pages import PRINTED_MIN_PT, printed_scale, svg_size_mm
from patchgen.render.diagram_symbols import SMALLEST_PT, dial_decimals, quantity_label, signed_label
from patchgen.render.margins_view import patched_banner, patched_context
from patchgen.render.sign_sheet import sign_note, sign_rows
from patchgen.render.template_cache import bytecode_cache


@dataclass(frozen=True)
class SheetSection:
    """An extra table on the sheet (e.g. 'Predicted on the bench', 'Why this patch')."""

    title: str
    header: list[str]
    rows: list[list[str]]
    note: str = ""
    banner: str = ""  # one line shown at the top of the sheet (a patch predicted to fail says why)


@dataclass(frozen=True)
class SheetSummary:
    """The design as the sheet summarises it.

    ``margins`` maps a loop name (e.g. 'plant input') to its figures by name, already chosen by
    the design stage (e.g. {'lower GM': '0.2757 (-11.19 dB)', 'PM': 79.12}).
    """

    design: str
    description: str
    states: list[str]
    K: list[float]
    poles: list[complex]
    margins: dict[str, dict[str, float | str]]
    estimator: str
    sections: list[SheetSection] = field(default_factory=list)
    K_spread: list[float] = field(default_factory=list)  # per gain, the design's (0: fully determined)
    judged: AsPatched | None = None  # the patch judged as patched: the sheet's 'Margins as patched'
    signs: tuple[SignStep, ...] = ()  # the sign check (patchgen.patch.sign_check), a step per pot
    static: SheetSection | None = None  # the static check, after the sign check
    plant: PlantModel = CART  # whose states the gains are on, and whose input u is


def render_sheet(netlist: Netlist, summary: SheetSummary, svg: str | list[tuple[str, str]],
                 procedure: Procedure) -> tuple[str, str]:
    """The patch sheet as (HTML, Markdown).

    Parameters
    ----------
    netlist : Netlist
        The patch.
    summary : SheetSummary
        The design beside it: gains, poles, margins, extra sections.
    svg : str or list of (str, str)
        The wiring diagram, inlined in the HTML; or several, each with its caption (a patch on
        slaved units: one per unit, patchgen.render.diagram.diagram_pages).
    procedure : Procedure
        The machine profile's procedure: the bench checklist in the machine's own words.
    """
    ctx = sheet_context(netlist, summary, procedure)
    figures = [("", svg)] if isinstance(svg, str) else svg
    html = _env(autoescape=True).get_template("patch-sheet.html.j2").render(
        **ctx, figures=[(caption, *_inline_svg(body)) for caption, body in figures])
    md = _env(autoescape=False).get_template("patch-sheet.md.j2").render(**ctx)
    return _end(html), _end(md)


def sheet_context(net: Netlist, summary: SheetSummary, procedure: Procedure) -> dict:
    """Every value the templates show, as plain strings and lists."""
    decimals = dial_decimals(net.pot_resolution)
    amps = {a.id: a for a in net.amplifiers}
    sensors = {s.id: s for s in net.sensors}

    def source_name(src: str) -> str:
        if src in sensors:
            return f"{quantity_label(sensors[src].quantity)} ({src} sensor)"
        a = amps[src]
        return f"{src} ({signed_label(a.carries.polarity, a.carries.quantity)})"

    pots = [{
        "id": p.id,
        "setting": f"{p.setting:.{decimals}f}",
        "signal": p.signal,
        "source": source_name(p.source),
        "input": f"{p.amplifier} {p.jack}",
        "weight": f"x{p.weight}",
        "realized": _signed(p.realized, 4),
        "design": _signed(p.coefficient, 4),
        "error": _error(p),
        "note": "; ".join(n for n in (p.note, _dial_note(p.setting, net.pot_resolution)) if n),
    } for p in net.pots]

    amplifiers = [{
        "id": a.id,
        "role": a.role,
        "carries": _carries(a),
        "inputs": [_input_text(inp, source_name) for inp in a.inputs],
        "settings": _amp_settings(a, net.time_scale_s, procedure.ic_input),
        "purpose": a.purpose,
    } for a in net.amplifiers]

    wires = [{"n": i + 1, "from": f, "to": t} for i, (f, t) in enumerate(wire_list(net))]

    ics = [{"id": a.id, "role": a.role,
            "ic": ("settled on its input (runs while the pendulum is held)" if a.role == "integrator" else "0 V")
            if a.ic_V is None else f"{a.ic_V:g} V",
            "carries": _carries(a)}
           for a in net.amplifiers if a.role in ("integrator", "lag")]

    spread = summary.K_spread or [0.0] * len(summary.K)
    states, gain_notes = [], []
    for s, k, u in zip(summary.states, summary.K, spread):
        text, cut = gain_text(k, u)
        states.append({"state": quantity_label(s), "name": s, "K": _minus(text) + (" *" if cut else ""),
                       "unit": gain_unit(s, summary.plant)})
        if cut:
            n = significant_digits(k, u)
            gain_notes.append(f"{s}: {n} significant digits" if n else f"{s}: not beyond its size")
    parts = [{"id": p.id, "fit": p.fit, "value": fmt_value(p.value, "Ω" if p.unit == "ohm" else "F"),
              "tolerance": f"±{100 * p.tolerance:g} %", "where": f"{p.amplifier}{' ' + p.jack if p.jack else ''}",
              "connection": p.connection, "purpose": p.purpose} for p in net.parts]
    margins = [{"loop": loop, "figures": [(name, _fmt(v)) for name, v in figs.items()]}
               for loop, figs in summary.margins.items()]

    judged = summary.judged
    banners = [patched_banner(judged)] if judged is not None else []
    return {
        "banners": [b for b in banners + [sec.banner for sec in summary.sections] if b],
        "patched": patched_context(judged) if judged is not None else None,
        "gain_note": ("A gain marked * is fixed by the design to fewer digits (" + "; ".join(gain_notes)
                      + "; a nearly uncontrollable mode): further digits, and those of the pots set from it, "
                      "follow the computer's arithmetic, not the design.") if gain_notes else "",
        "parts": parts,
        "net": net,
        "summary": summary,
        "title": f"Patch sheet: {summary.design or net.design}",
        "states": states,
        "poles": [_complex(p) for p in summary.poles],
        "margins": margins,
        "pots": pots,
        "amplifiers": amplifiers,
        "wires": wires,
        "ics": ics,
        "sign_checks": sign_rows(summary.signs, net, procedure.ic_input, summary.plant),
        "sign_note": sign_note(procedure.ic_input, summary.plant),
        "plant": summary.plant,
        "static": summary.static,
        "static_tables": _column_groups(summary.static) if summary.static is not None else [],
        "checklist": procedure.steps("checklist", machine=net.machine_name, units=net.units,
                                     resolution=net.pot_resolution, reference_V=net.reference_V,
                                     integrators=tuple(i["id"] for i in ics), signs=bool(summary.signs),
                                     plant=summary.plant),
        "notes": list(net.notes),
        "sections": summary.sections,
        "resolution": f"{net.pot_resolution:g}",
        "pot_reading": procedure.pot_reading,
        "output_amp": net.output.source,
        "time_scale": time_scale_text(net),
    }


STATIC_COLUMNS = 7  # conditions side by side in one static-check table: each reading fits its cell on one line


def _column_groups(section: SheetSection) -> list[tuple[list[str], list[list[str]]]]:
    """A table of many columns as several of at most STATIC_COLUMNS beside its first column."""
    n = len(section.header) - 1
    k = -(-n // STATIC_COLUMNS)
    size = -(-n // k)
    return [([section.header[0], *section.header[1 + i:1 + i + size]], [[r[0], *r[1 + i:1 + i + size]]
                                                                         for r in section.rows])
            for i in range(0, n, size)]


def time_scale_text(net: Netlist) -> str:
    """The header's word on the integrators' time scale: the one time scale of a machine with one
    integrator mode (``time scale 1 s``), else each mode the patch uses, with how to select it."""
    used = sorted({(a.mode.k0_per_s, a.mode.name, a.mode.jumper or "") for a in net.amplifiers if a.mode is not None})
    if not used or (len(used) == 1 and not used[0][2] and used[0][0] * net.time_scale_s == 1.0):
        return f"time scale {net.time_scale_s:g} s"
    return "integrators at " + " and ".join(f"k0 {k0:g} 1/s ({_mode_words(name, jumper)})" for k0, name, jumper in used)


def _mode_words(name: str, jumper: str) -> str:
    """How an integrator mode is selected, in the sheet's words: 'SLOW patched to OUT'."""
    if not jumper:
        return name
    return f"{jumper} patched to OUT" if jumper == name else f"{name}: {jumper} patched to OUT"


def gain_unit(state: str, plant: PlantModel = CART) -> str:
    """The unit of a state's gain in u = -K x, u the plant's input (the cart's force in N): the
    input's unit per the state's (N s/m for m/s; V s/rad for a rotary arm's rad/s)."""
    u = plant.input_unit
    unit = plant.state_units().get(state, "")
    if unit == u:
        return f"{u}/{u}"
    if "/" in unit:
        num, den = unit.split("/", 1)
        return f"{u} {den}/{num}"
    return f"{u}/({unit})" if " " in unit else f"{u}/{unit}" if unit else u


def _carries(a: Amplifier) -> str:
    c = a.carries
    label = signed_label(c.polarity, c.quantity)
    if c.unit == "V" and c.volts_per_unit == 1.0:
        return label
    return f"{label} ({c.volts_per_unit:g} V per {c.unit})" if c.unit else label


def _input_text(inp, source_name) -> str:
    via = f" via {inp.pot}" if inp.pot else ""
    return f"{inp.jack} ← {source_name(inp.source)}{via}"


def _amp_settings(a: Amplifier, time_scale_s: float, ic_input: str) -> str:
    """An amplifier's element values; an integrator's mode when it is selected by a cord or is not
    the machine's time scale (a GP-6's one mode goes without saying: the header says it); its IC
    with what its IC input (``ic_input``) is patched to."""
    parts = []
    if a.mode is not None and (a.mode.jumper or a.mode.k0_per_s * time_scale_s != 1.0):
        parts.append(f"{_mode_words(a.mode.name, a.mode.jumper or '')}: k0 {a.mode.k0_per_s:g} 1/s")
    if a.ic_V is not None:
        parts.append(f"IC 0 V ({ic_input} grounded)" if a.ic_V == 0 else
                     f"IC {a.ic_V:g} V ({ic_input} at {-a.ic_V:g} V)")
    if a.T_d_s is not None:
        parts.append(f"T_d {a.T_d_s:g} s")
    if a.rolloff_s is not None:
        parts.append(f"roll-off {a.rolloff_s:g} s")
    if a.tau_s is not None:
        parts.append(f"tau {a.tau_s:g} s")
    return ", ".join(parts)


def _error(p: Pot) -> str:
    e = p.error
    if math.isinf(e):
        return "n/a"
    if abs(e) < 1.0:
        return _minus(f"{100 * e:+.2f} %")
    return _minus(f"{100 * e:+.3g} %")


def _dial_note(setting: float, resolution: float) -> str:
    """A pot whose setting's step limits the law it sets, said so in words any machine's sheet may use
    (patchgen.patch.snr_scaling.dial_limits)."""
    if not dial_limits(setting, resolution):
        return ""
    return (f"the setting's resolution limits this coefficient: its step {resolution:g} is "
            f"{100 * resolution / setting:.1f} % of the setting")


def _signed(x: float, digits: int) -> str:
    return _minus(f"{x:+.{digits}g}")


def _minus(text: str) -> str:
    """Typographic minus signs."""
    return text.replace("-", "−")


def _complex(z: complex) -> str:
    z = complex(z)
    if abs(z.imag) < 1e-12:
        return _minus(f"{z.real:.4g}")
    sign = "+" if z.imag > 0 else "−"
    return _minus(f"{z.real:.4g}") + f" {sign} {abs(z.imag):.4g}j"


def _fmt(v: float | str) -> str:
    return v if isinstance(v, str) else _minus(f"{v:.4g}")


def _inline_svg(svg: str) -> tuple[str, str]:
    """The SVG without an XML declaration, at the scale it prints at (its own size, shrunk to the
    page: patchgen.render.diagram_pages.printed_scale); and the note that goes under it when its
    smallest label prints under PRINTED_MIN_PT (a diagram the split could not bring to one page)."""
    body = svg.strip()
    if body.startswith("<?xml"):
        body = body[body.index("?>") + 2:].lstrip()
    width, height = svg_size_mm(body)
    scale = printed_scale(body)
    printed = SMALLEST_PT * scale
    note = "" if printed >= PRINTED_MIN_PT - 1e-9 else (
        f"Too large for one page at {PRINTED_MIN_PT:g} pt: its smallest labels print at {printed:.1f} pt; zoom in on "
        "screen, or print wiring.svg larger.")
    tag = (f'<svg class="wiring" role="img" aria-label="wiring diagram" data-scale="{scale:.4f}" '
           f'style="width: {width * scale:.1f}mm; height: {height * scale:.1f}mm" ')
    return body.replace("<svg ", tag, 1), note


def _env(autoescape: bool) -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.PackageLoader("patchgen.templates", "."),
        autoescape=autoescape,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        bytecode_cache=bytecode_cache(),
    )


def _end(text: str) -> str:
    return text if text.endswith("\n") else text + "\n"
