"""The data patchgen ships inside its package: designs, scenarios, machine and bench profiles, templates.

Everything is reached through :mod:`importlib.resources`, so an installed wheel finds its data
wherever it is run from. A user names a shipped file by its stem (``bench-recommended``,
``hold-120s``) or gives a path to a file of their own; a path that exists always wins.
"""

from __future__ import annotations

from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path

from patchgen.inputs.errors import InputError

# kind -> (package, folder inside it); designs, sims and templates sit at the repository's top
# level and are installed as packages of their own (pyproject.toml maps them in)
FOLDERS = {
    "design": ("patchgen.designs", ""),
    "scenario": ("patchgen.sims", ""),
    "machine": ("patchgen", "profiles/machines"),
    "bench": ("patchgen", "profiles/benches"),
    "template": ("patchgen.templates", ""),
}
# what `patchgen examples` copies out for a user to edit: kind -> sub-folder of the examples folder
EXAMPLES = {"design": "designs", "scenario": "sims", "machine": "machines", "bench": "benches"}


def folder(kind: str) -> Traversable:
    """The package folder holding the shipped files of one kind."""
    package, sub = FOLDERS[kind]
    try:
        top = resources.files(package)
    except ModuleNotFoundError:
        # a source checkout run without installing it: the data folder beside the package
        top = Path(__file__).resolve().parents[2] / package.rpartition(".")[2]
        if not top.is_dir():
            raise
    return top.joinpath(*sub.split("/")) if sub else top


def shipped(kind: str) -> list[str]:
    """Stems of the shipped TOML files of one kind, sorted."""
    return sorted(p.name[:-5] for p in folder(kind).iterdir() if p.name.endswith(".toml"))


def example_files() -> dict[str, bytes]:
    """Every shipped design, scenario and profile, keyed by its path under the examples folder."""
    return {f"{sub}/{name}.toml": folder(kind).joinpath(f"{name}.toml").read_bytes()
            for kind, sub in EXAMPLES.items() for name in shipped(kind)}


def shipped_file(kind: str, name: str) -> Traversable:
    """One shipped file by stem; unknown names are an InputError listing the known ones."""
    f = folder(kind).joinpath(f"{name}.toml")
    if not f.is_file():
        raise InputError(name, "", f"no such file, and no shipped {kind} of that name "
                                   f"(shipped: {', '.join(shipped(kind))})")
    return f


def is_shipped_file(kind: str, name: str, name_or_path: str | Path) -> bool:
    """Whether what a user gave (a stem, or a path that exists) is the shipped file ``name`` of that
    kind itself."""
    found = resolve(kind, name_or_path)
    shipped_one = folder(kind).joinpath(f"{name}.toml")
    if not isinstance(found, Path):
        return found == shipped_one
    try:
        return isinstance(shipped_one, Path) and found.resolve() == shipped_one.resolve()
    except OSError:
        return False


def resolve(kind: str, name_or_path: str | Path, source: str = "", field: str = "") -> Path | Traversable:
    """A user's file by path, or a shipped one by stem (when no file of that name exists).

    Parameters
    ----------
    kind : str
        A key of :data:`FOLDERS` (``"design"``, ``"scenario"``, ``"machine"``, ``"bench"``).
    name_or_path : str or Path
        What the user gave. Anything that exists, or looks like a path (a suffix, a slash), is a
        path; otherwise a shipped stem.
    source, field : str
        The file and field that named it, for the error (a profile named in a spec). A relative
        path is looked for beside ``source`` first, then from the working folder.

    Returns
    -------
    Path or Traversable
        The path found, or the shipped resource.

    Raises
    ------
    InputError
        Neither a file nor a shipped stem; the known stems are listed.
    """
    text = str(name_or_path)
    path = Path(text)
    beside = Path(source).parent / path if source and text and not path.is_absolute() else None
    if beside is not None and _exists(beside):
        return beside  # a spec's relative path is read from the spec's own folder first
    if text and (_exists(path) or path.suffix or "/" in text or "\\" in text or "\0" in text):
        return path
    f = folder(kind).joinpath(f"{text}.toml")
    if text and _exists(f):
        return f
    known = ", ".join(shipped(kind))
    if source:
        raise InputError(source, field, f"unknown {kind} {text!r} (known: {known})")
    raise InputError(text or "''", field, f"no such file, and no shipped {kind} of that name (shipped: {known})")


def _exists(path: Path | Traversable) -> bool:
    """Whether anything is at path; a name the OS refuses (too long, say) is left for the reader to name."""
    try:
        return path.exists() if isinstance(path, Path) else path.is_file()
    except (OSError, ValueError):
        return isinstance(path, Path)
