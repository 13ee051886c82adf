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

from dataclasses import dataclass, field

from patchgen.patch.netlist import Amplifier, Netlist
from patchgen.render.schematic import (
    Element,
    Line,
    Segment,
    SegmentCircle,
    SegmentPoly,
    SegmentText,
    schemdraw,
    svg_backend,
)

# Geometry in drawing units (schemdraw draws 0.5 inch per unit, so 1 unit = 36 pt).
PIN_PITCH = 0.72        # vertical distance between two inputs of one amplifier
POT_R = 0.26            # pot circle radius
POT_LEAD = 0.30         # wire from the stage's left edge to a pot
POT_TO_AMP = 0.80       # wire from a pot to its amplifier input (the setting is written on it)
AMP_LEAD = 0.25         # left margin of a stage without pots
OUT_LEAD = 0.75         # amplifier output lead (what it carries is written on it)
TRACK_PITCH = 0.22      # distance between vertical tracks in a channel
LANE_PITCH = 0.22       # distance between lanes in one gap between rows
ROW_GAP = 0.30          # empty space between two rows
INT_BOX = 0.42          # width of the integrator's input rectangle
SENSOR_PAD = 0.30       # half height of a sensor or output terminal row
WIRE_LW = 1.1
SYMBOL_LW = 1.5
FONT = "DejaVu Sans, Arial, sans-serif"

_GREEK = {"theta": "θ", "phi": "φ", "alpha": "α", "omega": "ω"}


def quantity_label(q: str) -> str:
    """Readable name of a state or signal: theta_dot -> θ̇, int_theta -> ∫θ, xhat_s -> ŝ."""
    hat = ""
    if q.startswith("xhat_"):
        q, hat = q[5:], "\u0302"
    dot = ""
    if q.endswith("_dot"):
        q, dot = q[:-4], "\u0307"
    integral = ""
    if q.startswith("int_"):
        q, integral = q[4:], "∫"
    base = _GREEK.get(q, q)
    return f"{integral}{base}{hat}{dot}"


def signed_label(polarity: int, quantity: str) -> str:
    return ("+" if polarity > 0 else "−") + quantity_label(quantity)


# ----------------------------------------------------------------------------------------------
# Custom elements (local coordinates: origin at the element's reference point)


class PotSymbol(Element):
    """Coefficient pot: a circle with its id; input on the left, wiper output on the right."""

    def __init__(self, pot_id: str, radius: float, **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentCircle((radius, 0), radius, lw=SYMBOL_LW))
        self.segments.append(SegmentText((radius, 0), pot_id, fontsize=7, font=FONT,
                                         align=("center", "center")))


class AmplifierSymbol(Element):
    """Inverting amplifier in analog-computer notation, drawn from its input side at x = 0.

    ``pins`` are the input heights (relative to the centre) with their weights, top first.
    """

    def __init__(self, amp_id: str, role: str, pins: list[tuple[float, int]], half: float,
                 **kwargs):
        super().__init__(**kwargs)
        width = amp_width(role, half, amp_id, pins)
        x0 = INT_BOX if role in ("integrator", "lag") else 0.0
        tri = [(x0, half), (width, 0.0), (x0, -half)]
        self.segments.append(SegmentPoly(tri, lw=SYMBOL_LW, fill="white"))
        if role in ("integrator", "lag"):
            self.segments.append(SegmentPoly([(0, half), (x0, half), (x0, -half), (0, -half)],
                                             lw=SYMBOL_LW, fill="white"))
        for y, w in pins:
            x_text = 0.06 if role in ("integrator", "lag") else 0.08
            self.segments.append(SegmentText((x_text, y), str(w), fontsize=7, font=FONT,
                                             align=("left", "center")))
        cx = x0 + _label_offset(pins) + _label_width(amp_id) / 2
        self.segments.append(SegmentText((cx, 0.0 if role in ("summer", "inverter") else 0.17),
                                         amp_id, fontsize=8.5, font=FONT,
                                         align=("center", "center")))
        if role == "differentiator":
            self.segments.append(SegmentText((cx, -0.17), "d/dt", fontsize=6.5, font=FONT,
                                             align=("center", "center")))
        elif role == "integrator":
            self.segments.append(SegmentText((cx, -0.17), "∫", fontsize=8, font=FONT,
                                             align=("center", "center")))
        elif role == "lag":
            self.segments.append(SegmentText((cx, -0.17), "lag", fontsize=6.5, font=FONT,
                                             align=("center", "center")))
        self.anchors["out"] = (width, 0)


