"""A recording of one standard bench test: a CSV file whose first line names the test and whose
header names every column with its unit, read and checked into arrays.

::

    # test = actuator_step
    # cart held against a force gauge     (further comment lines are kept as notes)
    t_s, u_c_V, force_N
    0.000, 0.0, 0.013
    ...

A column is ``<quantity>_<unit>``: t (s), u_c (V), force (N), s (V read on the pot, counts read
on an encoder, or m set by hand), theta (V, counts, or rad set by hand), s_dot (V, the tachometer
or a filtered velocity), out (V, an amplifier's output). An encoder's column (``s_counts``,
``theta_counts``) stands where a test takes the pot's (``s_V``, ``theta_V``) in the tests that
read positions (ENCODER_TESTS); the bench profile's counts turn it into SI units. Every test
takes the columns in ``TESTS``; a column of a known quantity that a test does not take is left
aside, an unknown quantity or a known one in another unit is an error. The time column rises by
one sample interval (within ``CLOCK_TOLERANCE``) from line to line. docs/identify.md says what to
record for each test.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from patchgen.identify.cells import (
    MIN_SAMPLE_INTERVAL_S,
    flat_top,
    not_plain,
    plain_number,
    read_plain,
    signal_problem,
    unit_problem,
    whole_counts,
)
from patchgen.inputs.errors import InputError
from patchgen.inputs.inputfile import decode_text, read_bytes
from patchgen.plant.plant_model import PLANT_MODELS

MAX_RECORDING_BYTES = 64 << 20  # 64 MiB: ten minutes of four channels at 2 kHz is some 40 MB of text
CLOCK_TOLERANCE = 0.01  # a sample interval may differ from the median by 1 %: a recorder's clock, not a gap
COUNTS = "counts"  # an encoder's unit: whole counts, turned into SI units by the bench profile's
ENCODER_TESTS = ("calibration", "coast_down", "free_swing", "motor_step", "arm_coast")  # where a count stands
# for a pot's volts


def _measured(q: str) -> tuple[tuple[str, ...], str]:
    """The units a measured quantity (of any plant) may be recorded in, and what it is: a position
    on its sensor (V) or set by hand (SI); a rate on its sensor alone."""
    pm = next(pm for pm in PLANT_MODELS.values() if q in pm.measurable)
    what, unit = next(st.what for st in pm.states if st.name == q), pm.units[q]
    if q in pm.rate_of:
        return ("V", COUNTS, unit), (f"{what}: its sensor's voltage (V), an encoder's whole counts ({COUNTS}) "
                                     f"or a value set by hand ({unit})")
    return ("V",), f"{what}: its sensor's voltage"


QUANTITIES = {  # quantity -> the units it may be recorded in, and what it is
    "t": (("s",), "time"),
    "u_c": (("V",), "the actuator's command voltage"),
    "force": (("N",), "the force on the cart read on a force gauge"),
    "V_m": (("V",), "the motor's voltage, at its terminals"),
    **{q: _measured(q) for pm in PLANT_MODELS.values() for q in pm.measurable},
    "out": (("V",), "an amplifier's output"),
}


@dataclass(frozen=True)
class TestKind:
    """What one standard test records: its columns (name_unit), the fewest samples it needs and
    what it identifies. ``any_of`` are columns of which at least one is needed."""

    name: str
    required: tuple[str, ...]
    optional: tuple[str, ...] = ()
    any_of: tuple[str, ...] = ()
    min_samples: int = 200
    identifies: str = ""
    max_dt: float = 0.1  # s: ten samples a second at least (a lag of 0.2 s, a swing of 1.3 s)

    @property
    def columns(self) -> tuple[str, ...]:
        """Every column the test takes."""
        return self.required + self.optional + self.any_of


TESTS = {t.name: t for t in (
    TestKind("calibration", (), optional=("s_m", "s_V", "theta_rad", "theta_V", "alpha_rad", "alpha_V"), min_samples=3,
             identifies="sensor constants (V/m, V/rad) from positions and angles set by hand"),
    TestKind("actuator_step", ("t_s", "u_c_V", "force_N"), min_samples=200,
             identifies="K_U, the lag tau, a zero at the origin or not, a second-order term or not"),
    TestKind("actuator_ramp", ("t_s", "u_c_V", "force_N"), min_samples=200,
             identifies="the dead zone and any hysteresis"),
    TestKind("coast_down", ("t_s", "s_V", "s_dot_V"), min_samples=100,
             identifies="b_VF / (M + m), Coulomb friction when the data show it, the tachometer constant"),
    TestKind("free_swing", ("t_s", "theta_V"), min_samples=500,
             identifies="the effective length l from the period, c from the decay"),
    TestKind("motor_step", ("t_s", "V_m_V", "alpha_V"), min_samples=200,
             identifies="a rotary arm's decay and drive (1/s, rad/s^2 per V), the pendulum fixed to it"),
    TestKind("arm_coast", ("t_s", "alpha_V"), min_samples=100,
             identifies="a rotary arm's decay with the amplifier off (D_r / J_0)"),
    TestKind("quiet", ("t_s",), any_of=("s_V", "theta_V", "s_dot_V", "alpha_V"), min_samples=1000,
             identifies="each sensor's noise level and bandwidth"),
    TestKind("integrator_drift", ("t_s", "out_V"), min_samples=100,
             identifies="an integrator's drift rate", max_dt=10.0),
)}

LINE_BREAK = re.compile(r"\r\n|\r|\n")  # LF, CRLF or CR; no other character ends a line
_COMMENT = re.compile(r"^#\s*([A-Za-z_][A-Za-z0-9_ -]*?)\s*=\s*(.*?)\s*$")


@dataclass(frozen=True)
class Recording:
    """One recording, checked: its test, its columns (name_unit -> samples) and its notes."""

    source: str
    test: str
    columns: dict[str, np.ndarray]
    notes: dict[str, str] = field(default_factory=dict)
    ignored: tuple[str, ...] = ()

    @property
    def dt(self) -> float:
        """The sample interval (s): the median step of ``t_s``."""
        return float(np.median(np.diff(self.columns["t_s"])))

    def error(self, column: str, message: str) -> InputError:
        """An InputError naming this recording's file and ``column``."""
        return InputError(self.source, column, message)


