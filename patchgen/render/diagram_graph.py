"""What a wiring diagram shows, read from a netlist: sources on the left (sensors, or signals from
another unit), amplifiers in columns with their pots and external parts, and terminals on the
right (the control voltage, or signals for another unit).

A patch on one machine is one diagram. A patch on slaved units is also drawn one unit at a time:
that unit's amplifiers and pots, written as on its own panel (A1, P3 for U1.A1, U1.P3), with a
connector (a flag named for the jack at its other end, in full: "from U2.A6") for every signal
that crosses to or from another unit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from patchgen.patch.netlist import Amplifier, Netlist, Part, cords
from patchgen.patch.reading import read, stage_levels
from patchgen.render.diagram_symbols import dial_decimals, part_value, quantity_label, signed_label


@dataclass(frozen=True)
class PartMark:
    """An external part as drawn: its id and value."""

    id: str
    value: str


@dataclass(frozen=True)
class Feed:
    """One input of a block: where it comes from, through which pot and parts, with which weight."""

    source: str                           # a Source's or a Block's id
    weight: int = 1
    pot: str | None = None
    setting: str = ""                     # the pot's dial setting, as written
    parts: tuple[PartMark, ...] = ()      # in series on the input, source side first


@dataclass(frozen=True)
class Block:
    """An amplifier, or a terminal on the right (role ``out``: the control voltage; ``connector``:
    a signal for another unit)."""

    id: str
    role: str
    feeds: tuple[Feed, ...]
    label: str = ""                       # what an amplifier carries, with its sign
    ic: str = ""                          # an integrator's initial condition
    feedback: PartMark | None = None      # a lag's capacitor across its feedback
    name: str = ""                        # an amplifier's id or a terminal's name, as written
    mark: str = ""                        # written under the id: d/dt, or the cord that sets a mode (SLOW)
    details: tuple[str, ...] = ()

    @property
    def is_amplifier(self) -> bool:
        """True for an amplifier, False for a terminal on the right."""
        return self.role not in ("out", "connector")


@dataclass(frozen=True)
class Source:
    """A signal entering the diagram on the left: a sensor or a connector from another unit."""

    id: str
    kind: str                             # "sensor" or "connector"
    name: str
    details: tuple[str, ...]


@dataclass(frozen=True)
class Graph:
    """Everything one diagram draws; ``level`` is each amplifier's column (1, 2, ...)."""

    sources: tuple[Source, ...]
    blocks: tuple[Block, ...]
    outputs: tuple[Block, ...]
    level: dict[str, int]


def unit_of(element_id: str) -> str:
    """The unit an amplifier or pot id names (``U2.P3`` -> ``U2``), or "" on one machine."""
    return element_id.split(".")[0] if "." in element_id else ""


def units(net: Netlist) -> list[str]:
    """The units a patch uses, in order (``[""]`` for a patch on one machine)."""
    found = {unit_of(e) for e in [a.id for a in net.amplifiers] + [p.id for p in net.pots]}
    return sorted(found, key=lambda u: (len(u), u)) or [""]


def whole_graph(net: Netlist) -> Graph:
    """The whole patch: every sensor, amplifier and pot, and the control voltage."""
    level = read(net).levels()
    blocks = tuple(_amplifier(net, a, lambda src: src) for a in net.amplifiers)
    return Graph(tuple(_sensor(net, s.id) for s in net.sensors), blocks, (_control_output(net),),
                 {a.id: level[a.id] for a in net.amplifiers})


def unit_graph(net: Netlist, unit: str) -> Graph:
    """One unit of a patch on slaved units: its amplifiers and pots, connectors for the rest."""
    return page_graph(net, unit, [a.id for a in net.amplifiers if unit_of(a.id) == unit], loose_pots(net, unit))


def loose_pots(net: Netlist, unit: str) -> list[str]:
    """A unit's pots that feed another unit's amplifiers (drawn on their own, with a flag)."""
    return [p.id for p in net.pots if unit_of(p.id) == unit and unit_of(p.amplifier) != unit]