class Capacitor(Element):
    """Two plates across a horizontal wire at x = 0 (differentiator input)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        g, h = 0.05, 0.13
        self.segments.append(SegmentPoly([(-g, h), (g, h), (g, -h), (-g, -h)], color="white",
                                         fill="white", lw=0.1, zorder=3))
        self.segments.append(Segment([(-g, h), (-g, -h)], lw=SYMBOL_LW, zorder=4))
        self.segments.append(Segment([(g, h), (g, -h)], lw=SYMBOL_LW, zorder=4))


class Terminal(Element):
    """A named signal entering or leaving the machine: an open circle and its labels."""

    def __init__(self, name: str, details: list[str], side: str, **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentCircle((0, 0), 0.07, lw=SYMBOL_LW, fill="white", zorder=4))
        sign = -1 if side == "left" else 1
        align = "right" if side == "left" else "left"
        self.segments.append(SegmentText((sign * 0.15, 0.02), name, fontsize=10, font=FONT,
                                         align=(align, "bottom")))
        for i, line in enumerate(details):
            self.segments.append(SegmentText((sign * 0.15, -0.03 - i * 0.22), line, fontsize=6.5,
                                             font=FONT, align=(align, "top")))


class Text(Element):
    def __init__(self, text: str, size: float, align: tuple[str, str], **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentText((0, 0), text, fontsize=size, font=FONT, align=align))


def amp_half_height(n_inputs: int) -> float:
    return max(0.62, (n_inputs - 1) * PIN_PITCH / 2 + 0.36)


def _label_width(amp_id: str) -> float:
    return len(amp_id) * 0.58 * 8.5 / 36


def pot_radius(net: Netlist) -> float:
    """Pot circle radius: the default, or more for long ids (two-unit patches)."""
    longest = max((len(p.id) for p in net.pots), default=2)
    return max(POT_R, longest * 0.58 * 7 / 36 / 2 + 0.07)


def _weights(a: Amplifier) -> list[tuple[float, int]]:
    return [(0.0, inp.weight) for inp in a.inputs]


def _label_offset(pins: list[tuple[float, int]]) -> float:
    """Where the amplifier's id starts: right of the widest input weight."""
    widest = max((len(str(w)) for _, w in pins), default=1)
    return 0.16 + widest * 0.58 * 7 / 36


def amp_width(role: str, half: float, amp_id: str, pins: list[tuple[float, int]]) -> float:
    room = 0.4 if role in ("summer", "inverter") else 0.65   # two-line label needs more height
    body = max(1.05, 1.25 * half, _label_offset(pins) + _label_width(amp_id) + room)
    return body + (INT_BOX if role in ("integrator", "lag") else 0.0)


# ----------------------------------------------------------------------------------------------
# Placement in index space


@dataclass
class _AmpPlace:
    amp: Amplifier
    stage: int
    row: int = 0
    pins: list[int] = field(default_factory=list)  # input index for each pin, top first
    half: float = 0.62


@dataclass
class _Sink:
    stage: int
    ykey: tuple          # ("row", row, offset in pitches) or ("gap", gap, slot)
    target: tuple        # ("pot", pot id) | ("amp", amp id, pin offset) | ("out",)


@dataclass
class _Net:
    source: str
    stage: int
    row: int
    sinks: list[_Sink] = field(default_factory=list)
    tracks: dict[int, list[tuple]] = field(default_factory=dict)   # channel -> attached ykeys
    lanes: list[tuple[int, int, tuple]] = field(default_factory=list)  # (ch_from, ch_to, ykey)


def _levels(net: Netlist) -> dict[str, int]:
    """Stage of each amplifier: one after its latest source; feedback loops broken in order."""
    sensors = {s.id for s in net.sensors}
    amp_ids = [a.id for a in net.amplifiers]
    for a in net.amplifiers:
        for inp in a.inputs:
            if inp.source not in sensors and inp.source not in amp_ids:
                raise ValueError(f"amplifier {a.id}: unknown source {inp.source!r}")
    level: dict[str, int] = {s: 0 for s in sensors}
    remaining = list(net.amplifiers)
    while remaining:
        ready = [a for a in remaining
                 if all(i.source in level or i.source == a.id for i in a.inputs)]
        pick = ready if ready else [next((a for a in remaining if a.role == "integrator"),
                                         remaining[0])]
        for a in pick:
            placed = [level[i.source] for i in a.inputs if i.source in level]
            level[a.id] = 1 + max(placed, default=0)
        remaining = [a for a in remaining if a.id not in level]
    return level


