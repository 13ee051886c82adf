"""The wiring diagram of a patch, as SVG in analog-computer notation.

Drawn with schemdraw's SVG backend and a few custom elements: an inverting amplifier is a
triangle with the weight of each input (1 or 10) written inside beside it; an integrator has a
rectangle on its input side (holding the weights) and its IC input on top; a differentiator is
marked d/dt and has its external capacitor and series resistor on each input; a lag patched as a
summer has its external capacitor across its feedback, drawn over it; an amplifier fed back from
its own output (a lag built from an integrator and a pot) has that loop drawn over it, from its
output back through the pot to its input. A coefficient pot is a circle with its id, its setting
written on the wire it feeds; an external part is labelled with its id above and its value below.
Sensors are named on the left, the control voltage u_c on the right; on a diagram of one unit of
slaved units (or one part of a diagram split to fit a page: patchgen.render.diagram_pages), a flag
stands for a cord to or from an element drawn elsewhere, named for the jack at its other end.

Layout is by stages, left to right (patchgen.render.diagram_layout), and every label has room of
its own (patchgen.render.diagram_geometry). Everything is computed from the netlist alone, in a
fixed order, so the same netlist gives the same bytes.
"""

from __future__ import annotations

from patchgen.patch.netlist import Netlist
from patchgen.render.diagram_geometry import (
    IC_STUB,
    LABEL_CLEAR,
    Geometry,
    lead_label_x,
    lead_lines,
    loop_right_x,
    loops_of,
    measure,
    name_pt,
)
from patchgen.render.diagram_graph import Block, Graph, whole_graph
from patchgen.render.diagram_layout import Layout, place
from patchgen.render.diagram_symbols import (
    ASCENT,
    DESCENT,
    FLAG,
    FONT,
    GAP,
    LEAD,
    LOOP_PITCH,
    PLATE,
    PT,
    RESISTOR,
    SIGNAL_PT,
    SMALL_PT,
    TERMINAL_R,
    WIRE_LW,
    AmplifierSymbol,
    Capacitor,
    Connector,
    Dot,
    Label,
    PotSymbol,
    Resistor,
    Terminal,
    line_pitch,
    text_box,
)
from patchgen.render.schematic import BBox, Line, schemdraw, svg_backend


def wiring_svg(netlist: Netlist) -> str:
    """The wiring diagram of the whole patch as an SVG document.

    Parameters
    ----------
    netlist : Netlist
        The patch.

    Returns
    -------
    str
        SVG text: every sensor, amplifier, pot and external part, and the control voltage; the
        same netlist gives the same bytes.
    """
    return wiring_diagram(netlist).svg


def wiring_diagram(netlist: Netlist) -> Diagram:
    """The wiring diagram of the whole patch, drawn (:func:`wiring_svg` is its SVG)."""
    return graph_diagram(whole_graph(netlist))


def graph_svg(graph: Graph) -> str:
    """The SVG document of one diagram (patchgen.render.diagram_graph)."""
    return graph_diagram(graph).svg


def graph_diagram(graph: Graph) -> Diagram:
    """One diagram laid out and drawn, its SVG rendered when first asked for."""
    layout = place(graph)
    return Diagram(graph, _Painter(layout, measure(layout)).paint())


def labels_size_pt(graph: Graph) -> tuple[float, float]:
    """The size (pt) of a diagram's labels alone, at a tenth of the cost of drawing it: its labels'
    extents are part of its bounds, so this is no larger than ``graph_diagram(graph).size_pt``
    (the same floats, through the same sums), and near it: the labels reach furthest out."""
    layout = place(graph)
    return Diagram(graph, _Painter(layout, measure(layout), _Labels).paint()).size_pt


