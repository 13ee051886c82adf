"""The wiring diagram of a patch, as SVG in analog-computer notation.

Drawn with schemdraw's SVG backend and a few custom elements: an inverting amplifier is a
triangle with the weight of each input (1 or 10) written inside beside it; an integrator has a
rectangle on its input side and its IC input on top; a differentiator has a capacitor at each
input and is marked d/dt; a coefficient pot is a circle with its id, its setting written on the
wire it feeds. Sensors are named on the left, the control voltage u_c on the right.

Layout is by stages, left to right: the sensors, then for each level of amplifiers (an amplifier
sits one level after its latest source) a column of pots and a column of amplifiers, then the
output. Wires run on vertical tracks in the channels between stages; a wire that skips a stage
or feeds back runs along a lane between rows, which no element occupies. Everything is computed
from the netlist alone, in a fixed order, so the same netlist gives the same bytes.
"""

from __future__ import annotations

from patchgen.patch.netlist import Netlist
from patchgen.render.diagram_layout import place, track_order
from patchgen.render.diagram_symbols import (
    AMP_LEAD,
    FONT,
    INT_BOX,
    LANE_PITCH,
    OUT_LEAD,
    PIN_PITCH,
    POT_LEAD,
    POT_TO_AMP,
    ROW_GAP,
    SENSOR_PAD,
    TRACK_PITCH,
    WIRE_LW,
    AmplifierSymbol,
    Capacitor,
    Dot,
    PotSymbol,
    Terminal,
    Text,
    amp_width,
    dial_decimals,
    pin_weights,
    pot_radius,
    quantity_label,
    signed_label,
    text_width,
)
from patchgen.render.schematic import (
    Line,
    schemdraw,
    svg_backend,
)

# ----------------------------------------------------------------------------------------------
# Drawing


