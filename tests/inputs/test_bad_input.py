"""Every kind of bad input gives one line on stderr naming the file (or option) and the field,
exit status 2, no traceback, no numpy warning, and no output folder created or changed.

The corpus (tests/badinput_*.py) runs in-process through ``patchgen.cli.main``; a few cases go
through ``python -m patchgen`` to prove the real entry point behaves the same.
"""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from patchgen.cli import main
from tests.conftest import ROOT

from .badinput_cases import DIRECTORY, FIFO, LOOP, Case, spec_cases
from .badinput_check import check_cases
from .badinput_identify import identify_cases
from .badinput_inputs import profile_cases, scenario_cases
from .badinput_options import file_cases, option_cases
from .badinput_recordings import recording_cases

pytestmark = pytest.mark.heavy(12)  # seconds, roughly: see tests/conftest.py

CASES = (spec_cases() + scenario_cases() + profile_cases() + file_cases() + option_cases() + recording_cases()
         + identify_cases() + check_cases())


def _lay_out(case: Case, tmp: Path) -> None:
    for name, data in case.files.items():
        p = tmp / name.replace("@TMP@/", "")
        p.parent.mkdir(parents=True, exist_ok=True)
        if data == FIFO:
            os.mkfifo(p)
        elif data == DIRECTORY:
            p.mkdir()
        elif data == LOOP:
            os.symlink(p.name, p)
        else:
            p.write_bytes(data.replace("@TMP@", str(tmp)).encode() if isinstance(data, str) else data)
    for name in case.existing:
        p = tmp / "out" / name
        if name.endswith("/"):
            p.mkdir(parents=True)
        else:
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(b"written before")


def _snapshot(path: str) -> dict | None:
    """What is in the output folder (None when there is none)."""
    p = Path(path) if path else None
    if p is None or not os.path.lexists(p) or len(path) > 1000 or path.startswith(("/proc", "/sys", "/dev")):
        return None
    if not p.is_dir():
        return {".": p.read_bytes()}
    return {str(q.relative_to(p)): (q.read_bytes() if q.is_file() else None) for q in sorted(p.rglob("*"))}


def run_in_process(argv: list[str], capsys) -> tuple[int, str]:
    """patchgen.cli.main with argv; its exit status and stderr."""
    old = sys.argv
    sys.argv = ["patchgen", *argv]
    try:
        main()
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    finally:
        sys.argv = old
    return code, capsys.readouterr().err


def _expected(case: Case, tmp: Path) -> tuple[str, str]:
    return case.source.replace("@TMP@", str(tmp)), case.field


def check_line(case: Case, code: int, err: str, tmp: Path) -> None:
    source, field = _expected(case, tmp)
    assert "Traceback" not in err, err
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    if case.usage:
        assert line.startswith("patchgen ") and source in line, line
    else:
        prefix = f"patchgen: {source}: " + (f"{field}: " if field else "")
        assert line.startswith(prefix), f"{line!r} should start with {prefix!r}"


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_bad_input(case: Case, tmp_path: Path, capsys) -> None:
    _lay_out(case, tmp_path)
    argv = [a.replace("@TMP@", str(tmp_path)) for a in case.argv]
    out = case.out.replace("@TMP@", str(tmp_path))
    before = _snapshot(out)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code, err = run_in_process(argv, capsys)
    check_line(case, code, err, tmp_path)
    assert _snapshot(out) == before, "the output folder changed"
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]


def test_corpus_size() -> None:
    assert len(CASES) >= 500
    assert len({c.id for c in CASES}) == len(CASES)


ENTRY = ("file-spec-latin1-comment", "kind-spec-fifo", "option-patch-out-proc", "spec-lag-actuator.K_U-inf",
         "scenario-initial.theta_deg-nan")


def test_real_entry_point(tmp_path: Path) -> None:
    """A few cases through ``python -m patchgen``, side by side (a FIFO spec must not block)."""
    runs = []
    for case in (c for c in CASES if c.id in ENTRY):
        tmp = tmp_path / case.id
        tmp.mkdir()
        _lay_out(case, tmp)
        argv = [a.replace("@TMP@", str(tmp)) for a in case.argv]
        runs.append((case, tmp, subprocess.Popen([sys.executable, "-m", "patchgen", *argv], cwd=ROOT, text=True,
                                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE)))
    assert len(runs) == len(ENTRY)
    for case, tmp, proc in runs:
        _, err = proc.communicate(timeout=120)
        check_line(case, proc.returncode, err, tmp)
        assert not (tmp / "out").exists()
