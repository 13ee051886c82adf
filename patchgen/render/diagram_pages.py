"""The wiring diagrams a patch sheet prints, each on a page at a size whose labels can be read.

A patch on one machine is one diagram; a patch on slaved units one diagram per unit. A diagram
that would print its smallest label under PRINTED_MIN_PT when shrunk to a page (PRINT_WIDTH_MM by
PRINT_HEIGHT_MM) is split: its amplifiers, in the order the diagram stacks them, into as few
consecutive parts as print at that size, each on a page of its own, with a flag for every cord
between the parts (patchgen.render.diagram_graph.page_graph).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from patchgen.patch.netlist import Netlist
from patchgen.render.diagram import Diagram, graph_diagram, labels_size_pt, wiring_diagram
from patchgen.render.diagram_graph import Graph, loose_pots, page_graph, unit_of, units
from patchgen.render.diagram_layout import place
from patchgen.render.diagram_symbols import SMALLEST_PT

PRINT_WIDTH_MM = 186.0  # the printed content's width: A4 and Letter's common 210 mm less 12 mm margins
PRINT_HEIGHT_MM = 230.0  # a page's 250 mm of content less a heading and a caption: the tallest a diagram gets
PRINTED_MIN_PT = 6.0  # the smallest label a printed diagram may have
MM_PER_PT = 25.4 / 72.0


def svg_size_mm(svg: str) -> tuple[float, float]:
    """A diagram's width and height (mm), read from its SVG's own width and height (pt)."""
    size = {k: float(v) for k, v in re.findall(r'\b(width|height)="([0-9.eE+-]+)pt"', svg.split(">", 1)[0])}
    if set(size) != {"width", "height"}:
        raise ValueError("the wiring SVG must give its width and height in pt")
    return size["width"] * MM_PER_PT, size["height"] * MM_PER_PT


def printed_scale(svg: str, height_mm: float = PRINT_HEIGHT_MM) -> float:
    """The scale a diagram prints at: its own size, shrunk to the page's width and ``height_mm``."""
    return _scale(*svg_size_mm(svg), height_mm)


def _scale(width: float, height: float, height_mm: float = PRINT_HEIGHT_MM) -> float:
    return min(1.0, PRINT_WIDTH_MM / width, height_mm / height)


def fits(svg: str) -> bool:
    """Whether a diagram, shrunk to a page, prints its smallest label at PRINTED_MIN_PT or more."""
    return _fits_at(printed_scale(svg))


def _fits(diagram: Diagram) -> bool:
    """:func:`fits` for a diagram drawn, from its size, without rendering its SVG."""
    return _fits_pt(*diagram.size_pt)


def _fits_pt(width: float, height: float) -> bool:
    return _fits_at(_scale(width * MM_PER_PT, height * MM_PER_PT))


def _fits_at(scale: float) -> bool:
    return SMALLEST_PT * scale >= PRINTED_MIN_PT - 1e-9


@dataclass(frozen=True)
class DiagramPage:
    """One printed diagram: its caption, what it draws (the amplifiers and pots, by their full
    ids), its graph and its SVG."""

    caption: str
    amplifiers: tuple[str, ...]
    pots: tuple[str, ...]
    graph: Graph
    svg: str


def diagram_pages(net: Netlist, whole: Diagram | None = None) -> list[tuple[str, str]]:
    """The wiring diagrams a patch sheet prints, a page each.

    Parameters
    ----------
    net : Netlist
        The patch.
    whole : Diagram, optional
        Its whole wiring diagram when the caller has drawn it (patchgen.render.diagram.wiring_diagram).

    Returns
    -------
    list of (str, str)
        (caption, SVG text) for each page (:func:`diagram_parts`).
    """
    return [(p.caption, p.svg) for p in diagram_parts(net, whole)]


def diagram_parts(net: Netlist, whole: Diagram | None = None) -> list[DiagramPage]:
    """The wiring diagrams a patch sheet prints, with what each draws.

    Parameters
    ----------
    net : Netlist
        The patch.
    whole : Diagram, optional
        As for :func:`diagram_pages`.

    Returns
    -------
    list of DiagramPage
        One machine: the whole patch, captioned with the design and the machine. Slaved units:
        each unit's amplifiers and pots, named as on its own panel (A1 for U1.A1; the caption says
        which unit), units in order; each cord to or from another unit ends in a flag named for the
        jack at its other end ("from U2.A6", "to U2.P3", "to U1.A7 x1a") with its number in the
        wire list. A diagram too large to print its smallest label at PRINTED_MIN_PT on one page is
        split into parts (the caption says which), with flags between them.
    """
    found = units(net)
    if found == [""]:
        whole = wiring_diagram(net) if whole is None else whole
        if _fits(whole):
            return [DiagramPage(f"{net.design} on {net.machine_name}", tuple(a.id for a in net.amplifiers),
                                tuple(p.id for p in net.pots), whole.graph, whole.svg)]
    pages = []
    for unit in found:
        parts = _parts(net, unit)
        for k, (amps, pots, drawn) in enumerate(parts, 1):
            pages.append(DiagramPage(_caption(net, unit, found, drawn.graph, k, len(parts)), amps, pots,
                                     drawn.graph, drawn.svg))
    return pages