def wiring_svg(netlist: Netlist, outputs: list[tuple[str, str, list[str]]] | None = None,
               terminals: dict[str, tuple[str, list[str]]] | None = None) -> str:
    """The wiring diagram of ``netlist`` as an SVG document (same netlist -> same bytes).

    Parameters
    ----------
    netlist : Netlist
        The patch (or one unit of it, patchgen.render.diagram_units).
    outputs : list of (amplifier id, name, detail lines), optional
        The terminals on the right (default: u_c to the servo amplifier).
    terminals : dict, optional
        Names and detail lines of input terminals by source id (default: each sensor's).
    """
    outputs = outputs or [(netlist.output.source, "u_c",
                           ["to the servo amplifier", f"{netlist.output.K_U_N_per_V:g} N/V"])]
    terminals = terminals or {}
    _level, places, nets, n_rows, out_stage, out_rows, slots = place(netlist, [o[0] for o in outputs])
    pots = {p.id: p for p in netlist.pots}

    # Vertical geometry: gaps (with their lanes) and rows, top to bottom.
    up = [SENSOR_PAD] * n_rows
    down = [SENSOR_PAD] * n_rows
    for p in places.values():
        top = p.half + (0.55 if p.amp.role in ("integrator", "lag") else 0.12)
        up[p.row] = max(up[p.row], top)
        down[p.row] = max(down[p.row], p.half + 0.12)
    row_y: list[float] = []
    lane_y: dict[tuple[int, int], float] = {}
    cursor = 0.0
    for gap in range(n_rows + 1):
        inner = ROW_GAP if 0 < gap < n_rows else 0.0
        for s in range(slots[gap]):
            lane_y[(gap, s)] = cursor - inner / 2 - (s + 0.5) * LANE_PITCH
        cursor -= inner + slots[gap] * LANE_PITCH
        if gap < n_rows:
            row_y.append(cursor - up[gap])
            cursor -= up[gap] + down[gap]

    def y_of(key: tuple) -> float:
        if key[0] == "row":
            return row_y[key[1]] + key[2] * PIN_PITCH
        return lane_y[(key[1], key[2])]

    # Horizontal geometry: stages and channels.
    pot_r = pot_radius(netlist)
    stage_pots = {s: any(i.pot for p in places.values() if p.stage == s for i in p.amp.inputs)
                  for s in range(1, out_stage)}
    order = {ch: track_order(nets, ch) for ch in range(out_stage)}
    stage_left: list[float] = [0.0]
    stage_right: list[float] = [0.0]    # sensor terminals at x = 0
    amp_left: dict[int, float] = {}
    chan_x: dict[tuple[int, str], float] = {}
    for stage in range(1, out_stage + 1):
        ch = stage - 1
        for i, k in enumerate(order[ch]):
            chan_x[(ch, k)] = stage_right[ch] + (i + 1) * TRACK_PITCH
        left = stage_right[ch] + (len(order[ch]) + 1) * TRACK_PITCH
        stage_left.append(left)
        if stage == out_stage:
            stage_right.append(left)
            break
        a_left = left + (POT_LEAD + 2 * pot_r + POT_TO_AMP if stage_pots[stage] else AMP_LEAD)
        amp_left[stage] = a_left
        # each output lead long enough for what it carries, written on it
        widths = [amp_width(p.amp.role, p.half, p.amp.id, pin_weights(p.amp))
                  + max(OUT_LEAD, text_width(signed_label(p.amp.carries.polarity, p.amp.carries.quantity), 8) + 0.3)
                  for p in places.values() if p.stage == stage]
        stage_right.append(a_left + max(widths, default=0.0))

    d = _Drawing(canvas="svg", show=False)
    d.config(fontsize=8, font=FONT, lw=WIRE_LW, margin=0.15)
    wires: list[tuple[str, tuple[float, float], tuple[float, float]]] = []

    def wire(name: str, a: tuple[float, float], b: tuple[float, float]) -> None:
        if abs(a[0] - b[0]) > 1e-9 or abs(a[1] - b[1]) > 1e-9:
            wires.append((name, a, b))

    # Sensors.
    for s in netlist.sensors:
        y = row_y[nets[s.id].row]
        unit = f"({s.unit})" if ("/" in s.unit or " " in s.unit) else s.unit
        name, details = terminals.get(s.id, (quantity_label(s.quantity), [s.label, f"{s.volts_per_unit:g} V/{unit}"]))
        d.add(Terminal(name, details, "left").at((0, y)))
        d.extent(-0.15 - max(text_width(t, 6.5) for t in details), y)

    # Amplifiers, their pots and input leads.
    for a in netlist.amplifiers:
        p = places[a.id]
        yc = row_y[p.row]
        xa = amp_left[p.stage]
        pins = [(p.pins.index(j), a.inputs[j].weight) for j in range(len(a.inputs))]
        pin_w = [((len(p.pins) - 1) / 2 - i) * PIN_PITCH for i, _ in pins]
        d.add(AmplifierSymbol(a.id, a.role, [(pin_w[j], w) for j, (_, w) in enumerate(pins)],
                              p.half).at((xa, yc)))
        x_out = xa + amp_width(a.role, p.half, a.id, pin_weights(a))
        wire(a.id, (x_out, yc), (stage_right[p.stage], yc))
        d.add(Text(signed_label(a.carries.polarity, a.carries.quantity), 8,
                   ("center", "bottom")).at(((x_out + stage_right[p.stage]) / 2 - 0.05, yc + 0.05)))
        across = [x for x in netlist.parts if x.amplifier == a.id and x.jack is None]
        if across:  # a capacitor across the feedback (a lag built as a summer)
            d.add(Text(" + ".join(f"{x.id} {x.fit.split(' (')[0]} across feedback" for x in across), 6,
                       ("left", "top")).at((xa, yc - p.half - 0.06)))
        if a.role in ("integrator", "lag"):
            xi = xa + INT_BOX / 2
            wire(a.id + ".ic", (xi, yc + p.half), (xi, yc + p.half + 0.22))
            ic = "IC" if a.ic_V is None else f"IC {a.ic_V:g} V"
            d.add(Text(ic, 7, ("center", "bottom")).at((xi, yc + p.half + 0.25)))
        for j, inp in enumerate(a.inputs):
            y = yc + pin_w[j]
            if inp.pot:
                xp = stage_left[p.stage] + POT_LEAD
                d.add(PotSymbol(inp.pot, pot_r).at((xp, y)))
                wire(inp.pot, (xp + 2 * pot_r, y), (xa, y))
                setting = f"{pots[inp.pot].setting:.{dial_decimals(netlist.pot_resolution)}f}"
                d.add(Text(setting, 7.5,
                           ("center", "bottom")).at(((xp + 2 * pot_r + xa) / 2, y + 0.04)))
            if a.role == "differentiator":
                d.add(Capacitor().at((xa - 0.22, y)))
        fitted = [x for x in netlist.parts if x.amplifier == a.id and x.jack is not None]
        if fitted:  # a differentiator's external parts, named as the parts list names them, above it
            d.add(Text(", ".join(f"{x.id} {x.fit.split(' (')[0]}" for x in fitted), 6,
                       ("left", "bottom")).at((xa, yc + p.half + 0.06)))

    # Output.
    xo = stage_left[out_stage] + 0.1
    for (_, name, details), row in zip(outputs, out_rows):
        yo = row_y[row]
        d.add(Terminal(name, details, "right").at((xo, yo)))
        d.extent(xo + 0.15 + max([text_width(name, 10)] + [text_width(t, 6.5) for t in details]), yo)

    # Nets: stubs, tracks, lanes.
    for k, n in nets.items():
        if not n.sinks:
            continue
        x_src = stage_right[n.stage]
        xt_out = chan_x[(n.stage, k)]
        wire(k, (x_src, y_of(("row", n.row, 0.0))), (xt_out, y_of(("row", n.row, 0.0))))
        for ch, keys in n.tracks.items():
            ys = [y_of(key) for key in keys]
            xt = chan_x[(ch, k)]
            wire(k, (xt, max(ys)), (xt, min(ys)))
        for ch_from, ch_to, key in n.lanes:
            y = y_of(key)
            wire(k, (chan_x[(ch_from, k)], y), (chan_x[(ch_to, k)], y))
        for s in n.sinks:
            y = y_of(s.ykey)
            xt = chan_x[(s.stage - 1, k)]
            if s.target[0] == "pot":
                x_end = stage_left[s.stage] + POT_LEAD
            elif s.target[0] == "amp":
                x_end = amp_left[s.stage]
            else:
                x_end = xo - 0.07
            wire(k, (xt, y), (x_end, y))

    for _, a, b in wires:
        d.add(Line().at(a).to(b).linewidth(WIRE_LW))
    for pt in _junctions(wires):
        d.add(Dot().at(pt))

    return _render(d)


