"""The bad-input corpus, continued: recordings that look like numbers but are not plain decimal,
values no bench shows, clipped channels, a recording given twice, repeated header keys, headers
that are not, and estimates no profile takes (each named by its recording and column).

The good recordings are bench-test's (badinput_recordings.good_files); each case breaks one.
"""

from __future__ import annotations

import numpy as np

from .badinput_cases import DIRECTORY, FIFO, ROOT, SPEC, Case
from .badinput_options import GOOD_SCENARIO, GOOD_SPEC
from .badinput_recordings import REC, _case, _rows, _with_column, _write, good_files


def _cell(text: str, line: int, column: int, value: str) -> str:
    """The recording with one cell (line counted from 1, column from 0) replaced by ``value``."""
    lines = text.splitlines()
    cells = lines[line - 1].split(",")
    cells[column] = " " + value if column else value
    lines[line - 1] = ",".join(cells)
    return "\n".join(lines) + "\n"


def _scaled(text: str, column: str, k: float, offset: float = 0.0) -> str:
    return _with_column(text, column, lambda t, x: x * k + offset)


def _clipped(text: str, column: str, lo: float, hi: float) -> str:
    return _with_column(text, column, lambda t, x: np.clip(x, lo, hi))


def _number_cases(g: dict[str, str]) -> list[Case]:
    step, quiet, cal = g["actuator-step.csv"], g["quiet.csv"], g["calibration.csv"]
    return [
        _case("calibration-mark-underscore", "calibration.csv", cal.replace("-0.3488, -1.745961", "-0_3488, -1.745961"),
              "s_m"),
        _case("calibration-mark-hex", "calibration.csv", _cell(cal, 5, 0, "-0x1p-2"), "s_m"),
        _case("cell-NaN-word", "quiet.csv", _cell(quiet, 40, 2, "NaN"), "theta_V"),
        _case("cell-infinity-word", "quiet.csv", _cell(quiet, 40, 3, "-Infinity"), "s_dot_V"),
        _case("cell-fullwidth-digit", "actuator-step.csv", _cell(step, 30, 2, "0.\uff15"), "force_N"),
        _case("cell-no-break-space", "actuator-step.csv", _cell(step, 30, 2, "0.5\u00a01"), "force_N"),
        _case("cell-empty", "actuator-step.csv", _cell(step, 30, 1, ""), "u_c_V"),
        _case("cell-comma-decimal", "actuator-step.csv", _cell(step, 30, 2, "0,5"), "force_N"),
        _case("line-short", "actuator-step.csv", step.replace("\n0.1, ", "\n0.1\n", 1), "u_c_V"),
        _case("line-long", "quiet.csv", _cell(quiet, 50, 3, "0.001, 0.002"), "s_dot_V"),
        _case("masses-hex", "masses.toml", g["masses.toml"].replace("M_kg = 3.552", "M_kg = 0x4"), "M_kg"),
        _case("masses-underscore", "masses.toml", g["masses.toml"].replace("M_kg = 3.552", "M_kg = 3_552e-3"), "M_kg"),
        _case("incline-inf", "incline.toml", g["incline.toml"].replace("time_s = ", "time_s = inf #"), "time_s"),
    ]


def _range_cases(g: dict[str, str]) -> list[Case]:
    step, swing, coast = g["actuator-step.csv"], g["free-swing.csv"], g["coast-down-1.csv"]
    quiet, cal, drift = g["quiet.csv"], g["calibration.csv"], g["integrator-drift.csv"]
    return [
        _case("step-force-near-1e300", "actuator-step.csv", _scaled(step, "force_N", 1e299), "force_N"),
        _case("step-command-near-1e300", "actuator-step.csv", _scaled(step, "u_c_V", 1e299), "u_c_V"),
        _case("step-force-squares-overflow", "actuator-step.csv", _scaled(step, "force_N", 1e160), "force_N"),
        _case("coast-squares-overflow", "coast-down-1.csv", _scaled(coast, "s_V", 1e200), "s_V", whole_folder=True),
        _case("quiet-tiny", "quiet.csv", _scaled(quiet, "theta_V", 1e-300), "theta_V"),
        _case("drift-subnormal", "integrator-drift.csv", _scaled(drift, "out_V", 1e-310), "out_V"),
        _case("calibration-cm", "calibration.csv", _scaled(cal, "s_m", 100), "s_m"),
        _case("calibration-degrees", "calibration.csv", _scaled(cal, "theta_rad", 57.2958), "theta_rad"),
        _case("calibration-voltage-constant", "calibration.csv", _scaled(cal, "s_V", 0, 0.3), "s_V",
              whole_folder=True),
        _case("time-milliseconds", "free-swing.csv", _scaled(swing, "t_s", 1000), "t_s"),
        _case("time-picoseconds", "quiet.csv", _scaled(quiet, "t_s", 1e-12), "t_s"),
        _case("time-epoch", "coast-down-1.csv", _scaled(coast, "t_s", 1, 1.7e9), "t_s"),
        _case("time-tenfold-swing", "free-swing.csv", _scaled(swing, "t_s", 10), "theta_V"),
        _case("force-hundredfold", "actuator-step.csv", _scaled(step, "force_N", 100), "force_N"),
        _case("command-reversed", "actuator-ramp.csv", _scaled(g["actuator-ramp.csv"], "u_c_V", -1), "force_N"),
        _case("calibration-reversed", "calibration.csv", _scaled(cal, "s_m", -1), "s_V"),
        _case("coast-pot-reversed", "coast-down-2.csv", _scaled(g["coast-down-2.csv"], "s_V", -1), "s_dot_V",
              whole_folder=True),
    ]


