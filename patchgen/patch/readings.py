"""Reading a filled static-check.csv: the technician's measured voltages, in the check's order.

The file is read as a spec is (patchgen.inputs.inputfile: a regular file only, no FIFO or device,
a size limit, UTF-8 with or without the byte-order mark spreadsheets write). Every row must be one
of the check's readings, each reading must be there, and each measured value a number of volts a
voltmeter on the machine can show; anything else is one InputError naming the file, the row and
the column.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from patchgen.inputs.errors import InputError
from patchgen.inputs.inputfile import decode_text, read_bytes
from patchgen.patch.static_check import CSV_COLUMNS, StaticCheck
from patchgen.profiles.machine import MachineProfile

# A static check has a row per amplifier per condition: under 10 kB for the shipped designs and
# under 1 MiB for any machine's; a spreadsheet may add columns of notes. Far below a memory problem.
MAX_READINGS_BYTES = 4 << 20
# A reading past this many times the machine's reference (or rails) is no voltage of the patch: a
# misread digit or a wrong unit (mV for V). It also keeps the chi-square of every fault finite.
READING_LIMIT = 10.0
REQUIRED = ("condition", "point", "measured_V")
_KIND = "a static-check CSV file"


def reading_limit_V(machine: MachineProfile) -> float:
    """The largest reading accepted, V: READING_LIMIT times the machine's reference or rails."""
    return READING_LIMIT * max(machine.reference_V, machine.imperfections.saturation_V)


def _rows(name: str, text: str) -> list[tuple[int, list[str]]]:
    """(line, cells) of every non-blank row, the header first."""
    rows, reader = [], csv.reader(io.StringIO(text, newline=""))
    start = 1
    try:
        for cells in reader:
            if any("\n" in c or "\r" in c for c in cells):
                raise InputError(name, f"row {start}", f"a quoted cell runs on to line {reader.line_num}: "
                                 "a quote mark (\") left open?")
            if any(c.strip() for c in cells):
                rows.append((start, [c.strip() for c in cells]))
            start = reader.line_num + 1
    except csv.Error as exc:
        what = (f"a cell longer than {csv.field_size_limit()} characters" if "field limit" in str(exc)
                else f"not CSV ({exc})")
        raise InputError(name, f"row {max(start, reader.line_num)}", f"{what}: not a static check") from None
    return rows


def _header(name: str, rows: list[tuple[int, list[str]]], check: StaticCheck) -> dict[str, int]:
    """Column name -> index, with the columns the readings need."""
    if not rows:
        raise InputError(name, "", "is empty: expected static-check.csv as patchgen patch wrote it, with the "
                         "measured_V column filled in")
    cells = rows[0][1]
    missing = [c for c in REQUIRED if c not in cells]
    if missing:
        if cells and cells[0] in {r.condition for r in check.readings}:
            problem = f"the first row is a reading: the header ({','.join(CSV_COLUMNS)}) is missing"
        elif len(cells) == 1 and any(d in cells[0] for d in ";\t"):
            problem = "its columns are not separated by commas: save it as CSV with commas and decimal points"
        else:
            problem = f"needs the columns {', '.join(CSV_COLUMNS)} (missing {', '.join(missing)})"
        raise InputError(name, "header", problem)
    seen: dict[str, int] = {}
    for i, c in enumerate(cells):
        if c in seen and c:
            raise InputError(name, "header", f"the column {c} appears twice (columns {seen[c] + 1} and {i + 1})")
        seen[c] = i
    return seen


def _decimal_comma(raw: str) -> bool:
    try:
        return "," in raw and math.isfinite(float(raw.replace(",", ".", 1)))
    except ValueError:
        return False