class _Drawing(schemdraw.Drawing):
    """A drawing whose bounds also cover long labels (schemdraw underestimates text width)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._extents: list[tuple[float, float]] = []

    def extent(self, x: float, y: float) -> None:
        self._extents.append((x, y))

    def get_bbox(self):
        box = super().get_bbox()
        xs = [x for x, _ in self._extents] + [box.xmin, box.xmax]
        ys = [y for _, y in self._extents] + [box.ymin, box.ymax]
        return type(box)(min(xs), min(ys), max(xs), max(ys))


def _junctions(wires) -> list[tuple[float, float]]:
    """Points where three or more wire ends or passes of one net meet: drawn as dots."""
    by_net: dict[str, list] = {}
    for name, a, b in wires:
        by_net.setdefault(name.split(".")[0], []).append((a, b))
    dots: set[tuple[float, float]] = set()
    for segs in by_net.values():
        ends = {(round(x, 6), round(y, 6)) for s in segs for (x, y) in s}
        for pt in sorted(ends):
            degree = 0
            for a, b in segs:
                a_ = (round(a[0], 6), round(a[1], 6))
                b_ = (round(b[0], 6), round(b[1], 6))
                if pt in (a_, b_):
                    degree += 1
                elif _on_segment(pt, a_, b_):
                    degree += 2
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
