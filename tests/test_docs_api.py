"""The worked example in docs/api.md runs as printed: its python blocks, in order, in one namespace
(in a scratch directory, as it writes its plots there), with python-control's warnings as errors."""

from __future__ import annotations

import re
import warnings

import matplotlib
import pytest

from tests.conftest import ROOT

BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def test_api_doc_example_runs(tmp_path, monkeypatch, capsys):
    matplotlib.use("Agg")
    blocks = BLOCK.findall((ROOT / "docs" / "api.md").read_text())
    assert len(blocks) >= 5
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "docs_api"}
    with warnings.catch_warnings():
        warnings.filterwarnings("error", module="control")
        for i, code in enumerate(blocks):
            exec(compile(code, f"docs/api.md block {i + 1}", "exec"), namespace)
    out = capsys.readouterr().out
    # the figures conventions.md quotes for case 1 (thesis section 4.5.1), as the example prints them
    assert "LQR: lower GM -11.19 dB, PM 79.12 deg" in out
    assert "gain margins [ 1.03 -1.18] dB" in out and "-5.68" in out
    assert "closed-loop RHP poles 0" in out
    assert (tmp_path / "case1-bode.png").stat().st_size > 0 and (tmp_path / "case1-nyquist.png").stat().st_size > 0
    assert namespace["y"]["u"][-1] == pytest.approx(-1.0, abs=1e-3)  # the push is cancelled
