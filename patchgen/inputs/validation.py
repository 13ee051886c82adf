"""Reading TOML input and turning pydantic's complaints into one-line InputErrors."""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Callable
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from patchgen.inputs.errors import InputError
from patchgen.inputs.inputfile import decode_text, read_bytes
from patchgen.inputs.resources import resolve

M = TypeVar("M", bound=BaseModel)
SHOWN_MAX = 40  # characters of an offending value an error line quotes: the line stays one line

# the parts of a pydantic location that name a union member or a validator, not a field
_TAG = re.compile(r"^[a-z][a-z-]*\[.*\]$|^(float|int|str|bool|list|dict|none|constrained-float|constrained-int"
                  r"|\[key\])$")


def read_toml(path: str | Path | Traversable) -> dict[str, Any]:
    """Parse a TOML file.

    Parameters
    ----------
    path : str, Path or Traversable
        A user's file or a shipped resource.

    Returns
    -------
    dict
        The TOML document.

    Raises
    ------
    InputError
        Any problem with the file: unreadable, not UTF-8, not valid TOML.
    """
    return parse_toml(read_bytes(path), str(path))


def parse_toml(data: bytes, source: str) -> dict[str, Any]:
    """The TOML document in ``data`` (UTF-8); a syntax error names its line and column."""
    text = decode_text(data, source)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(source, "", f"not valid TOML ({exc})") from None
    except RecursionError:
        raise InputError(source, "", "not valid TOML (nested too deeply)") from None


def field_path(loc: tuple) -> str:
    """Render a pydantic location as a dotted field path (list indices in brackets)."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def _fields(loc: tuple) -> tuple:
    return tuple(p for p in loc if not (isinstance(p, str) and _TAG.match(p)))


def _shown(v: Any) -> str:
    """An input value as it would be written in TOML."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    text = repr(v)
    return text if len(text) <= SHOWN_MAX else text[:SHOWN_MAX - 3] + "..."


_BOUNDS = {"greater_than": ("gt", "must be greater than"), "greater_than_equal": ("ge", "must be at least"),
           "less_than": ("lt", "must be less than"), "less_than_equal": ("le", "must be at most")}
_TYPES = {"float_type": "must be a number", "int_type": "must be an integer", "bool_type": "must be true or false",
          "string_type": "must be a string", "finite_number": "must be a finite number (not inf or nan)",
          "int_from_float": "must be an integer", "list_type": "must be a list", "dict_type": "must be a table",
          "model_type": "must be a table", "model_attributes_type": "must be a table",
          "extra_forbidden": "unknown field", "missing": "missing field"}


def _message(err: dict) -> str:
    kind = err["type"]
    if kind in _BOUNDS:
        key, words = _BOUNDS[kind]
        limit = err.get("ctx", {}).get(key)
        return f"{words} {limit:g}" if isinstance(limit, (int, float)) else err["msg"]
    if kind in _TYPES:
        return _TYPES[kind]
    msg = err["msg"]
    if kind == "literal_error":
        return "must be " + msg.removeprefix("Input should be ")
    return msg.removeprefix("Value error, ")


def _chosen(errors: list[dict]) -> tuple[tuple, str, Any]:
    """The first problem, as field path, message and offending input. When it comes from a union
    (a number or "auto", a table or a matrix), the member that got deepest into the input says
    what is wrong; members failing at the same place are joined ("a number or 'auto'")."""
    first = errors[0]
    raw = first["loc"]
    cut = next((i for i, p in enumerate(raw) if isinstance(p, str) and _TAG.match(p)), None)
    group = [first] if cut is None else [e for e in errors if tuple(e["loc"][:cut]) == tuple(raw[:cut])]
    depth = max(len(_fields(e["loc"])) for e in group)
    deepest = [e for e in group if len(_fields(e["loc"])) == depth]
    loc = _fields(deepest[0]["loc"])
    msgs: list[str] = []
    for e in deepest:
        m = _message(e)
        if msgs and m.startswith("must be ") and msgs[0].startswith("must be "):
            m = m.removeprefix("must be ")
        if m not in msgs and "must be " + m not in msgs:
            msgs.append(m)
    return loc, " or ".join(msgs), deepest[0]


def validate(model: type[M], data: Any, source: str, prefix: str = "") -> M:
    """Validate data against a pydantic model, raising the first problem as one line.

    Parameters
    ----------
    model : type
        The pydantic model (an InputModel).
    data : object
        The parsed input.
    source : str
        The file it came from, named in the error.
    prefix : str
        A field path the model sits under, put before the field in the error ("" at the top).

    Returns
    -------
    model
        The validated instance.

    Raises
    ------
    InputError
        The first problem: its field path, what is wrong, and the offending value.
    """
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        loc, msg, err = _chosen(exc.errors())
        where = field_path(loc)
        if prefix:
            where = f"{prefix}.{where}" if where else prefix
        got = err.get("input")
        if (err["type"] not in ("missing", "extra_forbidden") and isinstance(got, (int, float, str, bool))
                and "(got " not in msg):
            msg = f"{msg} (got {_shown(got)})"
        raise InputError(source, where, msg) from None


def load_profile(model: type[M] | Callable[[dict, str], type[M]], name_or_path: str, kind: str, source: str, field: str,
                 check: Callable[[M, str], None] | None = None) -> M:
    """A shipped profile by id (``uw-1991``) or any profile file by path.

    A path that cannot be read is named against the field that gave it; a bad profile names the
    profile's own field.

    Parameters
    ----------
    model : type or callable
        The profile's model, or ``model(document, label)`` choosing it from the parsed file (a
        bench profile's by its plant).
    name_or_path : str
        A shipped profile's id or a file's path.
    kind : str
        ``"machine"`` or ``"bench"`` (see :data:`patchgen.inputs.resources.FOLDERS`).
    source, field : str
        The file and field that named the profile ("" when a user named it directly).
    check : callable, optional
        ``check(profile, label)``: the checks that need more than one field.

    Returns
    -------
    model
        The checked profile.
    """
    path = resolve(kind, name_or_path, source, field)
    data = read_bytes(path, named_by=(source, field, f"{kind} profile") if source else None)
    label = str(path) if isinstance(path, Path) else str(name_or_path)
    document = parse_toml(data, label)
    if not isinstance(model, type):
        model = model(document, label)
    profile = validate(model, document, label)
    if check is not None:
        check(profile, label)
    return profile