def read_csv_text(path: str | Path) -> str:
    """The text of a recording file: read as a spec is (a regular file, opened without blocking,
    at most MAX_RECORDING_BYTES, UTF-8 with or without a byte-order mark)."""
    data = read_bytes(path, limit=MAX_RECORDING_BYTES, kind="a CSV recording", too_large="record fewer samples")
    return decode_text(data, str(path), kind="a CSV recording")


def split_column(name: str) -> tuple[str, str] | None:
    """(quantity, unit) of a column name, the longest known quantity first; None if unknown."""
    for q in sorted(QUANTITIES, key=len, reverse=True):
        if name.startswith(q + "_") and len(name) > len(q) + 1:
            return q, name[len(q) + 1:]
    return None


def _header(source: str, names: list[str], kind: TestKind) -> tuple[list[str], list[str]]:
    """The header's columns checked against the test: (used, ignored)."""
    used, ignored = [], []
    for n in names:
        if not n:
            raise InputError(source, "header", "an empty column name (a stray comma?)")
        if names.count(n) > 1:
            raise InputError(source, n, "named twice in the header")
        parts = split_column(n)
        if parts is None:
            raise InputError(source, n, "unknown column: name it <quantity>_<unit>, the quantity one of "
                                        + ", ".join(QUANTITIES))
        q, unit = parts
        units, what = QUANTITIES[q]
        if unit not in units:
            wanted = [c for c in kind.columns if split_column(c)[0] == q]
            expect = " or ".join(wanted) if wanted else " or ".join(f"{q}_{u}" for u in units)
            raise InputError(source, n, f"unit {unit!r} is not one {q} is recorded in ({what}): "
                                        f"write {expect}")
        (used if _as_taken(n, kind) in kind.columns else ignored).append(n)
    taken = [_as_taken(n, kind) for n in names]
    if len(set(taken)) < len(taken):
        n = next(n for n in names if _as_taken(n, kind) != n and _as_taken(n, kind) in names)
        raise InputError(source, n, f"the position twice: {n} and {_as_taken(n, kind)} (record the encoder or "
                                    "the pot)")
    for n in kind.required:
        if n not in taken:
            raise InputError(source, n, f"missing column (the {kind.name} test records "
                                        f"{', '.join(kind.required + kind.any_of + kind.optional)})")
    if kind.any_of and not any(n in taken for n in kind.any_of):
        raise InputError(source, kind.any_of[0], f"missing column: the {kind.name} test records at least one "
                                                 f"of {', '.join(kind.any_of)}")
    return used, ignored


def _as_taken(name: str, kind: TestKind) -> str:
    """The column a test takes that ``name`` stands for: an encoder's count for the pot's voltage in
    ENCODER_TESTS (``s_counts`` for ``s_V``), else the name itself."""
    q, _, unit = name.rpartition("_")
    return f"{q}_V" if unit == COUNTS and kind.name in ENCODER_TESTS else name


