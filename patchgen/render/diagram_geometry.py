"""Coordinates of a wiring diagram, from its layout in index space.

Every label gets room of its own before anything is placed: a row is as tall as what its
amplifiers and terminals need above and below their centre line (pots, settings, parts and their
labels, the IC, feedback loops, terminal names and details); a stage is as wide as its pot column
(with the settings), its parts columns, its widest amplifier and the longest label on an output
lead. Wires between stages run in channels and lanes that hold no label, so no label meets a wire
it does not name, an element, or another label.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from patchgen.render.diagram_graph import Block, Graph
from patchgen.render.diagram_layout import Layout, self_feeds, track_order
from patchgen.render.diagram_symbols import (
    DESCENT,
    FLAG,
    GAP,
    LANE_PITCH,
    LEAD,
    LOOP_PITCH,
    NAME_PT,
    PIN_PITCH,
    PLATE,
    PT,
    RESISTOR,
    ROW_GAP,
    SIGNAL_PT,
    SMALL_PT,
    TERMINAL_R,
    TRACK_PITCH,
    amp_shape,
    line_pitch,
    pot_radius,
    text_height,
    text_width,
)

LABEL_CLEAR = 0.08      # from an output lead to the label on it
IC_STUB = 0.15          # the IC input's stub above an integrator's rectangle, its label beside it
PART_WIDTH = {0: 0.10, 1: RESISTOR}   # symbol width of a part by its place in the series


@dataclass
class Shape:
    """An amplifier's symbol and what it needs around its centre line."""

    half: float
    box: float
    width: float
    up: float = 0.0
    down: float = 0.0
    loops: list[float] = field(default_factory=list)   # heights of its feedback loops, inner first


@dataclass
class Geometry:
    """A diagram in drawing units (y up)."""

    pitch: float
    pot_r: float
    row_y: list[float]
    lane_y: dict[tuple[int, int], float]
    stage_left: list[float]
    stage_right: list[float]
    pot_x: dict[int, float]                  # stage -> left edge of its pots
    part_x: dict[str, list[float]]           # block -> centre of each input part's slot
    amp_x: dict[str, float]                  # block -> input side of an amplifier, or a terminal
    chan_x: dict[tuple[int, str], float]     # (channel, net) -> track
    shapes: dict[str, Shape]

    def y(self, key: tuple) -> float:
        """Height of a row key (row, offset in pitches) or a lane key (gap, slot)."""
        if key[0] == "row":
            return self.row_y[key[1]] + key[2] * self.pitch
        return self.lane_y[(key[1], key[2])]


def name_pt(kind: str) -> float:
    """Font size of a terminal's name: sensors and the control voltage large, connectors smaller."""
    return SIGNAL_PT if kind == "connector" else NAME_PT


def terminal_reach(kind: str, name: str, details: tuple[str, ...]) -> tuple[float, float, float]:
    """(width, up, down) a terminal's labels take beside it."""
    w = max([text_width(name, name_pt(kind))] + [text_width(d, SMALL_PT) for d in details])
    return w, GAP + text_height(name_pt(kind)), GAP + len(details) * line_pitch(SMALL_PT)


def loops_of(block: Block) -> list[int | None]:
    """A block's feedback loops, inner first: None for a lag's capacitor, else the self feed's index."""
    return ([None] if block.feedback else []) + self_feeds(block)


def _self_loops(block: Block) -> int:
    return len(self_feeds(block))


def part_label_reach() -> float:
    """Height a part's id (above) or value (below) needs from its wire."""
    return PLATE + GAP + text_height(SMALL_PT)


