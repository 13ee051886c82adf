"""Reading a user's input file: whatever the path names, the answer is its text or one InputError.

A path may name a directory, a FIFO (opening one for reading would wait for a writer forever), a
device, a file too large to be a spec, or bytes that are not UTF-8 text; each is named as such.
The file is checked with stat before it is opened, opened without blocking, and checked again
on the open descriptor (the path may change in between).
"""

from __future__ import annotations

import errno
import os
import stat
from importlib.resources.abc import Traversable
from pathlib import Path

from patchgen.inputs.errors import InputError

MAX_INPUT_BYTES = 1 << 20  # 1 MiB: a spec, scenario or profile is a few kB of TOML

_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))


def _kind(mode: int) -> str | None:
    """What a non-regular file is, or None for a regular file."""
    if stat.S_ISREG(mode):
        return None
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _os_problem(exc: OSError) -> str:
    if exc.errno == errno.ENOENT:
        return "no such file"
    if exc.errno == errno.ENOTDIR:
        return "no such file (a part of the path is a file, not a folder)"
    if exc.errno in (errno.EACCES, errno.EPERM):
        return "cannot be read (permission denied)"
    if exc.errno == errno.ENAMETOOLONG:
        return "cannot be read (the path or one of its names is too long)"
    return f"cannot be read ({exc.strerror or exc})"


def read_bytes(path: str | Path | Traversable, named_by: tuple[str, str, str] | None = None, *,
               limit: int = MAX_INPUT_BYTES, kind: str = "a TOML file",
               too_large: str = "not a spec, scenario or profile") -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes (a shipped resource is read as is).

    Parameters
    ----------
    path : str, Path or Traversable
        The file.
    named_by : tuple of (str, str, str), optional
        (file, field, what) when the path came from another file's field, e.g. a spec's machine
        profile: a path that cannot be used (missing, a directory, a FIFO, unreadable) is then
        named against that field, which is what to fix. What is read (too large) names the path
        itself.
    limit : int
        The largest file accepted, in bytes.
    kind, too_large : str
        What the file should be ("a TOML file"), and what a file over ``limit`` is not.

    Returns
    -------
    bytes
        The file's contents.

    Raises
    ------
    InputError
        Naming what the path is when it is not a readable regular file of a spec's size.
    """
    if isinstance(path, Traversable) and not isinstance(path, Path):
        return path.read_bytes()
    p = str(path)

    def refuse(problem: str) -> InputError:
        if named_by is None:
            return InputError(p or "''", "", problem)
        source, field, what = named_by
        if problem == "no such file":
            return InputError(source, field, f"no {what} file {p!r}")
        return InputError(source, field, f"{what} {p!r} {problem}")

    if not p:
        raise refuse("is an empty file name")
    if "\0" in p:
        raise refuse("cannot be read (a file name cannot contain a NUL character)")
    try:
        found = _kind(os.stat(p).st_mode)
    except OSError as exc:
        raise refuse(_os_problem(exc)) from None
    if found is not None:
        raise refuse(f"is {found}, not {kind}")
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise refuse(_os_problem(exc)) from None
    try:
        found = _kind(os.fstat(fd).st_mode)
        if found is not None:
            raise refuse(f"is {found}, not {kind}")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise refuse(_os_problem(exc)) from None
    finally:
        os.close(fd)
    if len(data) > limit:
        raise InputError(p, "", f"is larger than {_size(limit)}: {too_large}")
    return data


def _size(n: int) -> str:
    return f"{n >> 20} MiB" if n >= 1 << 20 else f"{n >> 10} kB"


def decode_text(data: bytes, source: str, kind: str = "a TOML file") -> str:
    """UTF-8 text (a leading byte-order mark is dropped); other encodings and binary data are named."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise InputError(source, "", f"not UTF-8 text: byte 0x{data[exc.start]:02x} on line {line} "
                                     "(save the file as UTF-8)") from None
    if "\0" in text:
        line = text[:text.index("\0")].count("\n") + 1
        raise InputError(source, "", f"binary data, not {kind} (a NUL byte on line {line})")
    return text.removeprefix("\ufeff")
