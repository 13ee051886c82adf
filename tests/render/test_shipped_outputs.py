"""Every shipped GP-6 design's patch files against golden copies: words and structure exactly,
numbers to 1e-9 relative (the goldens were written before the code moved into its folders)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from patchgen.design.lqg import design_on
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.render.patchfiles import patch_files
from tests.golden import assert_matches, assert_text_matches

GOLDEN = Path(__file__).parents[1] / "fixtures" / "golden"
RTOL, ATOL = 1e-9, 1e-12


@pytest.fixture(scope="module", params=sorted(p.name for p in GOLDEN.iterdir()))
def files(request):
    spec = load_spec(request.param)
    machine = load_machine(spec.machine)
    d = design_on(spec, machine, load_bench(spec.bench))
    return request.param, patch_files(d, machine, build_patch(d, machine))


def test_netlist_matches(files):
    name, got = files
    assert_matches(json.loads(got["netlist.json"]), json.loads((GOLDEN / name / "netlist.json").read_text()),
                   RTOL, ATOL, f"{name}/netlist.json")


@pytest.mark.parametrize("file", ["pots.csv", "wiring.svg", "patch-sheet.md"])
def test_rendered_file_matches(files, file):
    name, got = files
    assert_text_matches(got[file], (GOLDEN / name / file).read_text(), RTOL, ATOL, f"{name}/{file}")


def test_the_text_comparison_catches_a_changed_word_or_figure():
    want = "P2 0.267 theta x10 into A6"
    assert_text_matches("P2 0.26700000000001 theta x10 into A6", want, RTOL, ATOL)
    for wrong in ("P2 0.268 theta x10 into A6", "P2 0.267 theta x1 into A6", "P2 0.267 s_dot x10 into A6",
                  "P2 -0.267 theta x10 into A6"):
        with pytest.raises(AssertionError):
            assert_text_matches(wrong, want, RTOL, ATOL)
