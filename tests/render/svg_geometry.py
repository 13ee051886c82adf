"""Geometry of a wiring-diagram SVG for overlap tests: each label's box (from its anchor, font size
and characters), each wire segment, each symbol's polygon or circle."""

from __future__ import annotations

import re
import unicodedata
from dataclasses import dataclass

CHAR_W = 0.52  # of the font size: a typical DejaVu Sans advance (narrow glyphs make a box generous)
ASCENT, DESCENT = 0.72, 0.18  # of the font size, around the baseline
EPS = 0.4  # pt: boxes that only touch do not overlap


@dataclass(frozen=True)
class Box:
    text: str
    x0: float
    y0: float
    x1: float
    y1: float

    def overlaps(self, o: Box) -> bool:
        return self.x0 < o.x1 - EPS and o.x0 < self.x1 - EPS and self.y0 < o.y1 - EPS and o.y0 < self.y1 - EPS

    def crossed_by(self, seg) -> bool:
        (ax, ay), (bx, by) = seg
        if ay == by:  # horizontal
            return self.y0 + EPS < ay < self.y1 - EPS and min(ax, bx) < self.x1 - EPS and max(ax, bx) > self.x0 + EPS
        if ax == bx:
            return self.x0 + EPS < ax < self.x1 - EPS and min(ay, by) < self.y1 - EPS and max(ay, by) > self.y0 + EPS
        return False

    def inside(self, poly) -> bool:
        cx, cy = (self.x0 + self.x1) / 2, (self.y0 + self.y1) / 2
        return _point_in(cx, cy, poly)


def _visible(text: str) -> int:
    """Characters that take room (combining marks do not)."""
    return sum(1 for ch in text if not unicodedata.combining(ch))


def labels(svg: str) -> list[Box]:
    out = []
    for m in re.finditer(r"<text([^>]*)>(.*?)</text>", svg, re.S):
        attrs, body = m.group(1), m.group(2)
        a = dict(re.findall(r'([\w-]+)="([^"]*)"', attrs))
        fs = float(a["font-size"])
        x, y = float(a["x"]), float(a["y"])
        anchor = a.get("text-anchor", "start")
        for tm in re.finditer(r"<tspan([^>]*)>(.*?)</tspan>", body, re.S):
            ta = dict(re.findall(r'([\w-]+)="([^"]*)"', tm.group(1)))
            y += float(ta.get("dy", 0))
            text = re.sub(r"<[^>]+>", "", tm.group(2))
            text = text.replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&")
            w = _visible(text) * CHAR_W * fs
            x0 = x - (w if anchor == "end" else w / 2 if anchor == "middle" else 0)
            base = a.get("dominant-baseline", "alphabetic")
            if base == "ideographic":  # y is the bottom of the text's box
                top, bottom = y - (ASCENT + DESCENT) * fs, y
            elif base == "hanging":  # y is its top
                top, bottom = y, y + (ASCENT + DESCENT) * fs
            elif base in ("central", "middle"):
                top, bottom = y - (ASCENT + DESCENT) * fs / 2, y + (ASCENT + DESCENT) * fs / 2
            else:
                top, bottom = y - ASCENT * fs, y + DESCENT * fs
            out.append(Box(text, x0, top, x0 + w, bottom))
    return out


def wires(svg: str) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    segs = []
    for m in re.finditer(r'<path d="([^"]*)"', svg):
        pts = [tuple(map(float, p.split(","))) for p in re.findall(r"[-\d.e]+,[-\d.e]+", m.group(1))]
        segs += list(zip(pts, pts[1:]))
    return segs


def polygons(svg: str) -> list[list[tuple[float, float]]]:
    out = []
    for m in re.finditer(r'<polygon points="([^"]*)"([^>]*)>', svg):
        if "fill:white" not in m.group(2) or "stroke-width:0.1" in m.group(2):
            continue  # a capacitor's white mask, not a symbol
        out.append([tuple(map(float, p.split(","))) for p in m.group(1).split()])
    for m in re.finditer(r'<circle cx="([^"]*)" cy="([^"]*)" r="([^"]*)"', svg):
        cx, cy, r = map(float, m.groups())
        if r > 3:  # a pot, not a junction dot or a terminal
            out.append([(cx - r, cy - r), (cx + r, cy - r), (cx + r, cy + r), (cx - r, cy + r)])
    return out


def _point_in(x, y, poly) -> bool:
    inside = False
    for (x1, y1), (x2, y2) in zip(poly, poly[1:] + poly[:1]):
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def overlaps(svg: str) -> list[str]:
    """Every label that overlaps another label, a symbol that is not its own, or a wire."""
    boxes, segs, polys = labels(svg), wires(svg), polygons(svg)
    found = []
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            if a.overlaps(b):
                found.append(f"label {a.text!r} overlaps label {b.text!r}")
        own = [p for p in polys if a.inside(p)]
        for p in polys:
            if p in own:
                continue
            xs, ys = [q[0] for q in p], [q[1] for q in p]
            if a.overlaps(Box("", min(xs), min(ys), max(xs), max(ys))):
                found.append(f"label {a.text!r} overlaps a symbol at ({min(xs):.0f}, {min(ys):.0f})")
        if not own:
            for s in segs:
                if a.crossed_by(s):
                    found.append(f"label {a.text!r} is crossed by a wire at {s[0]}")
                    break
    return found
