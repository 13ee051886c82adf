"""The diagrams a sheet prints, for every shipped design on both machines: each fits a page with its
labels at 6 pt, and every flag leads somewhere. A flag names a jack that exists on another unit
(or another part of its own), its cord numbers are cords of the wire list between that jack and
an element drawn on the flag's page, every cord between elements drawn on different pages has a
flag on both, and no flag is left without a wire on its page (before, bench-lqg's unit U2 showed
'from U1.A1' and 'from U1.A2', which fed U3's pots, not U2)."""

from __future__ import annotations

import re

import pytest

from patchgen.patch.netlist import Netlist, cords
from patchgen.render.diagram import graph_diagram, labels_size_pt
from patchgen.render.diagram_graph import loose_pots, page_graph, unit_of, units
from patchgen.render.diagram_pages import DiagramPage, diagram_parts, fits
from tests.shipped import patch_of, shipped_cases

from .svg_geometry import parse
from .test_diagram import _two_unit_netlist

pytestmark = pytest.mark.heavy(6)  # seconds, roughly: see tests/conftest.py


@pytest.fixture(scope="module")
def drawn() -> dict[str, tuple[Netlist, list[DiagramPage]]]:
    """Every shipped design that fits its machine, and a hand-made two-unit patch: its pages."""
    out = {"two-unit fixture": (_two_unit_netlist(), diagram_parts(_two_unit_netlist()))}
    for name, machine in shipped_cases():
        made = patch_of(name, machine)
        if made is not None:
            net = made[0].netlist
            out[f"{name}-{machine}"] = (net, diagram_parts(net))
    return out


def _flags(page: DiagramPage) -> list[tuple[str, tuple[str, ...], bool]]:
    """Each flag on a page: its name, its details, and whether it leads in (a source on the left)."""
    g = page.graph
    return ([(s.name, s.details, True) for s in g.sources if s.kind == "connector"]
            + [(b.name, b.details, False) for b in g.outputs if b.role == "connector"])


def _numbers(details: tuple[str, ...]) -> list[int]:
    m = re.fullmatch(r"cords? ([0-9, ]+)", details[-1])
    assert m, details
    return [int(n) for n in m.group(1).split(", ")]


def test_the_cases_include_split_units_and_units_of_pots_alone(drawn):
    net, pages = drawn["bench-lqg-gp6"]
    assert net.units == 3 and len(pages) > 3 and any("part 2 of" in p.caption for p in pages)
    assert any(not p.amplifiers and p.pots for p in pages)
    assert sum(len(ps) > 1 for _, ps in drawn.values()) >= 8


def test_every_page_prints_its_smallest_label_at_6_pt_on_a_page(drawn):
    for key, (_, pages) in drawn.items():
        for p in pages:
            assert fits(p.svg), (key, p.caption)


def test_a_diagrams_labels_alone_are_no_larger_than_the_diagram(drawn):
    """A unit whose labels alone are too large for a page is split without drawing it whole: the
    labels' size bounds the diagram's from below."""
    for key, (net, pages) in drawn.items():
        graphs = [p.graph for p in pages] + [page_graph(net, u, [a.id for a in net.amplifiers if unit_of(a.id) == u],
                                                        loose_pots(net, u)) for u in units(net) if u]
        for g in graphs:
            width, height = labels_size_pt(g)
            full = graph_diagram(g).size_pt
            assert width <= full[0] and height <= full[1], key


def test_every_element_is_drawn_on_one_page(drawn):
    for key, (net, pages) in drawn.items():
        amps = [a for p in pages for a in p.amplifiers]
        pots = [x for p in pages for x in p.pots]
        assert sorted(amps) == sorted(a.id for a in net.amplifiers), key
        assert sorted(pots) == sorted(p.id for p in net.pots), key


def test_no_flag_is_left_without_a_wire(drawn):
    for key, (_, pages) in drawn.items():
        for p in pages:
            g = p.graph
            fed = {f.source for b in g.blocks + g.outputs for f in b.feeds}
            assert all(s.id in fed for s in g.sources), (key, p.caption, [s.name for s in g.sources if s.id not in fed])
            inside = {s.id for s in g.sources} | {b.id for b in g.blocks}
            assert all(f.source in inside for b in g.outputs for f in b.feeds), (key, p.caption)
            texts = parse(p.svg).strings()
            for name, details, _ in _flags(p):
                assert name in texts and all(d in texts for d in details), (key, name)


def test_every_flag_names_a_jack_drawn_elsewhere_and_its_cords(drawn):
    for key, (net, pages) in drawn.items():
        numbered = dict(enumerate(cords(net), 1))
        amps, pots = {a.id for a in net.amplifiers}, {p.id for p in net.pots}
        for p in pages:
            here = set(p.amplifiers) | set(p.pots)
            for name, details, inward in _flags(p):
                m = re.fullmatch(r"(from|to) (\S+)(?: (\S+))?", name)
                assert m and (m.group(1) == "from") == inward, name
                element, jack = m.group(2), m.group(3)
                assert element in amps | pots and element not in here, (key, p.caption, name)
                other = next(q for q in pages if element in q.amplifiers + q.pots)  # drawn on another page
                assert other is not p and (unit_of(element) != unit_of(p.amplifiers[0] if p.amplifiers else p.pots[0])
                                           or "part" in other.caption), (key, name)
                for n in _numbers(details):
                    c = numbered[n]
                    if inward:  # from an amplifier's output or a pot's wiper, to what this page draws
                        assert c.frm == f"{element} {'wiper' if element in pots else 'out'}", (key, name, c)
                        assert c.target in here, (key, name, c)
                    elif jack:  # to an amplifier's input, from what this page draws
                        assert (c.target, c.jack) == (element, jack) and c.source in here, (key, name, c)
                    else:       # to a pot's top
                        assert c.to == f"{element} top" and c.source in here, (key, name, c)


def test_every_cord_between_pages_has_a_flag_on_both(drawn):
    for key, (net, pages) in drawn.items():
        if len(pages) == 1:
            continue
        page_of = {e: i for i, p in enumerate(pages) for e in p.amplifiers + p.pots}
        page_of.update({x.id: page_of[x.amplifier] for x in net.parts if x.amplifier in page_of})
        flagged = [{n for _, details, _ in _flags(p) for n in _numbers(details)} for p in pages]
        crossing = 0
        for n, c in enumerate(cords(net), 1):
            if c.source not in page_of or c.target not in page_of or page_of[c.source] == page_of[c.target]:
                continue  # a sensor's cord (every page draws its sensors), the servo's, or one on a page
            crossing += 1
            assert n in flagged[page_of[c.source]] and n in flagged[page_of[c.target]], (key, n, c)
        assert crossing, key


def test_bench_lqgs_second_unit_has_no_flag_for_the_third_units_pots():
    made = patch_of("bench-lqg", "gp6")
    pages = [p for p in diagram_parts(made[0].netlist) if p.caption.startswith("Unit U2 ")]
    names = [n for p in pages for n, _, _ in _flags(p)]
    assert "from U1.A1" not in names and "from U1.A2" not in names
    assert "from U3.P1" in names and "from U3.P2" in names  # U1.A1 and U1.A2 reach U2 through U3's pots