def page_graph(net: Netlist, unit: str, shown: list[str], loose: list[str]) -> Graph:
    """Part of one unit on a page of its own: the amplifiers ``shown`` with the unit's pots that feed
    them, and the ``loose`` pots (of this unit, feeding amplifiers drawn elsewhere), each ending in
    a flag; a flag for every cord to or from an element drawn elsewhere, named for the jack at its
    other end in full ("from U1.A3", "to U2.P1", "to U1.A7 x10a") with its number in the wire list.

    Parameters
    ----------
    net : Netlist
        The patch.
    unit : str
        The unit ("" on one machine); its elements are named as on its panel (A1 for U1.A1).
    shown : list of str
        The amplifiers drawn, all on ``unit``.
    loose : list of str
        Pots of ``unit`` drawn without their amplifier.
    """
    pots = {p.id: p for p in net.pots}
    sensors = {s.id for s in net.sensors}
    here_amps = set(shown)
    here_pots = {p.id for p in net.pots if unit_of(p.id) == unit and p.amplifier in here_amps} | set(loose)
    numbered = list(enumerate(cords(net), 1))
    incoming: dict[str, Source] = {}

    def numbers(match) -> tuple[str, ...]:
        found = [n for n, c in numbered if match(c)]
        return (("cord " if len(found) == 1 else "cords ") + ", ".join(map(str, found)),) if found else ()

    def local(src: str) -> str:
        """The id a source has on this page (a connector for an amplifier drawn elsewhere)."""
        if src in sensors or src in here_amps:
            return src
        return _incoming(incoming, src, f"from {src}", (_signal(net, src), *numbers(
            lambda c: c.source == src and (c.target in here_amps or c.target in here_pots))))

    def shown_name(element_id: str) -> str:
        """This unit's amplifiers and pots as on its panel (A1 for U1.A1)."""
        return element_id.split(".", 1)[1] if unit_of(element_id) == unit and unit else element_id

    blocks: list[Block] = []
    for a in net.amplifiers:
        if a.id not in here_amps:
            continue
        block = _amplifier(net, a, local, lambda inp: inp.pot in here_pots if inp.pot else True)
        feeds = []
        for inp, feed in zip(a.inputs, block.feeds):
            if inp.pot and inp.pot not in here_pots:
                p = pots[inp.pot]
                src = _incoming(incoming, inp.pot, f"from {inp.pot}",
                                (f"{_signal(net, p.source)} × {feed.setting}",
                                 *numbers(lambda c, pot=inp.pot, a=a.id: c.source == pot and c.target == a)))
                feed = Feed(src, feed.weight, parts=feed.parts)
            elif inp.pot:
                feed = replace(feed, pot=shown_name(inp.pot))
            feeds.append(feed)
        blocks.append(replace(block, feeds=tuple(feeds), name=shown_name(a.id)))

    outputs: list[Block] = []
    for pid in loose:       # a pot of this unit feeding an amplifier drawn elsewhere
        p = pots[pid]
        feed = Feed(local(p.source), pot=shown_name(p.id), setting=_setting(net, p.id))
        outputs.append(_connector(f"to {p.amplifier} {p.jack}", (
            f"{_signal(net, p.source)} × {feed.setting}",
            *numbers(lambda c, p=p: c.source == p.id and c.target == p.amplifier and c.jack == p.jack)), feed))
    for a in net.amplifiers:  # this page's amplifiers feeding elements drawn elsewhere
        if a.id not in here_amps:
            continue
        for p in net.pots:
            if p.source == a.id and p.id not in here_pots:
                outputs.append(_connector(f"to {p.id}", (_signal(net, a.id), *numbers(
                    lambda c, p=p, a=a.id: c.source == a and c.target == p.id)), Feed(a.id)))
        for b in net.amplifiers:
            for inp in b.inputs:
                if inp.source == a.id and inp.pot is None and b.id not in here_amps:
                    outputs.append(_connector(f"to {b.id} {inp.jack}", (_signal(net, a.id), *numbers(
                        lambda c, b=b.id, j=inp.jack, a=a.id: c.source == a and c.target == b and c.jack == j)),
                        Feed(a.id)))
    if net.output.source in here_amps:
        outputs.append(_control_output(net))

    used = [f.source for b in blocks + outputs for f in b.feeds]
    sources = [_sensor(net, s.id) for s in net.sensors if s.id in used]
    sources += [incoming[k] for k in incoming if k in used]
    level = stage_levels([s.id for s in sources], [(b.id, b.role, [f.source for f in b.feeds]) for b in blocks])
    return Graph(tuple(sources), tuple(blocks), tuple(outputs), {b.id: level[b.id] for b in blocks})


