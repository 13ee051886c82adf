"""The wiring diagram page by page: one diagram for a one-unit patch; for a patch on slaved units
one per unit, its amplifiers and pots drawn at full size, with a terminal for every signal that
comes from or goes to another unit (named by its amplifier and what it carries), so each stays
legible at print size and the lines between units read off the terminals."""

from __future__ import annotations

from patchgen.patch.netlist import Netlist, SensorInput
from patchgen.render.diagram import wiring_svg
from patchgen.render.diagram_symbols import quantity_label, signed_label


def unit_of(element_id: str) -> int:
    """The unit of a slaved id (U2.A3 -> 2); 1 for a one-unit id."""
    return int(element_id.split(".")[0][1:]) if element_id.startswith("U") and "." in element_id else 1


def diagram_pages(net: Netlist) -> list[tuple[str, str]]:
    """The diagrams the sheet prints, as (caption, SVG).

    Parameters
    ----------
    net : Netlist
        The patch.

    Returns
    -------
    list of (str, str)
        One (an empty caption) for a one-unit patch; else one per unit, captioned with its links.
    """
    if net.units == 1:
        return [("", wiring_svg(net))]
    amps = {a.id: a for a in net.amplifiers}
    pages = []
    for u in range(1, net.units + 1):
        mine = [a for a in net.amplifiers if unit_of(a.id) == u]
        if not mine:
            continue
        ids = {a.id for a in mine}
        incoming = sorted({i.source for a in mine for i in a.inputs if i.source in amps and i.source not in ids})
        consumers = {a.id: sorted(b.id for b in net.amplifiers if b.id not in ids
                                  and any(i.source == a.id for i in b.inputs)) for a in mine}
        outgoing = [a.id for a in mine if consumers[a.id]]
        used = {i.source for a in mine for i in a.inputs}
        sensors = [s for s in net.sensors if s.id in used]
        terminals = {}
        for src in incoming:
            c = amps[src].carries
            sensors.append(SensorInput(id=src, label=f"from unit {unit_of(src)}", quantity=c.quantity,
                                       unit=c.unit or "V", volts_per_unit=c.volts_per_unit))
            terminals[src] = (src, [signed_label(c.polarity, c.quantity), f"from unit {unit_of(src)}"])
        outputs = []
        if net.output.source in ids:
            outputs.append((net.output.source, "u_c", ["to the servo amplifier", f"{net.output.K_U_N_per_V:g} N/V"]))
        for a in outgoing:
            c = amps[a].carries
            outputs.append((a, a, [signed_label(c.polarity, c.quantity), "to " + ", ".join(consumers[a])]))
        sub = net.model_copy(update={
            "sensors": sensors, "amplifiers": mine, "pots": [p for p in net.pots if p.amplifier in ids],
            "parts": [p for p in net.parts if p.amplifier in ids],
            "output": net.output.model_copy(update={"source": outputs[0][0] if outputs else mine[-1].id})})
        links = [f"{src} ({quantity_label(amps[src].carries.quantity)}) from unit {unit_of(src)}" for src in incoming]
        links += [f"{a} to {', '.join(consumers[a])}" for a in outgoing]
        caption = f"Unit {u} of {net.units}" + (": " + "; ".join(links) if links else "")
        pages.append((caption, wiring_svg(sub, outputs or None, terminals)))
    return pages
