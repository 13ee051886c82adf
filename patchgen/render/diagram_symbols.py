"""The wiring diagram's symbols and geometry: amplifiers, pots, capacitors, terminals and labels
in analog-computer notation, as schemdraw elements, with the sizes the layout works from."""

from __future__ import annotations

from patchgen.patch.netlist import Amplifier, Netlist
from patchgen.render.schematic import (
    Element,
    Segment,
    SegmentCircle,
    SegmentPoly,
    SegmentText,
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
    """Readable name of a state or signal: theta_dot -> θ̇, int_theta -> ∫θ, xhat_s -> ŝ,
    z_theta_dot -> z(θ̇), what_theta_dot -> ŵ(θ̇), theta_x1.48 -> 1.48·θ, partial u_c -> partial u_c.
    A combining dot or hat goes on a one-letter symbol only (on a longer name it would land on its
    last letter: theta_dot is θ̇, never thetȧ)."""
    if " " in q:  # "partial u_c": each word on its own
        return " ".join(quantity_label(w) for w in q.split(" "))
    for prefix, name in (("z_", "z"), ("what_", "ŵ")):
        if q.startswith(prefix):
            return f"{name}({quantity_label(q[len(prefix):])})"
    stage = q.rsplit("_x", 1)
    if len(stage) == 2 and stage[1].replace(".", "", 1).isdigit():
        return f"{stage[1]}·{quantity_label(stage[0])}"
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
    if len(base) > 1 and (dot or hat):  # a mark would sit on the last letter: write it out
        name = f"d{base}/dt" if dot else base
        return f"{integral}{'est. ' if hat else ''}{name}"
    return f"{integral}{base}{hat}{dot}"


def signed_label(polarity: int, quantity: str) -> str:
    """A quantity with its polarity, as the diagram writes it (a leading minus for -1)."""
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
        cx = x0 + label_offset(pins) + label_width(amp_id) / 2
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
        self.segments.append(SegmentText((sign * 0.15, 0.06), name, fontsize=10, font=FONT,
                                         align=(align, "bottom")))
        for i, line in enumerate(details):
            self.segments.append(SegmentText((sign * 0.15, -0.08 - i * 0.22), line, fontsize=6.5,
                                             font=FONT, align=(align, "top")))


class Text(Element):
    """A text label in the diagram's font."""

    def __init__(self, text: str, size: float, align: tuple[str, str], **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentText((0, 0), text, fontsize=size, font=FONT, align=align))


def amp_half_height(n_inputs: int) -> float:
    """Half the height of an amplifier symbol with this many inputs."""
    return max(0.62, (n_inputs - 1) * PIN_PITCH / 2 + 0.36)


def label_width(amp_id: str) -> float:
    """Width of an amplifier's id label in drawing units."""
    return len(amp_id) * 0.58 * 8.5 / 36


def pot_radius(net: Netlist) -> float:
    """Pot circle radius: the default, or more for long ids (two-unit patches)."""
    longest = max((len(p.id) for p in net.pots), default=2)
    return max(POT_R, longest * 0.58 * 7 / 36 / 2 + 0.07)


def pin_weights(a: Amplifier) -> list[tuple[float, int]]:
    """Each input pin's offset and weight, top to bottom."""
    return [(0.0, inp.weight) for inp in a.inputs]


def label_offset(pins: list[tuple[float, int]]) -> float:
    """Where the amplifier's id starts: right of the widest input weight."""
    widest = max((len(str(w)) for _, w in pins), default=1)
    return 0.16 + widest * 0.58 * 7 / 36


def amp_width(role: str, half: float, amp_id: str, pins: list[tuple[float, int]]) -> float:
    """Width of an amplifier symbol: its triangle plus room for the weights and label."""
    room = 0.4 if role in ("summer", "inverter") else 0.65   # two-line label needs more height
    body = max(1.05, 1.25 * half, label_offset(pins) + label_width(amp_id) + room)
    return body + (INT_BOX if role in ("integrator", "lag") else 0.0)


def text_width(text: str, size_pt: float) -> float:
    """Generous width of a label in drawing units (36 pt per unit)."""
    return len(text) * 0.56 * size_pt / 36


def dial_decimals(resolution: float) -> int:
    """Decimals a pot setting is written with, from the dial resolution (0.001 -> 3)."""
    text = f"{resolution:.10f}".rstrip("0")
    return max(0, len(text.split(".")[1]) if "." in text else 0)


class Dot(Element):
    """A junction dot where wires join."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.segments.append(SegmentCircle((0, 0), 0.055, fill=True, lw=0.5, zorder=3))
