"""The wiring diagrams as drawn, read back from their SVG: no label overlaps another or an element,
every external part is shown with its id and value, every feedback through a pot is drawn from the
amplifier's output back to its input, a unit's diagram holds that unit's amplifiers, and every
diagram prints its smallest text at 6 pt or more at the sheet's 186 mm.

The patches: both shipped designs on the GP-6 and on THE ANALOG THING, and each with the reduced
observer on as many GP-6 units as it needs (two).
"""

from __future__ import annotations

import re

import pytest

from patchgen.design.lqg import design_on
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.patch.netlist import Netlist
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.render.diagram import wiring_svg
from patchgen.render.diagram_graph import unit_of, units
from patchgen.render.diagram_pages import diagram_pages
from patchgen.render.diagram_symbols import part_value
from tests.conftest import design_path

from .svg_geometry import connected, overlaps, parse, printed_min_font
from .test_diagram import _two_unit_netlist

VARIANTS = {
    "bench-recommended": ("bench-recommended", {}),
    "thesis-ch5": ("thesis-ch5", {}),
    "bench-recommended-tat": ("bench-recommended", {"machine": "the-analog-thing"}),
    "thesis-ch5-tat": ("thesis-ch5", {"machine": "the-analog-thing"}),
    "bench-recommended-2u": ("bench-recommended", {"kind": "reduced_observer", "units": "auto"}),
    "thesis-ch5-2u": ("thesis-ch5", {"kind": "reduced_observer", "units": "auto"}),
}


def _spec_copy(name: str, edits: dict[str, str], folder) -> str:
    """A copy of a shipped spec with its machine, estimator kind or [patch] units changed."""
    text = design_path(name).read_text()
    if "machine" in edits:
        text = re.sub(r'^machine = .*$', f'machine = "{edits["machine"]}"', text, flags=re.M)
    if "kind" in edits:
        text = re.sub(r'^kind = .*$', f'kind = "{edits["kind"]}"', text, flags=re.M)
    if "units" in edits:
        if "[patch]" not in text:
            text += "\n[patch]\n"
        text = text.replace("[patch]\n", f'[patch]\nunits = "{edits["units"]}"\n')
    path = folder / f"{name}.toml"
    path.write_text(text)
    return str(path)


@pytest.fixture(scope="module")
def nets(tmp_path_factory) -> dict[str, Netlist]:
    out = {}
    for key, (name, edits) in VARIANTS.items():
        spec = load_spec(_spec_copy(name, edits, tmp_path_factory.mktemp(key)) if edits else name)
        machine = load_machine(spec.machine)
        out[key] = build_patch(design_on(spec, machine, load_bench(spec.bench)), machine)
    return out


@pytest.fixture(scope="module")
def drawn(nets) -> dict[str, list]:
    """Each variant's diagrams: the whole patch first, then the pages a sheet prints."""
    return {key: [("whole", wiring_svg(net))] + diagram_pages(net) for key, net in nets.items()}


def test_the_variants_are_what_they_claim(nets):
    assert [len(units(nets[k])) for k in VARIANTS] == [1, 1, 1, 1, 2, 2]
    assert nets["bench-recommended-tat"].machine == "the-analog-thing"
    assert any(a.role == "lag" for a in nets["bench-recommended-2u"].amplifiers)
    assert any(inp.source == a.id for a in nets["bench-recommended"].amplifiers for inp in a.inputs)


@pytest.mark.parametrize("key", VARIANTS)
def test_no_label_overlaps_a_label_or_an_element(drawn, key):
    for caption, svg in drawn[key]:
        assert overlaps(parse(svg)) == [], caption


@pytest.mark.parametrize("key", VARIANTS)
def test_every_page_prints_its_smallest_text_at_6_pt(drawn, key):
    for caption, svg in drawn[key][1:]:
        d = parse(svg)
        assert printed_min_font(d) >= 6.0, (caption, d.width)


def test_the_overlap_check_catches_an_overlapping_label(drawn):
    svg = drawn["bench-recommended"][0][1]
    d = parse(svg)
    assert overlaps(d) == []
    pot, circle = next((t, s) for t, s in d.inscriptions("circle") if t.text == "P3")
    amp, triangle = next((t, s) for t, s in d.inscriptions("polygon", 3) if t.text == "A7")
    setting = next(t for t in d.texts if t.text == "0.107")
    wire = max((s for s in d.shapes if s.kind == "path"), key=lambda s: abs(s.points[-1][0] - s.points[0][0]))
    (x0, y0), (x1, _) = wire.points[0], wire.points[-1]

    def with_label(x, y, text, anchor="middle"):
        extra = (f'<text x="{x}" y="{y - 7}" fill="black" font-size="7" font-family="DejaVu Sans" '
                 f'text-anchor="{anchor}"><tspan x="{x}" dy="7">{text}</tspan></text></svg>')
        return overlaps(parse(svg.replace("</svg>", extra)))

    cx, cy = setting.centre
    assert any("'0.107' overlaps label '0.999'" in f for f in with_label(cx + 3, cy + 3, "0.999"))
    # across the amplifier's outline (its tip), across a pot's circle, on a wire
    tip = max(triangle.points)
    assert any("overlaps a polygon" in f for f in with_label(tip[0], tip[1] + 2, "tip"))
    (cx, cy), r = circle.points[0], circle.r
    assert any("overlaps a circle" in f for f in with_label(cx + r, cy + 2, "x"))
    assert any("overlaps a path" in f for f in with_label((x0 + x1) / 2, y0 + 2, "wire"))
    assert any("leaves the drawing" in f for f in with_label(d.view[0], 20, "edge", "end"))
    # while a label wholly inside a shape is its inscription
    assert pot.box[0] > circle.points[0][0] - circle.r and amp.box[2] < tip[0]