def _clip_cases(g: dict[str, str]) -> list[Case]:
    return [
        _case("free-swing-clipped", "free-swing.csv", _clipped(g["free-swing.csv"], "theta_V", -0.5, 0.5), "theta_V",
              whole_folder=True),
        _case("quiet-clipped", "quiet.csv", _clipped(g["quiet.csv"], "s_V", -0.003, 0.003), "s_V"),
        _case("step-force-clipped", "actuator-step.csv", _clipped(g["actuator-step.csv"], "force_N", -9, 9), "force_N"),
        _case("coast-tach-clipped", "coast-down-1.csv", _clipped(g["coast-down-1.csv"], "s_dot_V", -0.2, 0.2),
              "s_dot_V"),
        _case("drift-clipped", "integrator-drift.csv", _clipped(g["integrator-drift.csv"], "out_V", -1e-4, 1e-4),
              "out_V"),
        _case("calibration-pot-clipped", "calibration.csv", _clipped(g["calibration.csv"], "s_V", -1.6, 1.6), "s_V"),
    ]


def _file_cases(g: dict[str, str]) -> list[Case]:
    step, quiet = g["actuator-step.csv"], g["quiet.csv"]
    notes, names, rows = _rows(step)
    first = step.splitlines()[0]
    ident = lambda *paths: ("identify", *paths, "-o", "@TMP@/out")  # noqa: E731
    folder = {f"rec/{k}": v for k, v in g.items()}
    return [
        _case("test-twice", "actuator-step.csv", step.replace(first, first + "\n# test = actuator_ramp", 1), "test"),
        _case("note-key-twice", "quiet.csv", quiet.replace("\n", "\n# gain = 1\n# gain = 2\n", 1), "gain"),
        _case("header-tabs", "actuator-step.csv", step.replace("t_s, u_c_V, force_N", "t_s\tu_c_V\tforce_N"), "header"),
        _case("header-missing", "actuator-step.csv", step.replace("t_s, u_c_V, force_N\n", ""), "header"),
        _case("copy-in-folder", "step-again.csv", step, "test", whole_folder=True),
        _case("incline-twice", "slide-again.toml", g["incline.toml"], "test", whole_folder=True),
        Case("recording-same-file-two-paths", ident(f"{REC}/actuator-step.csv", f"{REC}/../rec/actuator-step.csv"),
             f"{REC}/../rec/actuator-step.csv", "test", folder),
        Case("recording-folder-and-its-file", ident(REC, f"{REC}/quiet.csv"), f"{REC}/quiet.csv", "test", folder),
        Case("recording-fifo", ident(f"{REC}/step.csv"), f"{REC}/step.csv", "", {"rec/step.csv": FIFO}),
        Case("recording-directory-named-csv", ident(f"{REC}/x.csv"), f"{REC}/x.csv", "",
             {"rec/x.csv": DIRECTORY, "rec/x.csv/quiet.txt": "no\n"}),
        _case("binary", "actuator-step.csv", bytes(range(256)) * 40, ""),
        _case("latin-1", "actuator-step.csv", step.replace("gauge", "jauge \xe0 ressort", 1).encode("latin-1"), ""),
        _case("step-one-row", "actuator-step.csv", _write(notes, names, rows[:1]), "t_s"),
    ]


def _spread_cases() -> list[Case]:
    """Bench profiles whose [uncertainty] is wrong, given to simulate --bench-spread and bench-test --bench."""
    uw = (ROOT / "patchgen" / "profiles" / "benches" / "uw-1991.toml").read_text()
    bench = "@TMP@/b.toml"
    sim = ("simulate", SPEC, "--scenario", "@TMP@/sc.toml", "--bench", bench, "--bench-spread", "-o", "@TMP@/out")
    bt = ("bench-test", SPEC, "--bench", bench, "-o", "@TMP@/out")
    tables = {
        "dotted-unquoted": ("noise_V_rms.s = [0.001, 0.003]", "uncertainty.noise_V_rms"),
        "sensor-crosses-zero": ('"sensors.s" = [-1.0, 6.0]', "uncertainty.sensors.s"),
        "huge": ("K_U = [1.0, 1e300]", "uncertainty.K_U"),
        "subnormal": ("K_U = [1e-320, 20.0]", "uncertainty.K_U"),
        "distribution-unknown": ('distribution = "lognormal"', "uncertainty.distribution"),
    }
    out = []
    for name, (line, field) in tables.items():
        files = {"spec.toml": GOOD_SPEC, "sc.toml": GOOD_SCENARIO, "b.toml": f"{uw}\n[uncertainty]\n{line}\n"}
        out.append(Case(f"bench-spread-{name}", sim, bench, field, files))
        out.append(Case(f"bench-test-range-{name}", bt, bench, field, files))
    return out


def identify_cases() -> list[Case]:
    """Every case of this module."""
    g = good_files()
    return _number_cases(g) + _range_cases(g) + _clip_cases(g) + _file_cases(g) + _spread_cases()
