"""Where each part of a wiring diagram goes, in index space: stages left to right (the sources,
one stage per level of amplifiers, the terminals on the right), rows within a stage, vertical
tracks in the channels between stages, and lanes between rows for wires that skip a stage or feed
back. An amplifier's feedback to its own input is not routed here: it is drawn as a loop over
the amplifier. Everything follows from the graph in a fixed order."""

from __future__ import annotations

from dataclasses import dataclass, field

from patchgen.render.diagram_graph import Block, Graph


@dataclass
class Place:
    """Where a block sits: stage, row and the order of its input pins (feed indices, top first)."""

    block: Block
    stage: int
    row: int
    pins: list[int]

    def offset(self, j: int) -> float:
        """Height of feed j's pin above the block's centre, in pin pitches."""
        return (len(self.pins) - 1) / 2 - self.pins.index(j)


@dataclass
class Sink:
    """One end of a wire: the pot or pin of a block's feed."""

    stage: int
    ykey: tuple          # ("row", row, offset in pitches) or ("gap", gap, slot)
    block: str
    feed: int


@dataclass
class Net:
    """One signal's wiring: its source, the pins it feeds, its tracks and lanes."""

    source: str
    stage: int
    row: int
    sinks: list[Sink] = field(default_factory=list)
    tracks: dict[int, list[tuple]] = field(default_factory=dict)   # channel -> attached ykeys
    lanes: list[tuple[int, int, tuple]] = field(default_factory=list)  # (ch_from, ch_to, ykey)


@dataclass
class Layout:
    """A diagram in index space."""

    graph: Graph
    source_row: dict[str, int]
    places: dict[str, Place]      # amplifiers and right-hand terminals
    nets: dict[str, Net]
    n_rows: int
    out_stage: int
    slots: list[int]              # lanes in each gap between rows (gap 0 above row 0)


def self_feeds(block: Block) -> list[int]:
    """Indices of the feeds an amplifier takes from its own output."""
    return [j for j, f in enumerate(block.feeds) if f.source == block.id]


def place(graph: Graph) -> Layout:
    """Stages, rows, pins, tracks and lanes of every part of a diagram, in index space."""
    out_stage = max(graph.level.values(), default=0) + 1
    row_of: dict[str, int] = {s.id: i for i, s in enumerate(graph.sources)}
    source_row = dict(row_of)
    places: dict[str, Place] = {}
    occupant: list[dict[int, str]] = [{i: s.id for i, s in enumerate(graph.sources)}]
    for stage in range(1, out_stage + 1):
        items = ([b for b in graph.blocks if graph.level[b.id] == stage] if stage < out_stage
                 else list(graph.outputs))

        def bary(b: Block) -> float:
            rows = [row_of[f.source] for f in b.feeds if f.source in row_of and f.source != b.id]
            return sum(rows) / len(rows) if rows else float(len(graph.sources))

        before = occupant[stage - 1]
        occupant.append({})
        nxt = 0
        for k in sorted(range(len(items)), key=lambda k: (bary(items[k]), k)):
            b = items[k]
            pins = sorted(range(len(b.feeds)),
                          key=lambda j: (-1 if b.feeds[j].source == b.id
                                         else row_of.get(b.feeds[j].source, 1e6), j))
            row = max(nxt, int(round(bary(b))))
            # An input entering at the height where another signal leaves the previous stage
            # would read as one wire: move down until the centre input is free or the same.
            if len(pins) % 2 == 1:
                centre = b.feeds[pins[len(pins) // 2]].source
                while before.get(row, centre) != centre:
                    row += 1
            row_of[b.id] = row
            occupant[stage][row] = b.id
            nxt = row + 1
            places[b.id] = Place(b, stage, row, pins)
    n_rows = max(list(row_of.values()), default=0) + 1

    nets: dict[str, Net] = {s.id: Net(s.id, 0, row_of[s.id]) for s in graph.sources}
    for b in graph.blocks:
        nets[b.id] = Net(b.id, places[b.id].stage, places[b.id].row)
    for b in list(graph.blocks) + list(graph.outputs):
        p = places[b.id]
        for j, f in enumerate(b.feeds):
            if f.source != b.id:
                nets[f.source].sinks.append(Sink(p.stage, ("row", p.row, p.offset(j)), b.id, j))

    # Tracks and lanes.
    lane_use: dict[tuple[int, int], list[tuple[int, int]]] = {}  # (gap, slot) -> channel spans
    for n in nets.values():
        if not n.sinks:
            continue
        by_channel: dict[int, list[Sink]] = {}
        for s in n.sinks:
            by_channel.setdefault(s.stage - 1, []).append(s)
        n.tracks.setdefault(n.stage, []).append(("row", n.row, 0.0))
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
    return Layout(graph, source_row, places, nets, n_rows, out_stage, slots)


def track_order(nets: dict[str, Net], channel: int) -> list[str]:
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
