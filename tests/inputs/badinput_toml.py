"""TOML text from plain data, and the wrong values a field of each kind is tried with.

The bad-input corpus edits the shipped files as data (a dict from tomllib), so it needs to write
them back: every top-level key as ``key = value`` with inline tables, which TOML allows. inf and
nan are written as TOML's own ``inf`` and ``nan``.
"""

from __future__ import annotations

import copy
import json
import math
import re
from dataclasses import dataclass

DELETE = object()  # a mutation that removes the field


def value(v) -> str:
    """One TOML value."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{key(k)} = {value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def dumps(data: dict) -> str:
    """A TOML document holding ``data``."""
    return "".join(f"{key(k)} = {value(v)}\n" for k, v in data.items())


def with_field(data: dict, path: str, new) -> dict:
    """A deep copy of data with the dotted field set to ``new`` (or removed: DELETE)."""
    out = copy.deepcopy(data)
    *parents, last = path.split(".")
    node = out
    for p in parents:
        node = node.setdefault(p, {})
    if new is DELETE:
        node.pop(last, None)
    else:
        node[last] = new
    return out


@dataclass(frozen=True)
class Num:
    """A float field with the range its model declares (None: unbounded on that side)."""

    lo: float | None = None
    hi: float | None = None
    open_lo: bool = False
    required: bool = True
    symmetric: bool = False  # a signed magnitude: -hi .. hi
    matrix: bool = False  # a number or a matrix: a flat list is named at its first row


def number_mutations(f: Num) -> dict[str, object]:
    """Every wrong value for a number field, by name (the field that is wrong: see ``sub_field``)."""
    out: dict[str, object] = {"string": "3.5", "bool": True, "inf": math.inf, "-inf": -math.inf, "nan": math.nan,
                              "list": [1.0], "table": {"v": 1.0}}
    lo = -f.hi if f.symmetric else f.lo
    if lo is not None:
        if lo >= 0:
            out["negative"] = -1.0
        if lo > 0 or (lo == 0 and f.open_lo):
            out["zero"] = 0.0
        if lo > 0:
            out["tiny"] = 1e-300
            out["below"] = lo / 2
        elif lo < 0:
            out["below"] = lo * 2
    if f.hi is not None:
        out["huge"] = 1e300
        out["above"] = f.hi * 2 if f.hi > 0 else f.hi + 1
    if f.required:
        out["missing"] = DELETE
    return out


def sub_field(f: Num, mutation: str) -> str:
    """Where in the field the line points for a mutation ("[0]": its first row)."""
    return "[0]" if f.matrix and mutation == "list" else ""


INT_MUTATIONS = {"float": 1.5, "string": "2", "bool": True, "list": [1]}
STR_MUTATIONS = {"int": 3, "bool": True, "list": ["a"], "float": 1.5}
BOOL_MUTATIONS = {"string": "yes", "int": 1, "float": 1.0}
WORD_MUTATIONS = {"unknown": "bogus", "int": 3, "bool": False}
