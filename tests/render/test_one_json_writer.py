"""Every JSON file and --json output is written one way (patchgen.render.outputs.json_text): no
other module formats JSON for output itself (the netlist, below render, serialises itself)."""

from __future__ import annotations

import ast
import json
import math
from pathlib import Path

import pytest

import patchgen
from patchgen.render.outputs import json_text

PKG = Path(patchgen.__file__).parent
OWN = {"render/outputs.py", "patch/netlist.py"}


def test_no_module_formats_output_json_itself():
    found = []
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG).as_posix()
        if rel in OWN:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "dumps"
                    and any(k.arg == "indent" for k in node.keywords)):
                found.append(f"{rel}:{node.lineno}")
    assert found == []


def test_json_text_is_sorted_indented_and_refuses_non_finite():
    assert json_text({"b": 1, "a": [1.5, None]}) == '{\n  "a": [\n    1.5,\n    null\n  ],\n  "b": 1\n}\n'
    assert json.loads(json_text({"x": 0.1})) == {"x": 0.1}
    with pytest.raises(ValueError):
        json_text({"x": math.nan})
