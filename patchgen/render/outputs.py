"""Writing a command's output files all or nothing, never replacing a file without being told.

``check_out_dir`` is the pre-flight a command runs before it computes anything: the folder must
be a usable place (not empty, not a file, not under /proc, /sys or /dev, its nearest existing
parent a writable folder, names within the file system's limits) and, without --force, none of
the command's files may exist already. ``write_files`` repeats the check with the exact file
names, writes everything into a staging folder and moves it in only when all is ready.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import stat
import tempfile
from collections.abc import Iterable
from pathlib import Path

from patchgen.inputs.errors import InputError

KERNEL_FILE_SYSTEMS = ("/proc", "/sys", "/dev")


def json_text(data) -> str:
    """Every JSON patchgen writes or prints, one way: sorted keys, two-space indent, a final newline,
    no NaN or infinity (a non-finite figure is a bug, not a value), so the same data gives the same
    bytes."""
    return json.dumps(data, indent=2, sort_keys=True, allow_nan=False) + "\n"
NAME_MAX = 255  # bytes in one file name, when the file system does not say
PATH_MAX = 4096  # bytes in a whole path, likewise


def _problem(exc: OSError) -> str:
    if exc.errno == errno.ENAMETOOLONG:
        return "the path or one of its names is too long"
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return "not writable (permission denied)" if exc.errno != errno.EROFS else "on a read-only file system"
    if exc.errno == errno.ENOSPC:
        return "no space left on the device"
    return exc.strerror or str(exc)


def _lstat(path: Path) -> os.stat_result | None:
    """stat without following a final symlink; None when nothing is there."""
    try:
        return os.lstat(path)
    except FileNotFoundError:
        return None


def _is_dir(st: os.stat_result | None, path: Path) -> bool:
    return st is not None and (stat.S_ISDIR(st.st_mode) or (stat.S_ISLNK(st.st_mode) and path.is_dir()))


def _existing_ancestor(out: Path, label: str, option: str) -> Path:
    """The nearest folder above ``out`` that exists; a file on the way is an error."""
    for parent in out.absolute().parents:
        st = os.stat(parent) if os.path.lexists(parent) else None
        if st is None:
            continue
        if not stat.S_ISDIR(st.st_mode):
            raise InputError(label, option, f"{parent} is a file, not a folder")
        return parent
    return Path("/")


def _check_names(out: Path, label: str, option: str) -> None:
    text = os.fsencode(str(out.absolute()))
    if len(text) >= PATH_MAX:
        raise InputError(label, option, f"the path is longer than the file system allows ({PATH_MAX} bytes)")
    for part in out.parts:
        if len(os.fsencode(part)) > NAME_MAX:
            raise InputError(label, option, f"a name in the path is longer than the file system allows "
                                            f"({NAME_MAX} bytes)")


def check_out_dir(out_dir: str | os.PathLike, names: Iterable[str] = (), force: bool = False,
                  option: str = "-o") -> Path:
    """The output folder, checked before anything is computed or written (see the module doc)."""
    text = os.fspath(out_dir)
    if not text.strip():
        raise InputError("''", option, "empty: name an output folder")
    if "\0" in text:
        raise InputError(repr(text), option, "a folder name cannot contain a NUL character")
    out = Path(text)
    label = text
    try:
        _check_names(out, label, option)
        real = os.path.realpath(out)
        for root in KERNEL_FILE_SYSTEMS:
            if real == root or real.startswith(root + "/"):
                raise InputError(label, option, f"is under {root}, a kernel file system, not a place for output")
        st = os.stat(out) if os.path.lexists(out) else None
        if st is not None and not stat.S_ISDIR(st.st_mode):
            raise InputError(label, option, "exists and is not a directory")
        place = out if st is not None else _existing_ancestor(out, label, option)
        if not os.access(place, os.W_OK | os.X_OK):
            raise InputError(label, option, f"cannot write into {place} (permission denied)")
        if st is None:
            return out
        _check_clashes(out, list(names), force, label, option)
    except OSError as exc:
        raise InputError(label, option, _problem(exc)) from None
    return out


def _check_clashes(out: Path, names: list[str], force: bool, label: str, option: str) -> None:
    """Output paths in an existing folder: a directory (or a file where a sub-folder goes) is in
    the way whatever --force says; an existing file needs --force."""
    clash = []
    for name in names:
        target = out / name
        for sub in list(reversed(Path(name).parents))[1:]:
            st = _lstat(out / sub)
            if st is not None and not _is_dir(st, out / sub):
                raise InputError(str(out / sub), option, f"is a file where the output folder {sub} goes")
        st = _lstat(target)
        if st is None:
            continue
        if _is_dir(st, target):
            raise InputError(str(target), option, "is a directory where an output file goes "
                                                  "(--force replaces files only): move it away")
        clash.append(name)
    if clash and not force:
        raise InputError(str(out / clash[0]), option,
                         f"already exists ({len(clash)} output file(s) would be replaced); use --force to replace")


def _no_bad_numbers(name: str, data: str | bytes) -> None:
    """A JSON output must not carry NaN or Infinity (not JSON; a reader would choke): a bug if so."""
    def refuse(word: str):
        raise ValueError(f"{name}: {word} in a JSON output file: a non-finite number escaped the checks")
    json.loads(data, parse_constant=refuse)


def _write_text(path: Path, text: str, chunk: int = 1 << 20) -> None:
    """Write text as UTF-8 a million characters at a time, so that a file of tens of megabytes (a
    SPICE noise table) is not held twice, as text and as its encoding."""
    with open(path, "w", encoding="utf-8") as f:
        for i in range(0, len(text), chunk):
            f.write(text[i:i + chunk])


def write_files(out_dir: str | Path, files: dict[str, str | bytes], force: bool = False,
                option: str = "-o") -> list[Path]:
    """Write every file into out_dir, or none: the folder is checked again with the exact names,
    files are staged in a temporary folder (inside out_dir when it exists, else beside it) and
    moved in only when all are ready. Existing files are replaced only with force."""
    out = check_out_dir(out_dir, files, force, option)
    for name, data in files.items():
        if name.endswith(".json"):
            _no_bad_numbers(name, data)
    exists = out.is_dir()
    base = out if exists else _existing_ancestor(out, str(out), option)
    try:
        stage = Path(tempfile.mkdtemp(prefix=".patchgen-", dir=base))
    except OSError as exc:
        raise InputError(str(out), option, f"cannot write into {base} ({_problem(exc)})") from None
    try:
        tree = stage / "out"
        for name, data in files.items():
            p = tree / name
            p.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(data, bytes):
                p.write_bytes(data)
            else:
                _write_text(p, data)
        if not exists:
            out.parent.mkdir(parents=True, exist_ok=True)
            os.replace(tree, out)
        else:
            for name in files:
                (out / name).parent.mkdir(parents=True, exist_ok=True)
                os.replace(tree / name, out / name)
        return [out / name for name in files]
    except OSError as exc:
        raise InputError(str(out), option, f"cannot be written ({_problem(exc)})") from None
    finally:
        shutil.rmtree(stage, ignore_errors=True)
