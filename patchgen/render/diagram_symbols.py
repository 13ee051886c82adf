"""The wiring diagram's symbols and labels: amplifiers, pots, parts, terminals and connectors in
analog-computer notation as schemdraw elements, the names it writes, and the text metric every
label's room is computed from.

Geometry is in drawing units: schemdraw draws 0.5 inch per unit, so one unit is 36 pt. Text is
placed by its baseline (SVG's default alphabetic baseline, which every renderer agrees on) and
takes the room :func:`text_box` gives it: a conservative box from the font size and the number of
characters, wide enough for DejaVu Sans, Arial and Liberation Sans.
"""

from __future__ import annotations

import math

from patchgen.patch.netlist import Part
from patchgen.patch.parts import fmt_value
from patchgen.render.schematic import (
    Element,
    Segment,
    SegmentCircle,
    SegmentPoly,
    SegmentText,
)

PT = 1 / 36             # drawing units per point

# Font sizes in points. The smallest is 7 pt, so a diagram up to 615 pt wide prints it at 6 pt or
# more on the sheet's 186 mm (527 pt).
NAME_PT = 9.0           # terminal names
ID_PT = 7.5             # amplifier ids
SIGNAL_PT = 7.0         # what an amplifier carries, pot settings
SMALL_PT = 7.0          # weights, pot ids, details, IC, part labels
SMALLEST_PT = min(NAME_PT, ID_PT, SIGNAL_PT, SMALL_PT)

# Geometry in drawing units.
PIN_PITCH = 0.72        # vertical distance between two inputs of one amplifier
PIN_MARGIN = 0.55       # from the outer pins to the corners of the amplifier symbol
POT_R = 0.26            # smallest pot circle radius
INT_BOX = 0.42          # smallest width of the integrator's input rectangle
TRACK_PITCH = 0.16      # distance between vertical tracks in a channel
LANE_PITCH = 0.22       # distance between lanes in one gap between rows
LOOP_PITCH = 0.20       # distance between nested feedback loops
ROW_GAP = 0.24          # empty space between two rows
LEAD = 0.18             # shortest wire between two things on one line
GAP = 0.06              # clearance between a label and what it names
TERMINAL_R = 0.07       # open circle of a sensor or output terminal
FLAG = 0.30             # length of an off-unit connector's flag
PLATE = 0.13            # half the height of a capacitor plate
RESISTOR = 0.42         # length of a resistor's zigzag
WIRE_LW = 1.1
SYMBOL_LW = 1.5
FONT = "DejaVu Sans, Arial, sans-serif"

_EM_PER_CHAR = 0.62     # conservative width of a character, in font sizes
_EM_EXTRA = 0.20        # and of the whole label (short labels of wide digits and capitals)
ASCENT = 1.00           # top of a label above its baseline, in font sizes
DESCENT = 0.25          # bottom below it

_GREEK = {"theta": "θ", "phi": "φ", "alpha": "α", "omega": "ω"}


# ----------------------------------------------------------------------------------------------
# Names


def quantity_label(q: str) -> str:
    """Readable name of a state or signal, in characters every common font has.

    Parameters
    ----------
    q : str
        A netlist quantity: ``theta``, ``s_dot``, ``int_theta``, ``xhat_s``, ``z_theta_dot``,
        ``what_actuator``, ``partial u_c`` ...

    Returns
    -------
    str
        Greek letters for their names, ``d./dt`` for a derivative, ``∫`` for an integral,
        ``est.`` for an estimate (Kalman ``xhat_``, reduced observer ``what_``) and ``z(.)`` for
        a reduced-observer state: ``theta_dot`` -> ``dθ/dt``, ``int_theta`` -> ``∫θ``,
        ``xhat_s`` -> ``est. s``, ``z_theta_dot`` -> ``z(dθ/dt)``, ``partial u_c`` ->
        ``partial u_c``. No combining marks (they render badly in many fonts).
    """
    if q.startswith("partial "):
        return "partial " + quantity_label(q[len("partial "):])
    for prefix, form in (("xhat_", "est. {}"), ("what_", "est. {}"), ("z_", "z({})"), ("int_", "∫{}")):
        if q.startswith(prefix) and len(q) > len(prefix):
            return form.format(quantity_label(q[len(prefix):]))
    if q.endswith("_dot") and len(q) > len("_dot"):
        return f"d{quantity_label(q[:-len('_dot')])}/dt"
    return _GREEK.get(q, q)


