"""The layer contract: patchgen's folders form a declared graph of layers, and imports only run
along it.

DEPENDS declares, for each folder, the folders it builds on directly; a folder may import its
own modules and every folder its declared ones reach (the closure). Folders on no path to one
another are siblings and independent (identify, spice, swingup and studies know nothing of one
another). The declaration itself must be a DAG over every folder.

Every import in every module (top level or inside a function) is read from the source, so a late
import cannot hide an edge. A name the root package hands out lazily (``from patchgen import
load_design``) is an import of the module it comes from, and a dynamic import
(``importlib.import_module``, ``__import__``) of a literal module name is an import too; one whose
target cannot be read from the source is a violation of its own unless it is relative to the
module's own package (``f"{__name__}.{...}"``). No module may reach itself through imports.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

import patchgen

PKG = Path(patchgen.__file__).parent

DEPENDS = {  # each folder's direct foundations: data below, presentation (render) on top
    "plant": (),
    "inputs": ("plant",),
    "profiles": ("inputs",),
    "design": ("profiles",),
    "patch": ("design",),
    "bench": ("patch",),
    "identify": ("bench",),
    "spice": ("bench",),
    "lucidac": ("bench",),
    "swingup": ("bench",),
    "studies": ("bench",),
    "pipeline": ("identify", "spice", "lucidac", "swingup", "studies"),
    "render": ("pipeline",),
    "cli": ("render",),
}
LAZY = patchgen._LAZY  # the root package's lazily exported names -> their modules


def _closure(layer: str) -> frozenset[str]:
    """Every folder ``layer`` may import: its declared foundations, theirs, and so on."""
    out, todo = set(), list(DEPENDS[layer])
    while todo:
        d = todo.pop()
        if d not in out:
            out.add(d)
            todo.extend(DEPENDS[d])
    return frozenset(out)


ALLOWED = {layer: _closure(layer) for layer in DEPENDS}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PKG.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in PKG.rglob("*.py")}


def _dynamic_target(call: ast.Call, package: str) -> str | None:
    """The module a dynamic import names: a literal, or an f-string relative to ``__name__`` (its
    own package: returned as the package itself); "?" when the source does not say."""
    if not call.args:
        return "?"
    arg = call.args[0]
    if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
        return arg.value
    if (isinstance(arg, ast.JoinedStr) and arg.values and isinstance(arg.values[0], ast.FormattedValue)
            and isinstance(arg.values[0].value, ast.Name) and arg.values[0].value.id == "__name__"):
        return package
    return "?"


def _is_dynamic_import(node: ast.AST) -> bool:
    if not isinstance(node, ast.Call):
        return False
    f = node.func
    return ((isinstance(f, ast.Attribute) and f.attr == "import_module")
            or (isinstance(f, ast.Name) and f.id in ("import_module", "__import__")))


def imports_of(source: str, name: str, is_package: bool, modules=MODULES) -> set[str]:
    """The patchgen modules a source imports, anywhere in it, resolved to module names ("?" for a
    dynamic import whose target the source does not say)."""
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
            for a in node.names:
                sub = f"{target}.{a.name}"
                if target == "patchgen" and a.name in LAZY:  # the root's lazy export: its real module
                    found.add(LAZY[a.name])
                else:  # `from pkg import mod` names a module when mod is one
                    found.add(sub if sub in modules else target)
        elif _is_dynamic_import(node):
            target = _dynamic_target(node, package)
            if target == "?" or target.startswith("patchgen"):
                found.add(target)
    return {m for m in found if (m in modules or m == "?") and m != name}


@functools.cache
def graph() -> dict[str, set[str]]:
    """Each module's patchgen imports: parsed when a test first asks (not while collecting, which
    every worker does)."""
    return {m: imports_of(p.read_text(), m, p.name == "__init__.py") for m, p in MODULES.items()}


def _layer(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in DEPENDS else None


def edge_problem(module: str, target: str) -> str | None:
    """What is wrong with ``module`` importing ``target`` (None: nothing)."""
    if target == "?":
        return f"{module} imports a module its source does not name (a dynamic import the contract cannot read)"
    a, b = _layer(module), _layer(target)
    if a is None or b is None or a == b or b in ALLOWED[a]:
        return None
    how = "a sibling" if a not in ALLOWED[b] else "above it"
    return f"{module} ({a}) imports {target} ({b}), {how}: {a} may import {', '.join(sorted(ALLOWED[a])) or 'nothing'}"


def cycles(g: dict[str, set[str]]) -> list[list[str]]:
    """The import cycles of a module graph (Tarjan's strongly connected components, iterative)."""
    index, low, on, stack, out = {}, {}, set(), [], []
    for root in sorted(g):
        if root in index:
            continue
        work = [(root, iter(sorted(g[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in g:
                    continue
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(g[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    x = stack.pop()
                    on.discard(x)
                    comp.append(x)
                    if x == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_the_declared_layers_are_a_dag_over_every_folder():
    folders = {p.name for p in PKG.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert set(DEPENDS) == folders
    assert all(set(d) <= set(DEPENDS) for d in DEPENDS.values())
    assert cycles({k: set(v) for k, v in DEPENDS.items()}) == []
    assert all(layer not in ALLOWED[layer] for layer in DEPENDS)


def test_every_module_lives_in_a_layer():
    loose = sorted(m for m in MODULES if _layer(m) is None and m not in ("patchgen", "patchgen.__main__"))
    assert not loose, f"modules outside the layer folders: {loose}"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if _layer(m) is not None))
def test_imports_run_along_the_declared_graph(module):
    problems = [p for t in sorted(graph()[module]) if (p := edge_problem(module, t))]
    assert not problems, "\n".join(problems)


def test_no_import_cycles():
    assert cycles(graph()) == []


# ---- planted violations: each kind is seen ----------------------------------------------------

def _planted(source: str, name: str) -> list[str]:
    modules = {**MODULES, name: None}
    return [p for t in sorted(imports_of(source, name, False, modules)) if (p := edge_problem(name, t))]


def test_a_planted_upward_import_is_seen():
    """Relative and late imports are resolved: an upward edge, however written, is found."""
    source = ("import numpy\nfrom .equations import PlantParams\n"
              "def f():\n    from ..studies import recommend\n    from patchgen.bench.simulate import simulate\n")
    assert imports_of(source, "patchgen.plant.probe", False) == {
        "patchgen.plant.equations", "patchgen.studies.recommend", "patchgen.bench.simulate"}
    assert len(_planted(source, "patchgen.plant.probe")) == 2


def test_a_planted_sibling_import_is_seen():
    problems = _planted("from patchgen.spice.deck import spice_deck\n", "patchgen.identify.probe")
    assert len(problems) == 1 and "a sibling" in problems[0]
    assert _planted("from patchgen.bench.simulate import simulate\n", "patchgen.identify.probe") == []


def test_a_planted_lazy_root_import_is_seen():
    """``from patchgen import load_design`` in a low layer is an import of patchgen.design.lti."""
    problems = _planted("from patchgen import load_design\n", "patchgen.inputs.probe")
    assert len(problems) == 1 and "patchgen.design.lti" in problems[0]
    assert _planted("from patchgen import __version__\n", "patchgen.inputs.probe") == []


def test_a_planted_dynamic_import_is_seen():
    named = "import importlib\ndef f():\n    return importlib.import_module('patchgen.studies.recommend')\n"
    assert len(_planted(named, "patchgen.design.probe")) == 1
    hidden = "import importlib\ndef f(n):\n    return importlib.import_module('patchgen.' + n)\n"
    assert "cannot read" in _planted(hidden, "patchgen.design.probe")[0]
    dunder = "def f():\n    return __import__('patchgen.cli')\n"
    assert len(_planted(dunder, "patchgen.plant.probe")) == 1
    own = "import importlib\ndef f(n):\n    return importlib.import_module(f'{__name__}.{n}')\n"
    assert _planted(own, "patchgen.cli.probe") == []  # the command group loading its own commands


def test_a_planted_cycle_is_seen():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert cycles(g) == [["a", "b", "c"]]