def measure(layout: Layout) -> Geometry:
    """The coordinates of every row, lane, stage and track of a laid-out diagram."""
    graph: Graph = layout.graph
    pot_ids = [f.pot for b in graph.blocks + graph.outputs for f in b.feeds if f.pot]
    pot_r = pot_radius(pot_ids)
    multi_parts = any(len(b.feeds) > 1 and any(f.parts for f in b.feeds) for b in graph.blocks)
    pitch = max(PIN_PITCH, 2 * pot_r + 0.12, 2 * part_label_reach() + GAP if multi_parts else 0.0)

    # Vertical: what each row needs above and below its centre line.
    up = [0.30] * layout.n_rows
    down = [0.30] * layout.n_rows
    for s in graph.sources:
        _, u, d = terminal_reach(s.kind, s.name, s.details)
        r = layout.source_row[s.id]
        up[r], down[r] = max(up[r], u), max(down[r], d)
    shapes: dict[str, Shape] = {}
    for b in graph.blocks + graph.outputs:
        p = layout.places[b.id]
        if b.is_amplifier:
            shape = _amp_shape(b, pitch, pot_r)
            shapes[b.id] = shape
            u, d = shape.up, shape.down
        else:
            _, u, d = terminal_reach(b.role, b.name, b.details)
            if b.feeds[0].pot:
                u = max(u, pot_r, GAP + text_height(SIGNAL_PT))
                d = max(d, pot_r)
        up[p.row], down[p.row] = max(up[p.row], u), max(down[p.row], d)

    row_y: list[float] = []
    lane_y: dict[tuple[int, int], float] = {}
    cursor = 0.0
    for gap in range(layout.n_rows + 1):
        inner = ROW_GAP if 0 < gap < layout.n_rows else 0.0
        for s in range(layout.slots[gap]):
            lane_y[(gap, s)] = cursor - inner / 2 - (s + 0.5) * LANE_PITCH
        cursor -= inner + layout.slots[gap] * LANE_PITCH
        if gap < layout.n_rows:
            row_y.append(cursor - up[gap])
            cursor -= up[gap] + down[gap]

    def y_of(key: tuple) -> float:
        return row_y[key[1]] + key[2] * pitch if key[0] == "row" else lane_y[(key[1], key[2])]

    # Horizontal: channels and stages, left to right.
    stage_left, stage_right = [0.0], [0.0]      # source terminals end at x = 0
    pot_x: dict[int, float] = {}
    part_x: dict[str, list[float]] = {}
    amp_x: dict[str, float] = {}
    chan_x: dict[tuple[int, str], float] = {}
    for stage in range(1, layout.out_stage + 1):
        ch = stage - 1
        order = track_order(layout.nets, ch)
        for i, k in enumerate(order):
            chan_x[(ch, k)] = stage_right[ch] + (i + 1) * TRACK_PITCH
        left = stage_right[ch] + (len(order) + 1) * TRACK_PITCH
        stage_left.append(left)
        blocks = [pl.block for pl in layout.places.values() if pl.stage == stage]
        nested = max([_self_loops(b) for b in blocks], default=0)
        if any(f.pot for b in blocks for f in b.feeds):
            pot_x[stage] = left + LEAD + nested * LOOP_PITCH
        for b in blocks:
            x = left + LEAD + _self_loops(b) * LOOP_PITCH
            pots = [f for f in b.feeds if f.pot]
            if pots:
                settings = max(text_width(f.setting, SIGNAL_PT) for f in pots)
                x = pot_x[stage] + 2 * pot_r + max(LEAD, settings + 2 * GAP)
            part_x[b.id] = []
            for i in range(max((len(f.parts) for f in b.feeds), default=0)):
                texts = [t for f in b.feeds if len(f.parts) > i for t in (f.parts[i].id, f.parts[i].value)]
                w = max([PART_WIDTH.get(i, RESISTOR)] + [text_width(t, SMALL_PT) for t in texts]) + 2 * GAP
                part_x[b.id].append(x + w / 2)
                x += w + (LEAD / 2 if i == 0 else 0.0)
            amp_x[b.id] = x + (LEAD / 2 if part_x[b.id] else 0.0)
        if stage == layout.out_stage:
            xo = max((amp_x[b.id] for b in blocks), default=left)
            reach = []
            for b in blocks:
                amp_x[b.id] = xo
                reach.append(terminal_reach(b.role, b.name, b.details)[0]
                             + (FLAG if b.role == "connector" else 2 * TERMINAL_R))
            stage_right.append(xo + GAP + max(reach, default=0.0))
            break
        # A label on an output lead may reach into the channel on its right, up to the first
        # track that passes its height (wires leave a track only at heights the track spans).
        spans = []
        for k in track_order(layout.nets, stage):
            ys = [y_of(key) for key in layout.nets[k].tracks[stage]]
            spans.append((k, min(ys), max(ys)))
        right = left
        for b in blocks:
            yc = row_y[layout.places[b.id].row]
            x_out = amp_x[b.id] + shapes[b.id].width
            start = lead_label_x(x_out, len(shapes[b.id].loops))
            lines = lead_lines(b.label)
            y0, y1 = yc + LABEL_CLEAR, yc + LABEL_CLEAR + len(lines) * line_pitch(SIGNAL_PT)
            free = len(spans)
            for i, (k, lo, hi) in enumerate(spans):
                if (hi > yc + 1e-9) if k == b.id else (hi >= y0 - 0.08 and lo <= y1 + 0.08):
                    free = i
                    break
            end = start + max(text_width(t, SIGNAL_PT) for t in lines) + GAP
            right = max(right, start + GAP, end - (free + 1) * TRACK_PITCH)
        stage_right.append(right)
    return Geometry(pitch, pot_r, row_y, lane_y, stage_left, stage_right, pot_x, part_x, amp_x, chan_x,
                    shapes)