class Diagram:
    """A diagram drawn: its graph, its size as its SVG states it, and the SVG, rendered once and
    only when asked for (a diagram too large for a page is measured, then drawn again in parts)."""

    def __init__(self, graph: Graph, drawing: _Drawing):
        self.graph, self._drawing, self._svg = graph, drawing, None

    @property
    def size_pt(self) -> tuple[float, float]:
        """Width and height (pt): the drawing's bounds with schemdraw's margin, at its scale, as
        its SVG backend sizes the document (the same floats the SVG's width and height print)."""
        d = self._drawing
        fig = svg_backend.Figure(bbox=d.get_bbox(), inches_per_unit=d.dwgparams.get("inches_per_unit"),
                                 margin=d.dwgparams.get("margin"))
        return fig.pxwidth, fig.pxheight

    @property
    def svg(self) -> str:
        """The SVG document (see :func:`_render`)."""
        if self._svg is None:
            self._svg = _render(self._drawing)
        return self._svg


class _Painter:
    """Draws a laid-out, measured diagram on a schemdraw drawing."""

    def __init__(self, layout: Layout, geo: Geometry, drawing: type[_Drawing] | None = None):
        self.layout, self.geo = layout, geo
        self.d = (drawing or _Drawing)(canvas="svg", show=False)
        self.d.config(fontsize=SMALL_PT, font=FONT, lw=WIRE_LW, margin=0.1)
        self.wires: list[tuple[str, tuple[float, float], tuple[float, float]]] = []

    def wire(self, net: str, *pts: tuple[float, float]) -> None:
        for a, b in zip(pts, pts[1:]):
            if abs(a[0] - b[0]) > 1e-9 or abs(a[1] - b[1]) > 1e-9:
                self.wires.append((net, a, b))

    def label(self, text: str, size: float, x: float, y: float, anchor: str = "middle") -> None:
        """A label with its baseline at (x, y)."""
        self.d.add(Label(text, size, anchor).at((x, y)))
        x0, y0, x1, y1 = text_box(x, y, text, size, anchor)
        self.d.extent(x0, y0)
        self.d.extent(x1, y1)

    def paint(self) -> _Drawing:
        """Every element added to the drawing (rendering is :func:`_render`)."""
        g = self.layout.graph
        for s in g.sources:
            self.terminal(s.kind, s.name, s.details, self.geo.row_y[self.layout.source_row[s.id]], "left")
        for b in g.blocks:
            self.amplifier(b)
        for b in g.outputs:
            self.output(b)
        self.nets()
        for _, a, b in self.wires:
            self.d.add(Line().at(a).to(b).linewidth(WIRE_LW))
        for pt in _junctions(self.wires):
            self.d.add(Dot().at(pt))
        return self.d

    def terminal(self, kind: str, name: str, details: tuple[str, ...], y: float, side: str,
                 x: float = 0.0) -> None:
        """A sensor, the control voltage or a connector at (x, y), its labels outside it."""
        if kind == "connector":
            self.d.add(Connector(side).at((x, y)))
            reach = FLAG
        else:
            self.d.add(Terminal().at((x - TERMINAL_R if side == "left" else x + TERMINAL_R, y)))
            reach = 2 * TERMINAL_R
        sign, anchor = (-1, "end") if side == "left" else (1, "start")
        xt = x + sign * (reach + GAP)
        size = name_pt(kind)
        self.label(name, size, xt, y + GAP + DESCENT * size * PT, anchor)
        for i, line in enumerate(details):
            top = y - GAP - i * line_pitch(SMALL_PT)
            self.label(line, SMALL_PT, xt, top - ASCENT * SMALL_PT * PT, anchor)

    def amplifier(self, b: Block) -> None:
        geo, p = self.geo, self.layout.places[b.id]
        yc, xa = geo.row_y[p.row], geo.amp_x[b.id]
        sh = geo.shapes[b.id]
        pins = [(p.offset(j) * geo.pitch, b.feeds[j].weight) for j in range(len(b.feeds))]
        self.d.add(AmplifierSymbol(b.name, b.role, pins, geo.pitch, b.mark).at((xa, yc)))
        x_out = xa + sh.width
        self.wire(b.id, (x_out, yc), (geo.stage_right[p.stage], yc))
        lines = lead_lines(b.label)
        for i, line in enumerate(lines):
            self.label(line, SIGNAL_PT, lead_label_x(x_out, len(sh.loops)),
                       yc + LABEL_CLEAR + (len(lines) - 1 - i) * line_pitch(SIGNAL_PT) + DESCENT * SIGNAL_PT * PT,
                       "start")
        if b.ic:
            xi = xa + sh.box / 2
            self.wire(b.id + " ic", (xi, yc + sh.half), (xi, yc + sh.half + IC_STUB))
            self.label(b.ic, SMALL_PT, xi + GAP, yc + sh.half + GAP + DESCENT * SMALL_PT * PT, "start")
        for j in range(len(b.feeds)):
            self.feed(b, j, xa, yc + p.offset(j) * geo.pitch)
        self_loop = 0
        for k, (j, y_loop) in enumerate(zip(loops_of(b), sh.loops)):
            xr = loop_right_x(x_out, k)
            if j is None:       # a lag's capacitor across its feedback
                xc = (xa + xr) / 2
                self.wire(b.id, (xa, yc + sh.half), (xa, yc + y_loop), (xc - 0.05, yc + y_loop))
                self.wire(b.id, (xc + 0.05, yc + y_loop), (xr, yc + y_loop), (xr, yc))
                self.d.add(Capacitor().at((xc, yc + y_loop)))
                base = yc + y_loop + PLATE + GAP + DESCENT * SMALL_PT * PT
                self.label(b.feedback.value, SMALL_PT, xc, base)
                self.label(b.feedback.id, SMALL_PT, xc, base + line_pitch(SMALL_PT))
                continue
            y_pin = yc + p.offset(j) * geo.pitch
            x_in = geo.pot_x[p.stage] if b.feeds[j].pot else xa
            xl = x_in - LEAD / 2 - self_loop * LOOP_PITCH
            self_loop += 1
            self.wire(b.id, (xr, yc), (xr, yc + y_loop), (xl, yc + y_loop), (xl, y_pin), (x_in, y_pin))

    def feed(self, b: Block, j: int, x_end: float, y: float) -> None:
        """A block's feed from where its wire arrives: pot, setting, parts, into x_end."""
        geo, stage = self.geo, self.layout.places[b.id].stage
        f = b.feeds[j]
        x = geo.pot_x.get(stage, x_end) if f.pot else None
        if f.pot:
            self.d.add(PotSymbol(f.pot, geo.pot_r).at((x, y)))
            x += 2 * geo.pot_r
            self.label(f.setting, SIGNAL_PT, x + GAP, y + GAP + DESCENT * SIGNAL_PT * PT, "start")
        for i, part in enumerate(f.parts):
            xc = geo.part_x[b.id][i]
            half = 0.05 if i == 0 else RESISTOR / 2
            if x is not None:
                self.wire(f"{b.id} in{j}", (x, y), (xc - half, y))
            if i == 0:
                self.d.add(Capacitor().at((xc, y)))
            else:
                self.d.add(Resistor().at((xc - half, y)))
            self.part_labels(part, xc, y)
            x = xc + half
        if x is not None:
            self.wire(f"{b.id} in{j}", (x, y), (x_end, y))

    def part_labels(self, part, xc: float, y: float) -> None:
        """A part's id above it and its value below."""
        self.label(part.id, SMALL_PT, xc, y + PLATE + GAP + DESCENT * SMALL_PT * PT)
        self.label(part.value, SMALL_PT, xc, y - PLATE - GAP - ASCENT * SMALL_PT * PT)

    def output(self, b: Block) -> None:
        geo, p = self.geo, self.layout.places[b.id]
        y, xo = geo.row_y[p.row], geo.amp_x[b.id]
        if b.feeds[0].pot:
            self.feed(b, 0, xo, y)
        self.terminal(b.role, b.name, b.details, y, "right", xo)

    def entry_x(self, b: Block, j: int) -> float:
        """Where the wire of block b's feed j arrives from its channel."""
        geo, stage = self.geo, self.layout.places[b.id].stage
        f = b.feeds[j]
        if f.pot:
            return geo.pot_x[stage]
        if f.parts:
            return geo.part_x[b.id][0] - 0.05
        return geo.amp_x[b.id]

    def nets(self) -> None:
        """Stubs, tracks and lanes of every net."""
        geo, lay = self.geo, self.layout
        for k, n in lay.nets.items():
            if not n.sinks:
                continue
            y_out = geo.y(("row", n.row, 0.0))
            self.wire(k, (geo.stage_right[n.stage], y_out), (geo.chan_x[(n.stage, k)], y_out))
            for ch, keys in n.tracks.items():
                ys = [geo.y(key) for key in keys]
                xt = geo.chan_x[(ch, k)]
                self.wire(k, (xt, max(ys)), (xt, min(ys)))
            for ch_from, ch_to, key in n.lanes:
                y = geo.y(key)
                self.wire(k, (geo.chan_x[(ch_from, k)], y), (geo.chan_x[(ch_to, k)], y))
            for s in n.sinks:
                y = geo.y(s.ykey)
                block = lay.places[s.block].block
                self.wire(k, (geo.chan_x[(s.stage - 1, k)], y), (self.entry_x(block, s.feed), y))


