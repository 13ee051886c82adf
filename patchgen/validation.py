"""Reading TOML input and turning pydantic's complaints into one-line InputErrors."""

from __future__ import annotations

import tomllib
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from .errors import InputError
from .resources import resolve

M = TypeVar("M", bound=BaseModel)


def read_toml(path: str | Path | Traversable) -> dict[str, Any]:
    """Parse a TOML file (a path or a shipped resource); a missing file or a syntax error is an InputError."""
    p = path if isinstance(path, Traversable) else Path(path)
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise InputError(str(path), "", "no such file") from None
    except IsADirectoryError:
        raise InputError(str(path), "", "is a directory, not a TOML file") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(str(path), "", f"not valid TOML ({exc})") from None


def field_path(loc: tuple) -> str:
    """Render a pydantic location as a dotted field path (list indices in brackets)."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def validate(model: type[M], data: Any, source: str, prefix: str = "") -> M:
    """Validate data against a pydantic model, raising the first problem as one line."""
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = tuple(p for p in err["loc"] if not (isinstance(p, str) and p.startswith("function-")))
        # pydantic puts the union member or validator name in loc; keep the field names only
        type_names = ("float", "int", "str", "bool", "list", "dict")
        loc = tuple(p for p in loc if not (isinstance(p, str) and ("[" in p or p in type_names)))
        where = field_path(loc)
        if prefix:
            where = f"{prefix}.{where}" if where else prefix
        msg = err["msg"]
        if err["type"] == "extra_forbidden":
            msg = "unknown field"
        elif err["type"] == "missing":
            msg = "missing field"
        elif msg.startswith("Value error, "):
            msg = msg[len("Value error, "):]
        got = err.get("input")
        if err["type"] not in ("missing", "extra_forbidden") and isinstance(got, (int, float, str, bool)):
            msg = f"{msg} (got {got!r})"
        raise InputError(source, where, msg) from None


def load_profile(model: type[M], name_or_path: str, kind: str, source: str, field: str) -> M:
    """A shipped profile by id (``uw-1991``) or any profile file by path."""
    path = resolve(kind, name_or_path, source, field)
    if isinstance(path, Path) and not path.is_file():
        raise InputError(source or name_or_path, field, f"no {kind} profile file {name_or_path!r}")
    return validate(model, read_toml(path), str(name_or_path) if not isinstance(path, Path) else str(path))