def _amp_shape(b: Block, pitch: float, pot_r: float) -> Shape:
    """An amplifier's symbol size, and the room it and its pins' labels take above and below."""
    half, box, width = amp_shape(b.role, b.name, [f.weight for f in b.feeds], pitch, b.mark)
    top_pin = (len(b.feeds) - 1) / 2 * pitch
    up = down = half
    if any(f.pot for f in b.feeds):
        up = max(up, top_pin + pot_r, top_pin + GAP + text_height(SIGNAL_PT))
        down = max(down, top_pin + pot_r)
    if any(f.parts for f in b.feeds):
        up = max(up, top_pin + part_label_reach())
        down = max(down, top_pin + part_label_reach())
    if b.ic:
        up = max(up, half + max(IC_STUB, GAP + text_height(SMALL_PT)))
    up = max(up, LABEL_CLEAR + len(lead_lines(b.label)) * line_pitch(SIGNAL_PT))
    loops: list[float] = []
    for k in loops_of(b):
        if k is None:       # the capacitor, its id and value above it
            y = up + PLATE + GAP
            up = y + part_label_reach() + line_pitch(SMALL_PT)
        else:
            y = up + (GAP if not loops else LOOP_PITCH - GAP)
            up = y + GAP
        loops.append(y)
    return Shape(half, box, width, up + GAP, down + GAP, loops)


def label_baseline_above(y: float, size_pt: float, clear: float = GAP) -> float:
    """Baseline of a label whose box starts ``clear`` above height y."""
    return y + clear + DESCENT * size_pt * PT


def lead_lines(label: str) -> list[str]:
    """The lines of the label on an output lead: a long one in two, at its first space."""
    if len(label) > 9 and " " in label:
        return list(label.split(" ", 1))
    return [label]


def loop_right_x(x_out: float, k: int) -> float:
    """Where the k-th feedback loop (inner first) leaves an amplifier's output lead."""
    return x_out + LEAD / 2 + k * LOOP_PITCH


def lead_label_x(x_out: float, n_loops: int) -> float:
    """Where the label on an amplifier's output lead starts: past its feedback loops."""
    return (loop_right_x(x_out, n_loops - 1) if n_loops else x_out) + 1.5 * GAP
