"""The layer contract: patchgen's folders follow its pipeline, and imports only run downwards.

Every import in every module (top level or inside a function) is read from the source, so a
late import cannot hide an upward edge. A folder may import its own modules and any folder
below it in LAYERS; no module may reach itself through imports (no cycles, inside a folder too).
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

import patchgen

PKG = Path(patchgen.__file__).parent

# lowest first: each folder may import itself and the folders before it
LAYERS = ("plant", "inputs", "profiles", "design", "patch", "render", "bench", "identify", "spice", "swingup",
          "studies", "cli")


def _module_name(path: Path) -> str:
    parts = path.relative_to(PKG.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """The patchgen modules a file imports, anywhere in it, resolved to module names."""
    return _imports_of(path.read_text(), _module_name(path), path.name == "__init__.py")


def _imports_of(source: str, name: str, is_package: bool) -> set[str]:
    package = name if is_package else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("patchgen")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("patchgen"):
                continue
            # `from pkg import mod` names a module when mod is one
            for a in node.names:
                sub = f"{target}.{a.name}"
                found.add(sub if sub in MODULES else target)
    return {m for m in found if m in MODULES and m != name}


MODULES = {_module_name(p): p for p in PKG.rglob("*.py")}


@functools.cache
def graph() -> dict[str, set[str]]:
    """Each module's patchgen imports: parsed when a test first asks (not while collecting, which
    every worker does)."""
    return {m: _imports(p) for m, p in MODULES.items()}


def _layer(module: str) -> int | None:
    parts = module.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 and parts[1] in LAYERS else None


def test_every_module_lives_in_a_layer():
    loose = sorted(m for m in MODULES if _layer(m) is None and m not in ("patchgen", "patchgen.__main__"))
    assert not loose, f"modules outside the layer folders: {loose}"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if _layer(m) is not None))
def test_imports_run_downwards(module):
    upward = sorted(t for t in graph()[module] if _layer(t) is not None and _layer(t) > _layer(module))
    assert not upward, f"{module} (layer {LAYERS[_layer(module)]}) imports higher layers: {upward}"


def test_no_import_cycles():
    # Tarjan's strongly connected components over the module graph
    index, low, stack, on, cycles = {}, {}, [], set(), []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph()[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(graph()):
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


def test_the_contract_sees_an_upward_import():
    """The reader resolves relative and late imports: a planted upward edge is found."""
    source = ("import numpy\nfrom .equations import PlantParams\n"
              "def f():\n    from ..studies import recommend\n    from patchgen.bench.simulate import simulate\n")
    found = _imports_of(source, "patchgen.plant.probe", is_package=False)
    assert found == {"patchgen.plant.equations", "patchgen.studies.recommend", "patchgen.bench.simulate"}
    assert _layer("patchgen.plant.probe") < _layer("patchgen.studies.recommend")
