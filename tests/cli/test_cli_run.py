"""The in-process runner (tests/cli_run.py) reports what a subprocess would: exit status, stdout,
stderr, and a warning as text on stderr, so that "no warning text" checks keep their meaning."""

import warnings

import patchgen.cli.design as design_cmd
from tests.cli_run import run_patchgen


def test_exit_status_and_streams_match_a_subprocess():
    ok = run_patchgen("design", "thesis-case1")
    assert ok.returncode == 0 and "-249.4119" in ok.stdout and ok.stderr == ""
    bad = run_patchgen("design", "designs/nope.toml")
    assert bad.returncode == 2 and bad.stdout == "" and "no such file" in bad.stderr


def test_a_warning_lands_on_stderr(monkeypatch):
    def warn(*_):
        warnings.warn("overflow encountered in matmul", RuntimeWarning, stacklevel=1)

    monkeypatch.setattr(design_cmd, "print_design", warn)
    r = run_patchgen("design", "thesis-case1")
    assert r.returncode == 0 and "RuntimeWarning: overflow encountered in matmul" in r.stderr
