"""The geometry of a wiring diagram read back from its SVG text, independently of how it was drawn:
text boxes from font size and character count, element outlines from the SVG's polygons, circles
and paths, and the checks the diagram tests make with them (overlaps, wiring, legibility).

Coordinates are the SVG's own (y down, points). A label's box is conservative: 0.62 em per
character plus 0.2 em, from 1.0 em above its baseline to 0.25 em below, which covers the glyphs
of DejaVu Sans, Arial and Liberation Sans for the diagram's labels.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

NS = "{http://www.w3.org/2000/svg}"
EM_PER_CHAR, EM_EXTRA, ASCENT, DESCENT = 0.62, 0.20, 1.00, 0.25
SHEET_WIDTH_PT = 186 / 25.4 * 72     # the widest the sheet prints a diagram


@dataclass(frozen=True)
class Text:
    text: str
    size: float
    box: tuple[float, float, float, float]     # x0, y0, x1, y1

    @property
    def centre(self) -> tuple[float, float]:
        return ((self.box[0] + self.box[2]) / 2, (self.box[1] + self.box[3]) / 2)


@dataclass(frozen=True)
class Shape:
    kind: str                                  # polygon, circle, path
    points: tuple[tuple[float, float], ...]    # polygon vertices or path points; circle: centre
    stroke: float
    r: float = 0.0
    filled: bool = False

    def segments(self):
        pts = self.points
        pairs = list(zip(pts, pts[1:]))
        return pairs + [(pts[-1], pts[0])] if self.kind == "polygon" else pairs


@dataclass(frozen=True)
class Diagram:
    width: float
    height: float
    view: tuple[float, float, float, float]    # x, y, w, h
    texts: list[Text]
    shapes: list[Shape]

    def strings(self) -> list[str]:
        return [t.text for t in self.texts]

    def inscriptions(self, kind: str, vertices: int | None = None) -> list[tuple[Text, Shape]]:
        """Texts lying inside a closed shape of this kind (and vertex count)."""
        out = []
        for t in self.texts:
            for s in self.shapes:
                if s.kind == kind and (vertices is None or len(s.points) == vertices) and _inside(t.box, s, 0.0):
                    out.append((t, s))
        return out


def parse(svg: str) -> Diagram:
    """Texts and shapes of an SVG document as patchgen writes it (schemdraw's SVG backend)."""
    root = ET.fromstring(svg)
    view = tuple(float(v) for v in root.get("viewBox").split())
    texts, shapes = [], []
    for el in root.iter():
        tag = el.tag.replace(NS, "")
        style = _style(el.get("style", ""))
        stroke = float(style.get("stroke-width", 1.0))
        if tag == "text":
            assert el.get("dominant-baseline", "alphabetic") == "alphabetic", "labels sit on their baseline"
            assert el.get("transform") is None
            spans = list(el)
            assert len(spans) == 1, "one line per label"
            size = float(el.get("font-size"))
            content = "".join(el.itertext())
            base = float(el.get("y")) + float(spans[0].get("dy", 0))
            x = float(spans[0].get("x", el.get("x")))
            w = (EM_PER_CHAR * len(content) + EM_EXTRA) * size
            x0 = {"start": x, "middle": x - w / 2, "end": x - w}[el.get("text-anchor", "start")]
            texts.append(Text(content, size, (x0, base - ASCENT * size, x0 + w, base + DESCENT * size)))
        elif tag == "polygon":
            nums = [float(v) for v in re.split(r"[ ,]+", el.get("points").strip())]
            shapes.append(Shape("polygon", tuple(zip(nums[::2], nums[1::2])), stroke,
                                filled=style.get("fill", "none") != "none"))
        elif tag == "circle":
            shapes.append(Shape("circle", ((float(el.get("cx")), float(el.get("cy"))),), stroke,
                                float(el.get("r")), filled=style.get("fill", "none") == "black"))
        elif tag == "path":
            d = el.get("d")
            assert re.fullmatch(r"M [-\d.e,]+( L [-\d.e,]+)*\s*", d), f"a polyline: {d}"
            pts = tuple(tuple(float(v) for v in p.split(",")) for p in re.findall(r"[-\d.e]+,[-\d.e]+", d))
            shapes.append(Shape("path", pts, stroke))
        elif tag not in ("svg", "tspan", "g", "defs"):
            raise AssertionError(f"unexpected SVG element <{tag}>")
    return Diagram(float(root.get("width").removesuffix("pt")), float(root.get("height").removesuffix("pt")),
                   view, texts, shapes)


def overlaps(d: Diagram) -> list[str]:
    """Every label that overlaps another label or an element, or leaves the drawing.

    A label may lie wholly inside a closed shape (a pot's id in its circle, a weight in its
    amplifier) but not cross its outline; it may not touch a wire or another label at all.
    """
    found = []
    for i, t in enumerate(d.texts):
        for u in d.texts[i + 1:]:
            if _boxes_meet(t.box, u.box):
                found.append(f"label {t.text!r} overlaps label {u.text!r}")
        for s in d.shapes:
            if _meets(t.box, s) and not (s.kind != "path" and _inside(t.box, s, s.stroke / 2)):
                found.append(f"label {t.text!r} at {_fmt(t.box)} overlaps a {s.kind} at {_fmt(_bounds(s))}")
        x, y, w, h = d.view
        if not (x <= t.box[0] and t.box[2] <= x + w and y <= t.box[1] and t.box[3] <= y + h):
            found.append(f"label {t.text!r} leaves the drawing")
    return found


def printed_min_font(d: Diagram, max_height_pt: float | None = None) -> float:
    """The smallest text size, in points, when the diagram is printed at most 186 mm wide (and, as
    the sheet inlines it, at most ``max_height_pt`` tall: the browser shrinks it to both)."""
    scale = min(1.0, SHEET_WIDTH_PT / d.width)
    if max_height_pt is not None:
        scale = min(scale, max_height_pt / d.height)
    return min(t.size for t in d.texts) * scale


def connected(d: Diagram, a: tuple[float, float], b: tuple[float, float], region=None) -> bool:
    """Whether wires (paths, or polygon and circle outlines not) join points a and b; with
    ``region`` (x0, y0, x1, y1) only through wires that lie wholly inside it."""
    segs = [seg for s in d.shapes if s.kind == "path" for seg in s.segments()
            if region is None or all(_in_box(p, region) for p in seg)]
    parent = list(range(len(segs)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, s in enumerate(segs):
        for j, t in enumerate(segs[:i]):
            if any(_on(p, t) for p in s) or any(_on(p, s) for p in t):
                parent[find(i)] = find(j)
    ends_a = {find(i) for i, s in enumerate(segs) if _on(a, s)}
    ends_b = {find(i) for i, s in enumerate(segs) if _on(b, s)}
    return bool(ends_a & ends_b)


# ----------------------------------------------------------------------------------------------


def _style(text: str) -> dict[str, str]:
    return dict(kv.split(":", 1) for kv in text.split(";") if ":" in kv)


def _fmt(box) -> str:
    return "(" + ", ".join(f"{v:.1f}" for v in box) + ")"


def _bounds(s: Shape):
    if s.kind == "circle":
        (cx, cy), r = s.points[0], s.r
        return (cx - r, cy - r, cx + r, cy + r)
    xs, ys = [p[0] for p in s.points], [p[1] for p in s.points]
    return (min(xs), min(ys), max(xs), max(ys))


def _boxes_meet(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _grow(box, m):
    return (box[0] - m, box[1] - m, box[2] + m, box[3] + m)


def _in_box(p, box, eps=1e-6) -> bool:
    return box[0] - eps <= p[0] <= box[2] + eps and box[1] - eps <= p[1] <= box[3] + eps


def _segment_meets_box(p, q, box) -> bool:
    """Liang-Barsky clipping: does segment pq touch the box?"""
    t0, t1 = 0.0, 1.0
    dx, dy = q[0] - p[0], q[1] - p[1]
    for pk, qk in ((-dx, p[0] - box[0]), (dx, box[2] - p[0]), (-dy, p[1] - box[1]), (dy, box[3] - p[1])):
        if pk == 0:
            if qk < 0:
                return False
        else:
            t = qk / pk
            if pk < 0:
                t0 = max(t0, t)
            else:
                t1 = min(t1, t)
            if t0 > t1:
                return False
    return True


def _point_in_polygon(p, pts) -> bool:
    inside = False
    for (x1, y1), (x2, y2) in zip(pts, pts[1:] + pts[:1]):
        if (y1 > p[1]) != (y2 > p[1]) and p[0] < x1 + (p[1] - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def _corners(box):
    return [(box[0], box[1]), (box[2], box[1]), (box[2], box[3]), (box[0], box[3])]


def _meets(box, s: Shape) -> bool:
    """Does the label's box touch the shape (its stroke, or for a filled shape its inside)?"""
    grown = _grow(box, s.stroke / 2)
    if s.kind == "circle":
        (cx, cy), r = s.points[0], s.r
        nx, ny = min(max(cx, grown[0]), grown[2]), min(max(cy, grown[1]), grown[3])
        if math.hypot(nx - cx, ny - cy) > r:
            return False
        return s.filled or any(math.hypot(x - cx, y - cy) >= r for x, y in _corners(grown))
    if any(_segment_meets_box(p, q, grown) for p, q in s.segments()):
        return True
    return s.kind == "polygon" and s.filled and all(_point_in_polygon(c, list(s.points)) for c in _corners(box))


def _inside(box, s: Shape, margin: float) -> bool:
    """Is the box wholly inside the closed shape, clear of its outline by ``margin``?"""
    grown = _grow(box, margin)
    if s.kind == "circle":
        (cx, cy), r = s.points[0], s.r
        return all(math.hypot(x - cx, y - cy) < r for x, y in _corners(grown))
    if s.kind != "polygon":
        return False
    return (all(_point_in_polygon(c, list(s.points)) for c in _corners(grown))
            and not any(_segment_meets_box(p, q, grown) for p, q in s.segments()))


def _on(p, seg, eps=0.01) -> bool:
    (x1, y1), (x2, y2) = seg
    if not (min(x1, x2) - eps <= p[0] <= max(x1, x2) + eps and min(y1, y2) - eps <= p[1] <= max(y1, y2) + eps):
        return False
    return abs((x2 - x1) * (p[1] - y1) - (y2 - y1) * (p[0] - x1)) <= eps * max(1.0, math.hypot(x2 - x1, y2 - y1))