class _Drawing(schemdraw.Drawing):
    """A drawing whose bounds also cover its labels (schemdraw underestimates text width), found
    once for what it holds (a diagram's size and its SVG both ask for them)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._extents: list[tuple[float, float]] = []
        self._bbox: tuple[tuple[int, int], object] | None = None  # (element and extent counts, bounds)

    def extent(self, x: float, y: float) -> None:
        self._extents.append((x, y))

    def get_bbox(self):
        held = (len(self.elements), len(self._extents))
        if self._bbox is None or self._bbox[0] != held:
            box = super().get_bbox()
            xs = [x for x, _ in self._extents] + [box.xmin, box.xmax]
            ys = [y for _, y in self._extents] + [box.ymin, box.ymax]
            self._bbox = held, type(box)(min(xs), min(ys), max(xs), max(ys))
        return self._bbox[1]


class _Labels(_Drawing):
    """A drawing that places nothing and keeps its labels' extents alone (:func:`labels_size_pt`)."""

    def add(self, element):
        return element

    def get_bbox(self):
        if not self._extents:  # no label: a point (any size is at least its margins)
            return BBox(0.0, 0.0, 0.0, 0.0)
        xs, ys = zip(*self._extents)
        return BBox(min(xs), min(ys), max(xs), max(ys))