def _volts(name: str, where: str, raw: str, limit: float) -> float:
    if not raw:
        raise InputError(name, where, "empty: fill in the reading (the diagnosis needs every reading)")
    try:
        v = float(raw)
    except ValueError:
        hint = " with a decimal point, not a comma" if _decimal_comma(raw) else ""
        raise InputError(name, where, f"must be a number of volts{hint} (got {raw!r})") from None
    if not math.isfinite(v):
        raise InputError(name, where, f"must be a finite number (got {raw!r})")
    if abs(v) > limit:
        raise InputError(name, where, f"{v:g} V is beyond any voltage of the patch (the machine's outputs stay "
                         f"within +/-{limit / READING_LIMIT:g} V; at most +/-{limit:g} V is accepted): a misread "
                         "digit or a wrong unit?")
    return v


def load_readings(path: str | Path, check: StaticCheck, machine: MachineProfile) -> np.ndarray:
    """The measured voltages of a filled static-check.csv, in the check's reading order.

    Parameters
    ----------
    path : str or Path
        The filled file.
    check : StaticCheck
        The check it should be the sheet of.
    machine : MachineProfile
        The machine measured (its reference bounds the readings).

    Returns
    -------
    numpy.ndarray
        One finite voltage per reading.

    Raises
    ------
    InputError
        Naming the file, the row and the column: a file that cannot be read or is not CSV, a
        column missing, a row that is not one of the check's readings or has more cells than the
        header, a reading given twice with different values or not at all, an expected_V that is
        not the check's (the sheet of another patch), a measured value that is not a number of
        volts the machine can show.
    """
    name = str(path)
    data = read_bytes(path, limit=MAX_READINGS_BYTES, kind=_KIND, too_large="not a static check")
    rows = _rows(name, decode_text(data, name, _KIND))
    col = _header(name, rows, check)
    width = len(rows[0][1])
    index = {(r.condition, r.point): k for k, r in enumerate(check.readings)}
    measured = np.full(len(check.readings), np.nan)
    row_of: dict[int, int] = {}
    limit = reading_limit_V(machine)
    for n, cells in rows[1:]:
        if len(cells) > width:
            raise InputError(name, f"row {n}", f"has {len(cells)} cells, the header {width} (a comma as the "
                             "decimal separator? write 0.5, not 0,5)")
        cells = cells + [""] * (width - len(cells))
        key = (cells[col["condition"]], cells[col["point"]])
        if key not in index:
            raise InputError(name, f"row {n}", f"condition {key[0]!r}, point {key[1]!r} is not a reading of this "
                             "patch's static check")
        k = index[key]
        r = check.readings[k]
        if "expected_V" in col:
            _same_patch(name, n, cells[col["expected_V"]], r.expected_V, r.tolerance_V)
        v = _volts(name, f"row {n}: measured_V", cells[col["measured_V"]], limit)
        if k in row_of and v != measured[k]:
            raise InputError(name, f"row {n}: measured_V", f"condition {key[0]!r}, point {key[1]!r} is read twice, "
                             f"{measured[k]:g} V on row {row_of[k]} and {v:g} V here: keep the right one")
        row_of.setdefault(k, n)
        measured[k] = v
    if np.isnan(measured).any():
        gone = np.flatnonzero(np.isnan(measured))
        r = check.readings[int(gone[0])]
        more = f" (and {len(gone) - 1} more)" if len(gone) > 1 else ""
        raise InputError(name, "measured_V", f"no reading for condition {r.condition!r}, point {r.point!r}{more}")
    return measured


def _same_patch(name: str, n: int, raw: str, expected: float, tol: float) -> None:
    """The sheet's expected value is the check's (within the reading's tolerance)."""
    try:
        v = float(raw)
    except ValueError:
        return  # the column is patchgen's own; a spreadsheet's edit of it is not a reading
    if math.isfinite(v) and abs(v - expected) > tol:
        raise InputError(name, f"row {n}: expected_V", f"{raw} V, but this patch expects {expected:.4f} V here: "
                         "the sheet is from another patch (or an older version of it); patch again and measure "
                         "with the new sheet")