def _header_line(source: str, names: list[str], line: str, number: int) -> None:
    """Refuse a header that is numbers (no header) or separated by other than commas."""
    if all(plain_number(n) is not None for n in names):
        raise InputError(source, "header", f"missing: line {number} is numbers ({line.strip()[:40]!r}); a line "
                                           "naming the columns comes first, e.g. t_s, u_c_V, force_N")
    for sep, what in (("\t", "tabs"), (";", "semicolons"), (" ", "spaces")):
        if len(names) == 1 and len(names[0].split(sep)) > 1:
            raise InputError(source, "header", f"columns separated by {what} ({line.strip()[:40]!r}): separate "
                                               "them by commas")


def parse_recording(text: str, source: str) -> Recording:
    """A recording from its text.

    Parameters
    ----------
    text : str
        The CSV text: ``# test = <name>`` first, other comment lines, the header, then numbers.
    source : str
        The file, named in errors.

    Returns
    -------
    Recording
        The checked recording (columns, sample count, clock, per-test pairs; not the excitation,
        which each test's fit checks).

    Raises
    ------
    InputError
        One line naming the file and the column (or line) at fault.
    """
    text = text.removeprefix("\ufeff")
    lines = LINE_BREAK.split(text) if "\r" in text else text.split("\n")
    notes: dict[str, str] = {}
    seen: dict[str, int] = {}
    i = 0
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("#")):
        m = _COMMENT.match(lines[i].strip())
        if m:
            key = m.group(1).strip()
            if key in seen:
                raise InputError(source, key, f"given twice (lines {seen[key]} and {i + 1}): write it once")
            seen[key] = i + 1
            notes[key] = m.group(2)
        i += 1
    test = notes.pop("test", None)
    if test is None:
        raise InputError(source, "test", "missing: the first line names the test, e.g. '# test = actuator_step' "
                                         f"(one of {', '.join(TESTS)})")
    if test not in TESTS:
        raise InputError(source, "test", f"unknown test {test!r} (one of {', '.join(TESTS)})")
    kind = TESTS[test]
    if i >= len(lines):
        raise InputError(source, "header", "missing: a line naming the columns, e.g. "
                                           + (", ".join(kind.required) or "s_m, s_V"))
    names = [n.strip(" \t") for n in lines[i].split(",")]
    _header_line(source, names, lines[i], i + 1)
    used, ignored = _header(source, names, kind)
    body = lines[i + 1:]
    while body and not body[-1]:
        body.pop()
    rows = list(zip(range(i + 2, i + 2 + len(body)), body))
    data = _plain_block(len(names), body)  # every line a row of numbers (the usual file) in one pass
    if data is None:  # else rows are the lines that are neither blank nor comments
        rows = [(k + 1, ln) for k, ln in enumerate(lines) if k > i and ln.strip() and not ln.lstrip().startswith("#")]
    if len(rows) < kind.min_samples:
        raise InputError(source, names[0], f"too few samples: {len(rows)}, the {test} test needs at least "
                                           f"{kind.min_samples}")
    data = _numbers(source, names, rows, data)
    columns = {n: data[:, names.index(n)].copy() for n in used}
    rec = Recording(source, test, columns, notes, tuple(ignored))
    _check_clock(rec)
    _check_pairs(rec)
    _check_signals(rec)
    return rec


MEASURED = ("force_N", "s_V", "theta_V", "s_dot_V", "out_V")  # read off the bench (not set by hand or commanded)


def _check_signals(rec: Recording) -> None:
    """Every column a fit uses holds a signal, and no measured channel of a time series is clipped."""
    for name, x in rec.columns.items():
        unit = split_column(name)[1]
        problem = signal_problem(unit, x) or (whole_counts(x) if unit == COUNTS else None)
        if problem:
            raise rec.error(name, problem)
        settles = rec.test == "coast_down" and name == "s_V"  # the cart comes to rest where it stopped
        top = flat_top(x, settles) if name in MEASURED and "t_s" in rec.columns else None
        if top:
            k, run, v = top
            t = rec.columns["t_s"]
            raise rec.error(name, f"clipped: held at exactly {v:.6g} for {run} samples from {t[k]:.4g} s, its "
                                  f"{'largest' if v == x.max() else 'smallest'} value (a recorder or amplifier at "
                                  "its limit): record within range")


def _numbers(source: str, names: list[str], rows: list[tuple[int, str]], data: np.ndarray | None = None
             ) -> np.ndarray:
    """The rows' cells as numbers, each plain decimal (see patchgen.identify.cells); ``data``
    when they have been read already."""
    if data is None:
        data = _plain_block(len(names), [ln for _, ln in rows])
    if data is None:
        data = _cell_by_cell(source, names, rows)
    for c, n in enumerate(names):
        parts = split_column(n)
        problem = unit_problem(parts[1], data[:, c]) if parts else None
        if problem:
            raise InputError(source, n, f"line {rows[problem[0]][0]}: {problem[1]}")
    return data


