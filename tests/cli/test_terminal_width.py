"""Every command's terminal output at 80 columns, piped (rich reads COLUMNS) and as a terminal
(TTY_COMPATIBLE: the same width, with colour): no line longer than 80, no value cut ("…"), no
signed zero; recommend and sweep a screen or less per candidate or row, their long lists summed up."""

from __future__ import annotations

import csv
import re
import shutil

import pytest

from tests.cli_run import run_patchgen

pytestmark = pytest.mark.heavy(60)  # seconds, roughly: see tests/conftest.py

WIDTH = 80
SCREEN = 24  # lines
PIPED = {"COLUMNS": str(WIDTH)}
TERMINAL = {"COLUMNS": str(WIDTH), "TTY_COMPATIBLE": "1"}
ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
SIGNED_ZERO = re.compile(r"(?<![\w.])[-+−]0(?:\.0*)?(?![\d.])")


def _run(*args, env=PIPED, cwd=None, status=0) -> list[str]:
    r = run_patchgen(*args, env=env, **({"cwd": cwd} if cwd else {}))
    assert r.returncode == status, r.stderr
    return ANSI.sub("", r.stdout).splitlines()


def _fits(lines: list[str]) -> None:
    long = [x for x in lines if len(x) > WIDTH]
    cut = [x for x in lines if "…" in x]
    zeros = [x for x in lines if SIGNED_ZERO.search(x)]
    assert (long, cut, zeros) == ([], [], []), "\n".join(lines)


@pytest.fixture(params=[PIPED, TERMINAL], ids=["piped", "terminal"])
def env(request):
    return request.param


@pytest.mark.parametrize("spec", ["thesis-ch5", "bench-lqg", "quanser-ip02"])
def test_patch(tmp_path, env, spec):
    lines = _run("patch", spec, "-o", "p", "--no-predict", env=env, cwd=tmp_path)
    _fits(lines)
    # the thesis's pot below the dial's resolution, whole: coefficient and error
    if spec == "thesis-ch5":
        p5 = next(x for x in lines if x.startswith("P5 "))
        assert "5.49" in p5 and "e-07" in p5 and "%" in p5


@pytest.mark.parametrize("spec", ["thesis-ch5", "thesis-case1", "bench-lqg", "bench-recommended", "quanser-ip02"])
def test_design(env, spec):
    _fits(_run("design", spec, env=env))


def test_check_with_faults(tmp_path, env):
    _run("patch", "bench-lqg", "-o", "p", "--no-predict", cwd=tmp_path)
    rows = list(csv.DictReader((tmp_path / "p" / "static-check.csv").open()))
    wrong = next(i for i, r in enumerate(rows) if abs(float(r["expected_V"])) > 1.0)
    for i, r in enumerate(rows):  # one reading well away from 0 V read with the wrong sign
        r["measured_V"] = f"{float(r['expected_V']) * (-1 if i == wrong else 1):.4f}"
    with (tmp_path / "filled.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    lines = _run("check", "bench-lqg", "--readings", "filled.csv", env=env, cwd=tmp_path, status=1)
    _fits(lines)
    assert any("Likeliest faults" in x for x in lines)


def test_simulate(tmp_path, env):
    _fits(_run("simulate", "thesis-ch5", "--scenario", "offset-10deg", "--runs", "4", "-o", "s", env=env,
               cwd=tmp_path))
    _fits(_run("simulate", "bench-recommended", "--scenario", "offset-10deg", "--bench", "uw-1991-uncertain",
               "--bench-spread", "--runs", "4", "--corner-runs", "1", "-o", "c", env=env, cwd=tmp_path))


@pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice is not installed")
def test_spice(tmp_path):
    _fits(_run("spice", "thesis-ch5", "--scenario", "offset-10deg", "--ideal", "-o", "x", cwd=tmp_path))


def _blocks(lines: list[str], starts: re.Pattern) -> list[list[str]]:
    """The rows of a table: each from a line ``starts`` matches, with the indented lines under it."""
    out: list[list[str]] = []
    current = None
    for x in lines:
        if starts.match(x):
            current = [x]
            out.append(current)
        elif current is not None and x.strip() and x.startswith(" "):
            current.append(x)
        else:
            current = None
    return out


def test_sweep_is_a_line_or_two_a_row(env):
    lines = _run("sweep", "bench-lqg", "--workers", "1", env=env)
    _fits(lines)
    cases = re.compile(r"^(nominal|all [+-]|[A-Za-z_]+ [+-]\d+%) ")
    rows = _blocks(lines, cases)
    assert len(rows) == 3 * 12  # three tables, twelve plants each
    assert max(len(b) for b in rows) <= 3
    assert len(lines) <= SCREEN * 12  # a screen a row at most, all tables together
    assert any("more" in x for x in lines)  # bench-lqg's 23 pots summed up past the four that move most


def test_recommend_is_a_screen_a_candidate_and_one_line_a_refusal(tmp_path):
    lines = _run("recommend", "bench-recommended", "--runs", "8", "-o", "r", cwd=tmp_path)
    _fits(lines)
    ranked = _blocks(lines, re.compile(r"^ ?\d+  "))
    assert ranked and max(len(b) for b in ranked) <= SCREEN
    text = "\n".join(lines)
    assert "4 candidates do not fit: the patch needs more pots than the Comdyna GP-6 x2 (slaved) has (16)" in " ".join(
        text.split())
    assert text.count("has 16 amplifiers") == 0  # the allocator's own sentence, once a candidate, is gone
    assert len(lines) <= 60


def test_recommend_with_variants_counts_the_rest(tmp_path):
    lines = _run("recommend", "thesis-ch5", "--runs", "8", "-o", "r", cwd=tmp_path)
    _fits(lines)
    ranked = _blocks(lines, re.compile(r"^ ?\d+  "))
    assert len(ranked) <= 12 and max(len(b) for b in ranked) <= SCREEN
    assert any(re.match(r"\d+ more ranked below", x) for x in lines)


def test_recommend_over_a_benchs_ranges(tmp_path):
    lines = _run("recommend", "bench-recommended", "--bench", "uw-1991-uncertain", "--runs", "8", "-o", "r",
                 cwd=tmp_path)
    _fits(lines)
    assert any("worst corner:" in x for x in lines)


def test_swingup_compared(tmp_path):
    lines = _run("swingup", "bench-recommended", "--compare", "-o", "s", cwd=tmp_path)
    _fits(lines)
    assert any(x.startswith("supervisory ") for x in lines)


def test_bench_test_identify_and_examples(tmp_path, env):
    _fits(_run("bench-test", "bench-recommended", "-o", "rec", env=env, cwd=tmp_path))
    _fits(_run("identify", "rec", "-o", "id", env=env, cwd=tmp_path))
    _fits(_run("examples", "ex", env=env, cwd=tmp_path))