def _parts(net: Netlist, unit: str) -> list[tuple[tuple[str, ...], tuple[str, ...], Diagram]]:
    """A unit's diagram in as few parts as each print at PRINTED_MIN_PT on a page: each part's
    amplifiers, the pots it draws, and its diagram (measured before its SVG is rendered). A whole
    whose labels alone are too large for a page (diagram.labels_size_pt) is not drawn at all."""
    amps = [a.id for a in net.amplifiers if unit_of(a.id) == unit]
    loose = loose_pots(net, unit)
    graph = page_graph(net, unit, amps, loose)
    counts = range(2, max(len(amps), len(loose)) + 1)  # the parts tried when the whole does not fit
    if len(amps) + len(loose) <= 1 or not counts or _fits_pt(*labels_size_pt(graph)):
        whole = _drawn(net, unit, amps, loose, graph)
        if len(amps) + len(loose) <= 1 or not counts or _fits(whole[2]):
            return [whole]
    rows = place(graph).places
    stacked = sorted(amps, key=lambda a: (rows[a].row, rows[a].stage))
    for n in counts:
        best = [_drawn(net, unit, run, pots) for run, pots in _split(net, stacked, loose, n)]
        if all(_fits(drawn) for *_, drawn in best):
            break
    return best


def _drawn(net: Netlist, unit: str, amps: list[str], loose: list[str], graph: Graph | None = None):
    """One part drawn: its amplifiers, the pots it draws (theirs on this unit, and ``loose``), and
    its diagram (of ``graph``, its page graph, when the caller has made it)."""
    graph = page_graph(net, unit, amps, loose) if graph is None else graph
    pots = tuple(p.id for p in net.pots if (unit_of(p.id) == unit and p.amplifier in amps) or p.id in loose)
    return tuple(amps), pots, graph_diagram(graph)


def _split(net: Netlist, amps: list[str], loose: list[str], n: int) -> list[tuple[list[str], list[str]]]:
    """A unit in n parts, (amplifiers, loose pots) each: its amplifiers in n consecutive runs (or, on
    a unit of pots alone, its pots); each loose pot with the amplifier that feeds it, else in the
    part with the fewest."""
    if not amps:
        return [([], run) for run in _runs(loose, n)]
    runs = _runs(amps, n)
    placed: list[list[str]] = [[] for _ in runs]
    for pid in loose:
        src = net.pot(pid).source
        k = next((i for i, run in enumerate(runs) if src in run), None)
        if k is None:
            k = min(range(len(runs)), key=lambda i: (len(runs[i]) + len(placed[i]), i))
        placed[k].append(pid)
    return list(zip(runs, placed))


def _runs(items: list[str], n: int) -> list[list[str]]:
    """``items`` in n consecutive runs of near-equal length (the longer ones first)."""
    n = min(n, len(items))
    size, extra = divmod(len(items), n)
    out, start = [], 0
    for k in range(n):
        end = start + size + (1 if k < extra else 0)
        out.append(items[start:end])
        start = end
    return out


def _caption(net: Netlist, unit: str, found: list[str], graph: Graph, k: int, parts: int) -> str:
    """What a page's diagram is: its unit (and part), what it holds, how its elements are named."""
    n_amps = len(graph.blocks)
    n_pots = sum(1 for b in graph.blocks + graph.outputs for f in b.feeds if f.pot)
    part = f", part {k} of {parts}" if parts > 1 else ""
    if not unit:
        return (f"{net.design} on {net.machine_name}{part}: {_count(n_amps, 'amplifier')} and "
                f"{_count(n_pots, 'pot')}; a flag is a cord to or from another part")
    others = [u for u in found if u != unit]
    where = " or ".join(filter(None, [", ".join(others), "another part of this unit" if parts > 1 else ""]))
    first = next((b.name for b in graph.blocks), None) or next(f.pot for b in graph.outputs for f in b.feeds if f.pot)
    return (f"Unit {unit} of {len(found)}{part}: {_count(n_amps, 'amplifier')} and {_count(n_pots, 'pot')}, "
            f"named as on its panel ({unit}.{first} is {first})" + (f"; a flag is a cord to or from {where}"
                                                                      if where else ""))


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")