def _plain_block(ncols: int, lines: list[str]) -> np.ndarray | None:
    """All lines at once when each is exactly ncols plain numbers (one pass of
    patchgen.identify.cells.read_plain, which reads them too); None to look cell by cell."""
    block = "\n".join(lines)
    if not lines or not block.isascii():
        return None
    values = np.empty(len(lines) * ncols)
    status = read_plain(np.frombuffer(block.encode("ascii"), np.uint8), ncols, values)
    if status == 0:
        return None
    if status == 2:  # a number beyond the exact fast path: float reads them all
        values = np.array(block.replace("\n", ",").split(","), dtype=float)
    return values.reshape(len(lines), ncols)


def _cell_by_cell(source: str, names: list[str], rows: list[tuple[int, str]]) -> np.ndarray:
    """The rows' numbers, or the first line, column and cell that is not one."""
    data = np.empty((len(rows), len(names)))
    for r, (line, ln) in enumerate(rows):
        cells = ln.split(",")
        if len(cells) < len(names):
            raise InputError(source, names[len(cells)], f"line {line}: missing: the line holds {len(cells)} of the "
                                                        f"{len(names)} values the header names")
        if len(cells) > len(names):
            raise InputError(source, names[-1], f"line {line}: {len(cells)} values, the header names {len(names)} "
                                                f"(a value after {names[-1]}, the last column)")
        for c, cell in enumerate(cells):
            v = plain_number(cell)
            if v is None:
                shown = cell.strip(" \t")
                shown = shown if len(shown) <= 40 else shown[:37] + "..."
                raise InputError(source, names[c], f"line {line}: {shown!r} is not {not_plain(shown)}")
            data[r, c] = v
    return data


def _check_clock(rec: Recording) -> None:
    if "t_s" not in rec.columns:
        return
    t = rec.columns["t_s"]
    step = np.diff(t)
    if np.any(step <= 0):
        k = int(np.argmax(step <= 0))
        raise rec.error("t_s", f"does not rise at sample {k + 2} ({t[k]:g} s then {t[k + 1]:g} s)")
    dt = float(np.median(step))
    top = TESTS[rec.test].max_dt
    if not MIN_SAMPLE_INTERVAL_S <= dt <= top:
        raise rec.error("t_s", f"the sample interval is {dt:.3g} s, outside the {MIN_SAMPLE_INTERVAL_S:g} to "
                               f"{top:g} s a {rec.test} recording takes: is the time in seconds?")
    off = np.abs(step - dt) > CLOCK_TOLERANCE * dt
    if np.any(off):
        k = int(np.argmax(off))
        raise rec.error("t_s", f"the sample interval is {dt:g} s but {step[k]:g} s at {t[k]:g} s: "
                               "record at a steady rate (a gap splits the recording in two files)")


def _check_pairs(rec: Recording) -> None:
    if rec.test != "calibration":
        return
    pairs = [(a, b if b in rec.columns or f"{a.split('_')[0]}_{COUNTS}" not in rec.columns
              else f"{a.split('_')[0]}_{COUNTS}") for a, b in (("s_m", "s_V"), ("theta_rad", "theta_V"))]
    if not any(a in rec.columns or b in rec.columns for a, b in pairs):
        raise rec.error("s_m", "missing columns: a calibration records s_m with s_V (or s_counts), theta_rad with "
                               "theta_V (or theta_counts), or both pairs")
    for a, b in pairs:
        if (a in rec.columns) != (b in rec.columns):
            have, lack = (a, b) if a in rec.columns else (b, a)
            raise rec.error(lack, f"missing column: {have} is calibrated against {lack}")


def read_recording(path: str | Path) -> Recording:
    """Read and check a CSV recording (see the module docstring and docs/identify.md)."""
    return parse_recording(read_csv_text(path), str(path))


def expand(paths: list[str]) -> list[str]:
    """The files to read: a folder stands for its .csv and .toml files, in name order.

    Raises
    ------
    InputError
        A path that does not exist, or a folder with no recording in it.
    """
    out: list[str] = []
    for p in paths:
        path = Path(p)
        if path.is_dir():
            found = sorted(str(f) for f in path.iterdir() if f.suffix in (".csv", ".toml") and f.is_file())
            if not found:
                raise InputError(p, "", "a folder with no recording (.csv) or test figures (.toml) in it")
            out.extend(found)
        elif not path.exists():
            raise InputError(p, "", "no such file or folder")
        else:
            out.append(str(path))
    return out