def signed_label(polarity: int, quantity: str) -> str:
    """A quantity with its polarity, as the diagram and the sheet write it (``−`` for -1)."""
    return ("+" if polarity > 0 else "−") + quantity_label(quantity)


def part_value(part: Part) -> str:
    """The value of an external part as the diagram writes it: what is fitted (``6.34 kΩ``, ``1 µF``)."""
    text = fmt_value(part.fit_value, part.unit)
    return text.replace(" kohm", " kΩ").replace(" Mohm", " MΩ").replace(" ohm", " Ω").replace(" uF", " µF")


def dial_decimals(resolution: float) -> int:
    """Decimals a pot setting is written with, from the dial resolution (0.001 -> 3)."""
    text = f"{resolution:.10f}".rstrip("0")
    return max(0, len(text.split(".")[1]) if "." in text else 0)


# ----------------------------------------------------------------------------------------------
# Text metric


def text_width(text: str, size_pt: float) -> float:
    """Width a label is given, in drawing units (conservative for the diagram's fonts)."""
    return (_EM_PER_CHAR * len(text) + _EM_EXTRA) * size_pt * PT


def text_box(x: float, y: float, text: str, size_pt: float, anchor: str = "middle"
             ) -> tuple[float, float, float, float]:
    """The box (x0, y0, x1, y1) a label with its baseline at (x, y) takes (y up)."""
    w = text_width(text, size_pt)
    x0 = {"start": x, "middle": x - w / 2, "end": x - w}[anchor]
    return (x0, y - DESCENT * size_pt * PT, x0 + w, y + ASCENT * size_pt * PT)


def text_height(size_pt: float) -> float:
    """Height a one-line label is given, in drawing units."""
    return (ASCENT + DESCENT) * size_pt * PT


def line_pitch(size_pt: float) -> float:
    """Distance between the baselines of stacked lines: their height and a little air."""
    return text_height(size_pt) + 0.02


def centred_baseline(y: float, size_pt: float) -> float:
    """The baseline that centres a label's box on height y."""
    return y - (ASCENT - DESCENT) / 2 * size_pt * PT


# ----------------------------------------------------------------------------------------------
# Sizes of the symbols


def pot_radius(ids: list[str]) -> float:
    """Pot circle radius: room for the longest pot id inside the circle."""
    half_w = max((text_width(i, SMALL_PT) for i in ids), default=0.0) / 2
    half_h = text_height(SMALL_PT) / 2
    return max(POT_R, math.hypot(half_w, half_h) + 0.04)


def weight_width(weights: list[int]) -> float:
    """Room for the widest input weight written inside an amplifier."""
    return max((text_width(str(w), SMALL_PT) for w in weights), default=0.0)


def amp_shape(role: str, amp_id: str, weights: list[int], pitch: float,
              mark: str = "") -> tuple[float, float, float]:
    """(half height, input box width, total width) of an amplifier symbol.

    The triangle is made long enough that every inscription (the weights beside the inputs, the
    id, a ``mark`` under it: ``d/dt`` for a differentiator, ``SLOW`` for an integrator set by that
    cord) lies inside it with a margin, and tall enough that it need
    not be much longer than high; an integrator writes its weights in its input rectangle.
    """
    n = max(len(weights), 1)
    ww = weight_width(weights)
    box = max(INT_BOX, ww + 2 * GAP) if role == "integrator" else 0.0
    inside: list[tuple[float, float]] = []      # (right edge from the triangle's base, |y| reach)
    x = GAP
    if role != "integrator":
        inside.append((x + ww, (n - 1) * pitch / 2 + text_height(SMALL_PT) / 2))
        x += ww + GAP
    idw = text_width(amp_id, ID_PT)
    if mark:
        inside.append((x + max(idw, text_width(mark, SMALL_PT)), text_height(ID_PT) + GAP))
    else:
        inside.append((x + idw, text_height(ID_PT) / 2))
    half = max(0.62, (n - 1) * pitch / 2 + PIN_MARGIN)
    for _ in range(40):
        length = max([1.05] + [(right + GAP) / (1 - (reach + GAP) / half) for right, reach in inside])
        if length <= max(1.05, 1.25 * half):
            break
        half += 0.04
    return half, box, box + length


# ----------------------------------------------------------------------------------------------
# Elements (local coordinates: origin at the element's reference point)