# ----------------------------------------------------------------------------------------------


def _setting(net: Netlist, pot_id: str) -> str:
    return f"{net.pot(pot_id).setting:.{dial_decimals(net.pot_resolution)}f}"


def _signal(net: Netlist, src: str) -> str:
    """What a source carries, as written beside a connector."""
    for s in net.sensors:
        if s.id == src:
            return quantity_label(s.quantity)
    a = net.amp(src)
    return signed_label(a.carries.polarity, a.carries.quantity)


def _sensor(net: Netlist, sid: str) -> Source:
    s = next(s for s in net.sensors if s.id == sid)
    unit = f"({s.unit})" if ("/" in s.unit or " " in s.unit) else s.unit
    return Source(s.id, "sensor", quantity_label(s.quantity), (*_wrap(s.label), f"{s.volts_per_unit:g} V/{unit}"))


def _wrap(text: str, width: int = 14) -> list[str]:
    """A label longer than ``width`` characters in two lines as even as its spaces allow."""
    words = text.split(" ")
    if len(text) <= width or len(words) == 1:
        return [text]
    splits = [(" ".join(words[:i]), " ".join(words[i:])) for i in range(1, len(words))]
    return list(min(splits, key=lambda ab: (max(len(ab[0]), len(ab[1])), len(ab[0]))))


def _incoming(incoming: dict[str, Source], key: str, name: str, details: tuple[str, ...]) -> str:
    sid = f"in:{key}"
    incoming.setdefault(sid, Source(sid, "connector", name, details))
    return sid


def _connector(name: str, details: tuple[str, ...], feed: Feed) -> Block:
    return Block(f"out:{name}", "connector", (feed,), name=name, details=details)


def _control_output(net: Netlist) -> Block:
    return Block("out:u_c", "out", (Feed(net.output.source),), name=quantity_label(net.output.quantity),
                 details=("to servo", f"{net.output.K_U_N_per_V:g} N/V"))


def _part_mark(part: Part) -> PartMark:
    return PartMark(part.id, part_value(part))


def _amplifier(net: Netlist, a: Amplifier, local, drawn=lambda inp: True) -> Block:
    """An amplifier as drawn: its feeds with pots and input parts, IC, feedback capacitor; the
    source of a feed that is not ``drawn`` (its pot is elsewhere) is left as it is, not looked up."""
    parts = [p for p in net.parts if p.amplifier == a.id]
    feeds = []
    for inp in a.inputs:
        marks = tuple(_part_mark(p) for p in parts if p.jack == inp.jack)
        setting = _setting(net, inp.pot) if inp.pot else ""
        feeds.append(Feed(local(inp.source) if drawn(inp) else inp.source, inp.weight, inp.pot, setting, marks))
    feedback = None
    if a.role == "lag":
        across = [p for p in parts if p.jack is None]
        feedback = (_part_mark(across[0]) if across
                    else PartMark("C", f"τ {a.tau_s:.3g} s" if a.tau_s else "τ"))
    ic = ("IC" if a.ic_V is None else f"IC {a.ic_V:g} V") if a.role == "integrator" else ""
    mark = "d/dt" if a.role == "differentiator" else (a.mode.jumper if a.mode is not None and a.mode.jumper else "")
    return Block(a.id, a.role, tuple(feeds), signed_label(a.carries.polarity, a.carries.quantity),
                 ic, feedback, name=a.id, mark=mark)
