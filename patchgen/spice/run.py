"""Running a SPICE deck in ngspice (batch mode, as a subprocess) and reading its wrdata table back.

ngspice writes into a work directory of its own (the deck, its noise table, ``patch.data`` and
``ngspice.log``); the command copies what the user asked for through patchgen's all-or-nothing
writer.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from patchgen.spice.deck import CONTROL_NODE, DATA_NAME, DECK_NAME, FORCE_NODE, INSTALL_HINT, SpiceDeck
from patchgen.spice.plant import ALL_STATE_NODES


class NgspiceMissing(RuntimeError):
    """ngspice is not on the PATH: the deck can be written but not run."""

    exit_status = 3

    def __init__(self) -> None:
        super().__init__(f"ngspice not found on the PATH: {INSTALL_HINT}")


class NgspiceError(RuntimeError):
    """ngspice ran but failed (non-zero exit, an error in its output, or no data written)."""

    exit_status = 4


@dataclass
class SpiceResult:
    """Time histories from ngspice: ``t`` (s) and ``signals`` by name.

    Names: the plant states (``s``, ``theta``, ``s_dot``, ``theta_dot``; SI units), ``u_c`` (V),
    ``force`` (N) and every amplifier id (its output, V).
    """

    t: np.ndarray
    signals: dict[str, np.ndarray]
    run_time_s: float = 0.0
    log: str = ""


def ngspice_path() -> str:
    """Path of the ngspice executable; NgspiceMissing if it is not on the PATH."""
    path = shutil.which("ngspice")
    if path is None:
        raise NgspiceMissing()
    return path


def run_ngspice(deck: SpiceDeck | str, workdir: str | Path, timeout_s: float = 600.0) -> SpiceResult:
    """Write ``deck`` into workdir (patch.cir and its files), run ``ngspice -b`` there and read its
    wrdata table.

    The deck must write ``patch.data`` (as spice_deck's does). Raises NgspiceMissing without
    ngspice, NgspiceError if ngspice fails or reports an error.
    """
    exe = ngspice_path()
    work = Path(workdir)
    (deck if isinstance(deck, SpiceDeck) else SpiceDeck(deck)).write(work)
    data = work / DATA_NAME
    data.unlink(missing_ok=True)
    start = time.perf_counter()
    try:
        proc = subprocess.run([exe, "-b", DECK_NAME], cwd=work, capture_output=True, text=True,
                              timeout=timeout_s)
    except subprocess.TimeoutExpired:
        raise NgspiceError(f"ngspice did not finish within {timeout_s} s ({work / DECK_NAME})") from None
    elapsed = time.perf_counter() - start
    log = proc.stdout + proc.stderr
    (work / "ngspice.log").write_text(log)
    problems = [ln.strip() for ln in log.splitlines()
                if re.search(r"\berror\b|aborted|timestep too small|singular matrix|no convergence",
                             ln, re.IGNORECASE)]
    if proc.returncode != 0 or problems or not data.exists():
        first = problems[0] if problems else (log.strip().splitlines() or ["no output"])[-1]
        raise NgspiceError(f"ngspice failed on {work / DECK_NAME} (exit {proc.returncode}): {first}; "
                           f"full log in {work / 'ngspice.log'}")
    result = read_wrdata(data)
    result.run_time_s = elapsed
    result.log = log
    return result


def read_wrdata(path: str | Path, names: Sequence[tuple[str, str]] | None = None) -> SpiceResult:
    """Parse a wrdata table written with wr_singlescale and wr_vecnames, streaming from the file
    (no copy of its text is held: it may be hundreds of megabytes).

    Parameters
    ----------
    path : str or Path
        The table: a header of vector names, then a row per time point.
    names : sequence of (str, str), optional
        (signal name, ngspice vector) pairs to map the columns exactly; otherwise v(x_s) -> s,
        v(u_c) -> u_c, v(a6_out) -> A6 (upper case amplifier ids, as ngspice lower-cases node
        names).

    Returns
    -------
    SpiceResult
        Time and every column by signal name.
    """
    with open(path) as f:
        header = f.readline().split()
        table = np.loadtxt(f, ndmin=2)
    if table.shape[1] != len(header):
        raise NgspiceError(f"{path}: {table.shape[1]} columns for {len(header)} names")
    by_vec = {(v.lower()): k for k, v in names} if names else {}
    state_of = {f"v({node})": k for k, node in ALL_STATE_NODES.items()}
    signals: dict[str, np.ndarray] = {}
    for i, col in enumerate(header[1:], start=1):
        key = col.lower()
        if key in by_vec:
            name = by_vec[key]
        elif key in state_of:
            name = state_of[key]
        elif key == f"v({CONTROL_NODE})":
            name = "u_c"
        elif key == f"v({FORCE_NODE})":
            name = "force"
        elif key.startswith("v(") and key.endswith("_out)"):
            name = key[2:-5].upper()
        else:
            name = key
        signals[name] = table[:, i]
    return SpiceResult(t=table[:, 0], signals=signals)