def _layout(net: Netlist):
    level = _levels(net)
    sensors = [s.id for s in net.sensors]
    n_stages = max([level[a.id] for a in net.amplifiers], default=0) + 2  # + sensors + output
    out_stage = n_stages - 1
    row_of: dict[str, int] = {s: i for i, s in enumerate(sensors)}
    places: dict[str, _AmpPlace] = {}
    occupant: list[dict[int, str]] = [{i: sid for i, sid in enumerate(sensors)}]
    for stage in range(1, out_stage):
        amps = [a for a in net.amplifiers if level[a.id] == stage]

        def bary(a: Amplifier) -> float:
            rows = [row_of[i.source] for i in a.inputs if i.source in row_of]
            return sum(rows) / len(rows) if rows else float(len(sensors))

        order = sorted(range(len(amps)), key=lambda k: (bary(amps[k]), k))
        before = occupant[stage - 1]
        occupant.append({})
        nxt = 0
        for k in order:
            a = amps[k]
            pins = sorted(range(len(a.inputs)),
                          key=lambda j: (row_of.get(a.inputs[j].source, 1e6), j))
            row = max(nxt, int(round(bary(a))))
            # An input entering at the height where another signal leaves the previous stage
            # would read as one wire: move down until the centre input is free or the same.
            if len(pins) % 2 == 1:
                centre = a.inputs[pins[len(pins) // 2]].source
                while before.get(row, centre) != centre:
                    row += 1
            row_of[a.id] = row
            occupant[stage][row] = a.id
            nxt = row + 1
            places[a.id] = _AmpPlace(a, stage, row, pins, amp_half_height(len(a.inputs)))
    out_row = row_of.get(net.output.source, 0)
    last = occupant[out_stage - 1]
    while last.get(out_row, net.output.source) != net.output.source:
        out_row += 1
    n_rows = max(list(row_of.values()) + [out_row]) + 1

    def pin_offset(p: _AmpPlace, j: int) -> float:
        i = p.pins.index(j)
        return (len(p.pins) - 1) / 2 - i      # +: above the centre, in pitches

    nets: dict[str, _Net] = {}
    for sid in sensors:
        nets[sid] = _Net(sid, 0, row_of[sid])
    for a in net.amplifiers:
        nets[a.id] = _Net(a.id, places[a.id].stage, places[a.id].row)
    for a in net.amplifiers:
        p = places[a.id]
        for j, inp in enumerate(a.inputs):
            off = pin_offset(p, j)
            target = ("pot", inp.pot) if inp.pot else ("amp", a.id, off)
            nets[inp.source].sinks.append(_Sink(p.stage, ("row", p.row, off), target))
    nets[net.output.source].sinks.append(_Sink(out_stage, ("row", out_row, 0.0), ("out",)))

    # Tracks and lanes.
    lane_use: dict[tuple[int, int], list[tuple[int, int]]] = {}  # (gap, slot) -> channel spans
    for n in nets.values():
        out_key = ("row", n.row, 0.0)
        by_channel: dict[int, list[_Sink]] = {}
        for s in n.sinks:
            by_channel.setdefault(s.stage - 1, []).append(s)
        if not n.sinks:
            continue
        n.tracks.setdefault(n.stage, []).append(out_key)
        for ch in sorted(by_channel):
            sinks = by_channel[ch]
            n.tracks.setdefault(ch, []).extend(s.ykey for s in sinks)
            if ch == n.stage:
                continue
            span = (min(ch, n.stage), max(ch, n.stage))
            target_row = sum(s.ykey[1] for s in sinks) / len(sinks)
            best = None
            for gap in range(n_rows + 1):
                cost = abs(gap - 0.5 - n.row) + abs(gap - 0.5 - target_row)
                slot = 0
                while any(not (sp[1] < span[0] or sp[0] > span[1])
                          for sp in lane_use.get((gap, slot), [])):
                    slot += 1
                cand = (cost, slot, gap)
                if best is None or cand < best:
                    best = cand
            _, slot, gap = best
            lane_use.setdefault((gap, slot), []).append(span)
            key = ("gap", gap, slot)
            n.tracks[n.stage].append(key)
            n.tracks[ch].append(key)
            n.lanes.append((n.stage, ch, key))
    slots = [1 + max([s for (g, s) in lane_use if g == gap], default=-1)
             for gap in range(n_rows + 1)]
    return level, places, nets, n_rows, out_stage, out_row, slots


def _track_order(nets: dict[str, _Net], channel: int) -> list[str]:
    """Left-to-right order of the tracks in a channel.

    An output stub (from the stage on the left to its track) must not run along an input stub
    of another net at the same height, so a net whose output leaves at height y sits left of
    every net entering the next stage at y. Otherwise tracks follow their mean height.
    """
    members = [k for k, n in nets.items() if channel in n.tracks]

    def mean_row(k: str) -> float:
        keys = nets[k].tracks[channel]
        return sum(y[1] + (0.0 if y[0] == "row" else -0.5) for y in keys) / len(keys)

    members.sort(key=lambda k: (nets[k].stage != channel, mean_row(k), k))
    before: dict[str, set[str]] = {k: set() for k in members}
    for b in members:
        nb = nets[b]
        if nb.stage != channel:
            continue
        out_key = ("row", nb.row, 0.0)
        for a in members:
            if a != b and out_key in nets[a].tracks[channel] and any(
                    s.ykey == out_key and s.stage == channel + 1 for s in nets[a].sinks):
                before[a].add(b)
    order: list[str] = []
    while members:
        pick = next((k for k in members if before[k] <= set(order)), members[0])
        order.append(pick)
        members.remove(pick)
    return order


# ----------------------------------------------------------------------------------------------
# Drawing


def wiring_svg(netlist: Netlist) -> str:
    """The wiring diagram of ``netlist`` as an SVG document (same netlist -> same bytes)."""
    _level, places, nets, n_rows, out_stage, out_row, slots = _layout(netlist)
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
    order = {ch: _track_order(nets, ch) for ch in range(out_stage)}
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
        widths = [amp_width(p.amp.role, p.half, p.amp.id, _weights(p.amp))
                  for p in places.values() if p.stage == stage]
        stage_right.append(a_left + max(widths, default=0.0) + OUT_LEAD)

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
        details = [s.label, f"{s.volts_per_unit:g} V/{unit}"]
        d.add(Terminal(quantity_label(s.quantity), details, "left").at((0, y)))
        d.extent(-0.15 - max(_text_width(t, 6.5) for t in details), y)

    # Amplifiers, their pots and input leads.
    for a in netlist.amplifiers:
        p = places[a.id]
        yc = row_y[p.row]
        xa = amp_left[p.stage]
        pins = [(p.pins.index(j), a.inputs[j].weight) for j in range(len(a.inputs))]
        pin_w = [((len(p.pins) - 1) / 2 - i) * PIN_PITCH for i, _ in pins]
        d.add(AmplifierSymbol(a.id, a.role, [(pin_w[j], w) for j, (_, w) in enumerate(pins)],
                              p.half).at((xa, yc)))
        x_out = xa + amp_width(a.role, p.half, a.id, _weights(a))
        wire(a.id, (x_out, yc), (stage_right[p.stage], yc))
        d.add(Text(signed_label(a.carries.polarity, a.carries.quantity), 8,
                   ("center", "bottom")).at(((x_out + stage_right[p.stage]) / 2 - 0.05, yc + 0.05)))
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

    # Output.
    xo = stage_left[out_stage] + 0.1
    yo = row_y[out_row]
    details = ["to the servo amplifier", f"{netlist.output.K_U_N_per_V:g} N/V"]
    d.add(Terminal("u_c", details, "right").at((xo, yo)))
    d.extent(xo + 0.15 + max(_text_width(t, 6.5) for t in details), yo)

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
        d.add(_Dot().at(pt))

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


def _text_width(text: str, size_pt: float) -> float:
    """Generous width of a label in drawing units (36 pt per unit)."""
    return len(text) * 0.56 * size_pt / 36


def dial_decimals(resolution: float) -> int:
    """Decimals a pot setting is written with, from the dial resolution (0.001 -> 3)."""
    text = f"{resolution:.10f}".rstrip("0")
    return max(0, len(text.split(".")[1]) if "." in text else 0)


class _Dot(Element):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentCircle((0, 0), 0.055, fill=True, lw=0.5, zorder=3))


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
    """SVG text of the drawing, with schemdraw's process-wide id counters reset first."""
    saved_text = svg_backend.config.text
    svg_backend.config.text = "text"     # searchable <text>, not glyph paths
    svg_backend.Figure.total_clips = 0
    try:
        data = d.get_imagedata("svg").decode("utf-8")
    finally:
        svg_backend.config.text = saved_text
    return data if data.endswith("\n") else data + "\n"