class Label(Element):
    """A one-line label with its baseline at the reference point (``anchor``: start, middle, end)."""

    def __init__(self, text: str, size_pt: float, anchor: str = "middle", **kwargs):
        super().__init__(**kwargs)
        halign = {"start": "left", "middle": "center", "end": "right"}[anchor]
        self.segments.append(SegmentText((0, 0), text, fontsize=size_pt, font=FONT,
                                         align=(halign, "base")))


class AmplifierSymbol(Element):
    """Inverting amplifier in analog-computer notation, drawn from its input side at x = 0.

    ``pins`` are the input heights (relative to the centre) with their weights. An integrator has
    a rectangle on its input side holding the weights; ``mark`` is written under the id (a
    differentiator's ``d/dt``, the cord that sets an integrator's mode).
    """

    def __init__(self, amp_id: str, role: str, pins: list[tuple[float, int]], pitch: float, mark: str = "",
                 **kwargs):
        super().__init__(**kwargs)
        weights = [w for _, w in pins]
        half, box, width = amp_shape(role, amp_id, weights, pitch, mark)
        self.segments.append(SegmentPoly([(box, half), (width, 0.0), (box, -half)], lw=SYMBOL_LW,
                                         fill="white"))
        if box:
            self.segments.append(SegmentPoly([(0, half), (box, half), (box, -half), (0, -half)],
                                             lw=SYMBOL_LW, fill="white"))
        for y, w in pins:
            self.segments.append(_text((GAP, centred_baseline(y, SMALL_PT)), str(w), SMALL_PT, "left"))
        x = box + GAP + (0.0 if box else weight_width(weights) + GAP)
        cx = x + text_width(amp_id, ID_PT) / 2
        if mark:
            cx = x + max(text_width(amp_id, ID_PT), text_width(mark, SMALL_PT)) / 2
            self.segments.append(_text((cx, GAP / 2 + DESCENT * ID_PT * PT), amp_id, ID_PT, "center"))
            self.segments.append(_text((cx, -GAP / 2 - ASCENT * SMALL_PT * PT), mark, SMALL_PT, "center"))
        else:
            self.segments.append(_text((cx, centred_baseline(0.0, ID_PT)), amp_id, ID_PT, "center"))
        self.anchors["out"] = (width, 0)


class PotSymbol(Element):
    """Coefficient pot: a circle with its id; input on the left, wiper output on the right."""

    def __init__(self, pot_id: str, radius: float, **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentCircle((radius, 0), radius, lw=SYMBOL_LW))
        self.segments.append(_text((radius, centred_baseline(0.0, SMALL_PT)), pot_id, SMALL_PT, "center"))


class Capacitor(Element):
    """Two plates across a horizontal wire, centred at x = 0; the wire stops at the plates."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        g = 0.05
        self.segments.append(Segment([(-g, PLATE), (-g, -PLATE)], lw=SYMBOL_LW))
        self.segments.append(Segment([(g, PLATE), (g, -PLATE)], lw=SYMBOL_LW))


class Resistor(Element):
    """A zigzag resistor on a horizontal wire, from x = 0 to RESISTOR."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        n, a = 6, 0.09
        pts = [(0.0, 0.0)] + [((i + 0.5) * RESISTOR / n, a if i % 2 == 0 else -a) for i in range(n)]
        self.segments.append(Segment(pts + [(RESISTOR, 0.0)], lw=SYMBOL_LW))


class Terminal(Element):
    """A signal entering or leaving the machine (a sensor, the control voltage): an open circle."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentCircle((0, 0), TERMINAL_R, lw=SYMBOL_LW, fill="white", zorder=4))


class Connector(Element):
    """An off-unit connector: a flag pointing the way the signal goes, its wire end at x = 0.

    ``side`` left: the signal comes in from another unit (flag from -FLAG to 0); right: it leaves
    for another unit (flag from 0 to FLAG).
    """

    def __init__(self, side: str, **kwargs):
        super().__init__(**kwargs)
        h, t = 0.11, 0.10
        x0 = -FLAG if side == "left" else 0.0
        pts = [(x0, h), (x0 + FLAG - t, h), (x0 + FLAG, 0.0), (x0 + FLAG - t, -h), (x0, -h)]
        self.segments.append(SegmentPoly(pts, lw=SYMBOL_LW, fill="white", zorder=4))


class Dot(Element):
    """A junction dot where wires join."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentCircle((0, 0), 0.055, fill=True, lw=0.5, zorder=3))


def _text(at: tuple[float, float], text: str, size_pt: float, halign: str) -> SegmentText:
    return SegmentText(at, text, fontsize=size_pt, font=FONT, align=(halign, "base"))