def _junctions(wires) -> list[tuple[float, float]]:
    """Points where three or more wire ends or passes of one net meet: drawn as dots."""
    by_net: dict[str, list] = {}
    for name, a, b in wires:
        by_net.setdefault(name, []).append(((round(a[0], 6), round(a[1], 6)), (round(b[0], 6), round(b[1], 6))))
    dots: set[tuple[float, float]] = set()
    for segs in by_net.values():
        for pt in sorted({q for s in segs for q in s}):
            degree = sum(1 if pt in (a, b) else 2 if _on_segment(pt, a, b) else 0 for a, b in segs)
            if degree >= 3:
                dots.add(pt)
    return sorted(dots)


def _on_segment(p, a, b) -> bool:
    if a[0] == b[0] == p[0]:
        return min(a[1], b[1]) < p[1] < max(a[1], b[1])
    if a[1] == b[1] == p[1]:
        return min(a[0], b[0]) < p[0] < max(a[0], b[0])
    return False


def _render(d: schemdraw.Drawing) -> str:
    """SVG text of the drawing: text as searchable <text> and clip ids counted from 0 for this
    drawing alone (same netlist, same bytes); schemdraw's process-wide settings are restored after."""
    saved_text, saved_clips = svg_backend.config.text, svg_backend.Figure.total_clips
    svg_backend.config.text = "text"     # searchable <text>, not glyph paths
    svg_backend.Figure.total_clips = 0
    try:
        data = d.get_imagedata("svg").decode("utf-8")
    finally:
        svg_backend.config.text, svg_backend.Figure.total_clips = saved_text, saved_clips
    return data if data.endswith("\n") else data + "\n"
