"""Data below, presentation on top: no module outside render/ imports a plotting, drawing,
templating or terminal library, and every command module stays thin (parse, call the pipeline,
hand the report to render)."""

from __future__ import annotations

import ast
from pathlib import Path

import patchgen
from patchgen.cli import COMMANDS

PKG = Path(patchgen.__file__).parent
PRESENTATION = ("matplotlib", "schemdraw", "jinja2", "rich")
MAX_COMMAND_LINES = 80


def _imports(path: Path) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            out.add(node.module.split(".")[0])
    return out


def test_only_render_imports_the_presentation_libraries():
    found = {p.relative_to(PKG).as_posix(): sorted(_imports(p) & set(PRESENTATION))
             for p in PKG.rglob("*.py") if p.relative_to(PKG).parts[0] != "render"}
    assert {k: v for k, v in found.items() if v} == {}


def test_command_modules_are_thin():
    sizes = {name: len((PKG / "cli" / f"{name.replace('-', '_')}.py").read_text().splitlines()) for name in COMMANDS}
    assert {k: v for k, v in sizes.items() if v > MAX_COMMAND_LINES} == {}
