"""Where each part of the wiring diagram goes, in index space: stages left to right, rows within a
stage, vertical tracks in the channels between stages and lanes between rows for wires that skip
a stage or feed back. Everything follows from the netlist in a fixed order."""

from __future__ import annotations

from dataclasses import dataclass, field

from patchgen.patch.netlist import Amplifier, Netlist
from patchgen.patch.reading import read
from patchgen.render.diagram_symbols import amp_half_height

# ----------------------------------------------------------------------------------------------
# Placement in index space


@dataclass
class AmpPlace:
    """Where an amplifier sits: stage, row and its input pins."""

    amp: Amplifier
    stage: int
    row: int = 0
    pins: list[int] = field(default_factory=list)  # input index for each pin, top first
    half: float = 0.62


@dataclass
class Sink:
    """One end of a wire: an amplifier pin or pot a signal feeds."""

    stage: int
    ykey: tuple          # ("row", row, offset in pitches) or ("gap", gap, slot)
    target: tuple        # ("pot", pot id) | ("amp", amp id, pin offset) | ("out",)


@dataclass
class Net:
    """One signal's wiring: its source, the pins it feeds, its tracks and lanes."""

    source: str
    stage: int
    row: int
    sinks: list[Sink] = field(default_factory=list)
    tracks: dict[int, list[tuple]] = field(default_factory=dict)   # channel -> attached ykeys
    lanes: list[tuple[int, int, tuple]] = field(default_factory=list)  # (ch_from, ch_to, ykey)


def place(net: Netlist, outputs: list[str] | None = None):
    """Stages, rows, tracks and lanes of every part of a netlist's diagram, in index space.
    ``outputs``: the amplifiers drawn as terminals on the right (default: the control output)."""
    outputs = outputs or [net.output.source]
    level = read(net).levels()
    sensors = [s.id for s in net.sensors]
    n_stages = max([level[a.id] for a in net.amplifiers], default=0) + 2  # + sensors + output
    out_stage = n_stages - 1
    row_of: dict[str, int] = {s: i for i, s in enumerate(sensors)}
    places: dict[str, AmpPlace] = {}
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
            places[a.id] = AmpPlace(a, stage, row, pins, amp_half_height(len(a.inputs)))
    last = occupant[out_stage - 1]
    out_rows: list[int] = []
    for src in outputs:
        out_row = row_of.get(src, 0)
        while last.get(out_row, src) != src or out_row in out_rows:
            out_row += 1
        out_rows.append(out_row)
    n_rows = max(list(row_of.values()) + out_rows) + 1

    def pin_offset(p: AmpPlace, j: int) -> float:
        i = p.pins.index(j)
        return (len(p.pins) - 1) / 2 - i      # +: above the centre, in pitches

    nets: dict[str, Net] = {}
    for sid in sensors:
        nets[sid] = Net(sid, 0, row_of[sid])
    for a in net.amplifiers:
        nets[a.id] = Net(a.id, places[a.id].stage, places[a.id].row)
    for a in net.amplifiers:
        p = places[a.id]
        for j, inp in enumerate(a.inputs):
            off = pin_offset(p, j)
            target = ("pot", inp.pot) if inp.pot else ("amp", a.id, off)
            nets[inp.source].sinks.append(Sink(p.stage, ("row", p.row, off), target))
    for k, (src, row) in enumerate(zip(outputs, out_rows)):
        nets[src].sinks.append(Sink(out_stage, ("row", row, 0.0), ("out", k)))

    # Tracks and lanes.
    lane_use: dict[tuple[int, int], list[tuple[int, int]]] = {}  # (gap, slot) -> channel spans
    for n in nets.values():
        out_key = ("row", n.row, 0.0)
        by_channel: dict[int, list[Sink]] = {}
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
    return level, places, nets, n_rows, out_stage, out_rows, slots


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
