"""patchgen export: a patched machine refused in one line, exit 2, before anything is computed or
written; a missing client library named by its extra; files never replaced silently."""

from __future__ import annotations

import sys

import pytest

from patchgen.inputs.errors import InputError
from patchgen.lucidac.config import lucipy_module
from tests.cli_run import run_patchgen


def test_a_patched_machine_is_refused_in_one_line(tmp_path):
    r = run_patchgen("export", "bench-recommended", "--machine", "gp6", "-o", tmp_path / "out")
    assert r.returncode == 2
    assert r.stderr.strip().splitlines() == [
        "patchgen: --machine: gp6: export targets programmed machines (lucidac); the Comdyna GP-6 is patched: "
        "use patchgen patch"]
    assert not (tmp_path / "out").exists()


def test_without_lucipy_the_extra_is_named(monkeypatch):
    monkeypatch.setitem(sys.modules, "lucipy", None)  # import lucipy raises ImportError
    with pytest.raises(InputError, match=r"pip install 'patchgen\[lucidac\]'"):
        lucipy_module()


def test_an_existing_file_is_not_replaced(tmp_path):
    pytest.importorskip("lucipy", reason="lucipy (pip install 'patchgen[lucidac]') builds the configuration")
    (tmp_path / "lucidac-config.json").write_text("mine\n")
    r = run_patchgen("export", "bench-recommended", "--machine", "lucidac", "-o", tmp_path)
    assert r.returncode == 2 and "lucidac-config.json" in r.stderr
    assert (tmp_path / "lucidac-config.json").read_text() == "mine\n"
