"""Tables for a terminal as narrow as 80 columns, piped or not: one compact style, text that
wraps, numbers that never do and are never cut, and no negative zeros.

A table made here has two kinds of column: ``text`` (left, wrapped at spaces, a word too long
for its column folded rather than cut) and ``number`` (right, never wrapped: each view keeps its
numbers short enough that the table fits 80 columns; were one ever squeezed, rich's ellipsis
would show it). ``show`` prints a table's title at the console's width, not the table's.
"""

from __future__ import annotations

import math
import re

from rich import box
from rich.console import Console
from rich.table import Column, Table
from rich.text import Text

# a signed zero written out ("-0.000", "+0.0", "−0.00"): a sign not after a letter, digit or
# point, then zeros only, then no further digit
_SIGNED_ZERO = re.compile(r"(?<![\w.])[-+−](0(?:\.0*)?)(?![\d.])")


def tidy(text: str) -> str:
    """``text`` with every zero that a sign was printed with written unsigned ("-0.00" -> "0.00")."""
    return _SIGNED_ZERO.sub(r"\1", text)


def figure(x: float | None, fmt: str = "{:.4g}", none: str = "-") -> str:
    """A number for a table: ``fmt`` applied, ``none`` for a missing one, "inf" for an infinite
    one, and a zero unsigned however it rounded."""
    if x is None:
        return none
    if isinstance(x, float) and not math.isfinite(x):
        return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return tidy(fmt.format(x))


def text(header: str, **kw) -> Column:
    """A column of words: left, wrapped at spaces, a long word folded."""
    return Column(header, justify=kw.pop("justify", "left"), overflow="fold", **kw)


def number(header: str, **kw) -> Column:
    """A column of figures: right, never wrapped (a cell may hold several lines, one figure each)."""
    return Column(header, justify=kw.pop("justify", "right"), no_wrap=True, **kw)


def table(title: str | None, *columns: Column | str, lines: bool = False) -> Table:
    """A table in the compact style: a rule under the header, no outer frame, two spaces between
    columns; ``lines`` puts a rule between rows (for rows of several lines). A plain string is a
    text column."""
    cols = [text(c) if isinstance(c, str) else c for c in columns]
    return Table(*cols, title=title, title_justify="left", box=box.SIMPLE_HEAD, show_edge=False, pad_edge=False,
                 collapse_padding=True, show_lines=lines, header_style="bold")


def add_row(t: Table, *cells: str | Text | None) -> None:
    """A row whose cells have their signed zeros unsigned (see ``tidy``)."""
    t.add_row(*(tidy(c) if isinstance(c, str) else c for c in cells))


def show(console: Console, t: Table) -> None:
    """The table with its title above it, wrapped at the console's width (rich wraps a title at
    the table's own, which for a narrow table is a column of two words a line)."""
    title, t.title = t.title, None
    try:
        if title:
            console.print(title, style="table.title")
        console.print(t)
    finally:
        t.title = title


def say(*lines: str, err: bool = False) -> None:
    """Plain lines (no markup) on stdout, or stderr with ``err``, wrapped at the console's width."""
    console = Console(stderr=err)
    for line in lines:
        console.print(line, markup=False, highlight=False)


def print_listing(rows: list[tuple[str, str]]) -> None:
    """Two columns without a header (a name, then words that wrap under themselves)."""
    t = table(None, text(""), text(""))
    t.show_header = False
    for a, b in rows:
        add_row(t, a, b)
    Console().print(t)
