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


STAGES = {"design_on", "build_patch", "simulate", "recommend", "sweep", "identify", "bench_test_files",
          "static_check", "diagnose_readings", "manoeuvre", "predict", "as_patched_on_bench", "study"}
WRITERS = {"write_text", "write_bytes"}
SCRATCH = {  # modules that write files other than a command's outputs, and why
    "render/outputs.py": "the one writer of a command's files",
    "spice/deck.py": "the deck for ngspice, into the temporary folder spice/run.py runs it in",
    "spice/run.py": "ngspice's log, into that temporary folder",
}


def _command_sources():
    return {name: (PKG / "cli" / f"{name.replace('-', '_')}.py").read_text() for name in COMMANDS}


def test_commands_call_the_pipeline_not_the_stages():
    """A command runs no stage itself: it parses, calls its pipeline function and hands the report
    to render (examples only copies the shipped files)."""
    called, no_pipeline = {}, []
    for name, text in _command_sources().items():
        tree = ast.parse(text)
        imported = {a.asname or a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names}
        called[name] = sorted(imported & STAGES)
        if name != "examples" and not any(isinstance(n, ast.ImportFrom) and (n.module or "").startswith(
                "patchgen.pipeline.") for n in ast.walk(tree)):
            no_pipeline.append(name)
    assert {k: v for k, v in called.items() if v} == {} and no_pipeline == []


def test_shared_options_are_declared_once():
    """--force, --json, --svg, --seed, --machine and --bench come from cli/options.py, not declared per
    command (bench-test's --bench, a bench to record on, means something else and says so)."""
    shared = {"--force", "--json", "--svg", "--seed", "--machine"}
    found = {}
    for name, text in _command_sources().items():
        for node in ast.walk(ast.parse(text)):
            if (isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "option"
                    and any(isinstance(a, ast.Constant) and a.value in shared for a in node.args)):
                found.setdefault(name, []).append(node.args[0].value)
    assert found == {}


def test_only_the_writer_writes_a_commands_files():
    """Every file a command writes goes through render.outputs.write_files (all or nothing, never a
    user's file silently replaced); nothing else in the package writes files, but ngspice's scratch."""
    found = []
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG).as_posix()
        if rel in SCRATCH:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.Call):
                continue
            name = getattr(node.func, "attr", getattr(node.func, "id", ""))
            mode = [a.value for a in node.args[1:2] if isinstance(a, ast.Constant)] + [
                k.value.value for k in node.keywords if k.arg == "mode" and isinstance(k.value, ast.Constant)]
            if name in WRITERS or (name == "open" and any(c in str(m) for m in mode for c in "wax")):
                found.append(f"{rel}:{node.lineno}")
    # the one exception: main() sends Python's last flush of stdout to /dev/null after a broken pipe
    assert found == ["cli/__init__.py:" + str(_devnull_line())]


def _devnull_line() -> int:
    text = (PKG / "cli" / "__init__.py").read_text().splitlines()
    return next(i for i, line in enumerate(text, 1) if "open(os.devnull" in line)
