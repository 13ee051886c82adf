"""patchgen's command line run inside the test process: the exit status, stdout and stderr that
`python -m patchgen` would give, without a fresh interpreter's start-up (about a second of
imports each). Warnings are written to stderr as the interpreter would, so a test that finds no
warning text there still means it. Tests of what only a fresh process shows (determinism across
hash seeds, imports, the environment) keep a subprocess."""

from __future__ import annotations

import contextlib
import io
import os
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

from patchgen.cli import main
from tests.conftest import ROOT


@dataclass(frozen=True)
class Ran:
    """What a finished command left: as subprocess.CompletedProcess names it."""

    returncode: int
    stdout: str
    stderr: str


def run_patchgen(*args, cwd: Path | str = ROOT, env: dict[str, str] | None = None) -> Ran:
    """``patchgen *args`` in ``cwd``, with ``env`` added to the environment for the call."""
    out, err = io.StringIO(), io.StringIO()
    argv, here, saved = sys.argv, os.getcwd(), {k: os.environ.get(k) for k in (env or {})}
    sys.argv = ["patchgen", *map(str, args)]
    os.environ.update(env or {})
    try:
        os.chdir(cwd)
        with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stdout(out), \
                contextlib.redirect_stderr(err):
            warnings.simplefilter("always")
            try:
                main()
                code = 0
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    finally:
        os.chdir(here)
        sys.argv = argv
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    said = "".join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno, w.line) for w in caught)
    return Ran(code, out.getvalue(), err.getvalue() + said)