@pytest.mark.parametrize("key", VARIANTS)
def test_every_external_part_is_drawn_with_its_id_and_value(nets, drawn, key):
    net = nets[key]
    assert net.parts
    for caption, svg in drawn[key]:
        d = parse(svg)
        unit = caption.split()[1] if caption.startswith("Unit ") else None
        on_page = [p for p in net.parts if unit is None or unit_of(p.amplifier) == unit]
        for part in on_page:
            ids = [t for t in d.texts if t.text == part.id]
            values = [t for t in d.texts if t.text == part_value(part)]
            assert len(ids) == 1, (caption, part.id)
            # the value right beside its id: stacked on the same centre line
            assert any(abs(v.centre[0] - ids[0].centre[0]) < 1 and abs(v.centre[1] - ids[0].centre[1]) < 40
                       for v in values), (caption, part.id, part_value(part))


def test_part_values_are_what_is_fitted(nets):
    parts = {p.id: part_value(p) for p in nets["bench-recommended"].parts}
    assert parts == {"C1": "1 µF", "R1": "6.34 kΩ"}


@pytest.mark.parametrize("key", ["bench-recommended", "bench-recommended-tat"])
def test_feedback_through_a_pot_is_drawn_over_the_amplifier(nets, drawn, key):
    net = nets[key]
    loops = [(a, inp) for a in net.amplifiers for inp in a.inputs if inp.source == a.id]
    assert loops
    d = parse(drawn[key][0][1])
    for a, inp in loops:
        _, tri = next((t, s) for t, s in d.inscriptions("polygon", 3) if t.text == a.id)
        _, circle = next((t, s) for t, s in d.inscriptions("circle") if t.text == inp.pot)
        (cx, cy), r = circle.points[0], circle.r
        tip = max(tri.points)
        top = min(p[1] for p in tri.points)
        # a loop of wire from the output, over the amplifier, into the pot's input side ...
        region = (cx - r - 20, top - 60, tip[0] + 20, max(p[1] for p in tri.points))
        assert connected(d, tip, (cx - r, cy), region), a.id
        # ... and the pot's wiper into the amplifier
        assert connected(d, (cx + r, cy), (_input_side(d, tri), cy)), a.id


@pytest.mark.parametrize("key", VARIANTS)
def test_every_pot_is_wired_into_its_amplifier(nets, drawn, key):
    net = nets[key]
    d = parse(drawn[key][0][1])
    for p in net.pots:
        _, circle = next((t, s) for t, s in d.inscriptions("circle") if t.text == p.id)
        _, tri = next((t, s) for t, s in d.inscriptions("polygon", 3) if t.text == p.amplifier)
        (cx, cy), r = circle.points[0], circle.r
        assert connected(d, (cx + r, cy), (_input_side(d, tri), cy)), p.id


@pytest.mark.parametrize("key", ["bench-recommended-2u", "thesis-ch5-2u"])
def test_a_unit_diagram_holds_that_units_amplifiers_and_pots(nets, drawn, key):
    net = nets[key]
    pages = drawn[key][1:]
    assert [c.split()[1] for c, _ in pages] == ["U1", "U2"]
    for caption, svg in pages:
        unit = caption.split()[1]
        d = parse(svg)
        amps = {t.text for t, _ in d.inscriptions("polygon", 3) if not t.text.isdigit() and t.text != "d/dt"}
        assert amps == {a.id.split(".")[1] for a in net.amplifiers if unit_of(a.id) == unit}, caption
        pots = {t.text for t, _ in d.inscriptions("circle")}
        assert pots == {p.id.split(".")[1] for p in net.pots if unit_of(p.id) == unit}, caption


@pytest.mark.parametrize("key", ["bench-recommended-2u", "thesis-ch5-2u"])
def test_every_signal_between_units_has_a_flag_at_both_ends(nets, drawn, key):
    net = nets[key]
    pages = {c.split()[1]: [t.text for t in parse(svg).texts] for c, svg in drawn[key][1:]}
    crossings = 0
    for a in net.amplifiers:
        for inp in a.inputs:
            hops = [inp.source, inp.pot, a.id] if inp.pot else [inp.source, a.id]
            for src, dst in zip(hops, hops[1:]):
                if src in {s.id for s in net.sensors} or unit_of(src) == unit_of(dst):
                    continue
                crossings += 1
                there = f"to {dst} {inp.jack}" if dst == a.id else f"to {dst}"
                assert there in pages[unit_of(src)], (src, dst)
                assert f"from {src}" in pages[unit_of(dst)], (src, dst)
    assert crossings >= 2


def _input_side(d, tri) -> float:
    """x of an amplifier's input side: its triangle's base, or the integrator's rectangle left of it."""
    base = [p for p in tri.points if p[0] == min(q[0] for q in tri.points)]
    boxes = [s for s in d.shapes if s.kind == "polygon" and len(s.points) == 4 and all(p in s.points for p in base)]
    return min(p[0] for s in boxes + [tri] for p in s.points)


def test_a_hand_made_two_unit_patch_draws_without_overlaps():
    """The section 5.3 fixture on two units, fed back between them (tests/render/test_diagram.py)."""
    net = _two_unit_netlist()
    for caption, svg in [("whole", wiring_svg(net))] + diagram_pages(net):
        d = parse(svg)
        assert overlaps(d) == [], caption
        assert caption == "whole" or printed_min_font(d) >= 6.0
