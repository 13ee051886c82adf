"""The wiring diagrams as printed: no label on another label, on a symbol not its own or under a
wire; every external part named; a patch on two units drawn unit by unit. Checked on the SVG's
own geometry (tests/render/svg_geometry.py)."""

import re

import pytest

from patchgen.design.lqg import design_on
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.render.diagram import wiring_svg
from patchgen.render.diagram_units import diagram_pages, unit_of
from tests.render.svg_geometry import labels, overlaps


def _net(name, machine_id="gp6", **estimator):
    spec = load_spec(name).model_copy(update={"machine": machine_id})
    if estimator:
        spec = spec.model_copy(update={"estimator": spec.estimator.model_copy(update=estimator)})
    m = load_machine(machine_id)
    d = design_on(spec, m, load_bench(spec.bench))
    return build_patch(d, m, "auto" if estimator else None)


CASES = {
    "bench-recommended": lambda: _net("bench-recommended"),
    "thesis-ch5": lambda: _net("thesis-ch5"),
    "bench-recommended-that": lambda: _net("bench-recommended", "the-analog-thing"),
    "thesis-ch5-that": lambda: _net("thesis-ch5", "the-analog-thing"),
    "bench-recommended-2-units": lambda: _net("bench-recommended", kind="reduced_observer", rolloff_s=None),
    "thesis-ch5-2-units": lambda: _net("thesis-ch5", kind="reduced_observer", rolloff_s=None),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def net(request):
    return CASES[request.param]()


def test_no_label_overlaps(net):
    assert overlaps(wiring_svg(net)) == []
    for caption, svg in diagram_pages(net):
        assert overlaps(svg) == [], caption


def test_the_check_catches_a_label_on_a_symbol():
    svg = wiring_svg(_net("thesis-ch5"))
    tri = re.search(r'<polygon points="([\d.]+),([\d.]+) ', svg)
    planted = (f'<text x="{tri.group(1)}" y="{float(tri.group(2)) + 12}" font-size="8" text-anchor="start">'
               f'<tspan x="{tri.group(1)}" dy="0">a label planted on a symbol</tspan></text></svg>')
    assert overlaps(svg.replace("</svg>", planted))


def test_every_external_part_is_drawn_with_its_value(net):
    text = " ".join(b.text for b in labels(wiring_svg(net)))
    for p in net.parts:
        assert f"{p.id} {p.fit.split(' (')[0]}" in text


def test_no_combining_mark_lands_on_a_long_name(net):
    for b in labels(wiring_svg(net)):
        for m in re.finditer("[\u0302\u0307]", b.text):
            assert m.start() >= 1 and b.text[m.start() - 1] in "θsφαωŝ\u0302" and (
                m.start() < 2 or not b.text[m.start() - 2].isalpha()), b.text


def test_a_two_unit_patch_is_drawn_unit_by_unit():
    net = CASES["bench-recommended-2-units"]()
    assert net.units == 2
    pages = diagram_pages(net)
    assert [c.split(":")[0] for c, _ in pages] == ["Unit 1 of 2", "Unit 2 of 2"]
    for u, (caption, svg) in enumerate(pages, 1):
        shown = set(re.findall(r">(U\d\.A\d)<", svg))
        mine = {a.id for a in net.amplifiers if unit_of(a.id) == u}
        assert mine <= shown  # every amplifier of the unit, drawn
        others = shown - mine  # other units' amplifiers appear only as the terminals of the links
        assert all(o in caption for o in others)
    assert len(diagram_pages(_net("thesis-ch5"))) == 1


def test_a_two_unit_wire_list_keeps_each_units_cords_together():
    import re as _re

    from patchgen.patch.netlist import wire_list

    net = CASES["bench-recommended-2-units"]()
    units = [int(m.group(1)) if (m := _re.search(r"\bU(\d+)\.", to)) else 99 for _, to in wire_list(net)]
    assert units == sorted(units) and units[-1] == 99  # unit 1, unit 2, then the servo command
