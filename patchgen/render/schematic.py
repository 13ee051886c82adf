"""schemdraw, loaded without its matplotlib backend.

schemdraw imports matplotlib.pyplot when it can (half a second), only to offer a matplotlib
canvas; the wiring diagram is drawn on its SVG canvas alone. While schemdraw loads, its matplotlib
backend is marked missing (a None in sys.modules), which schemdraw handles by using SVG.
If schemdraw was loaded before, it is used as it is.
"""

from __future__ import annotations

import sys

_MPL = "schemdraw.backends.mpl"

if "schemdraw" not in sys.modules and _MPL not in sys.modules:
    sys.modules[_MPL] = None  # type: ignore[assignment]
    try:
        import schemdraw
    finally:
        del sys.modules[_MPL]

import schemdraw  # noqa: E402
from schemdraw.backends import svg as svg_backend  # noqa: E402
from schemdraw.elements import Element, Line  # noqa: E402
from schemdraw.segments import Segment, SegmentCircle, SegmentPoly, SegmentText  # noqa: E402
from schemdraw.types import BBox  # noqa: E402

__all__ = ["BBox", "Element", "Line", "Segment", "SegmentCircle", "SegmentPoly", "SegmentText", "schemdraw",
           "svg_backend"]
