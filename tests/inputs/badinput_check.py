"""The bad-input corpus, continued: the readings file of ``patchgen check`` (what it is, how it is
written, the rows and values in it).

The good readings are bench-recommended's static check with every expected value as measured;
each case breaks that file one way.
"""

from __future__ import annotations

import csv
import functools
import io

from .badinput_cases import DIRECTORY, FIFO, KAL, LAG, LOOP, SPEC, Case, patch_argv, shipped
from .badinput_toml import dumps, with_field

READ = "@TMP@/r.csv"


def check_argv(path: str = READ, *extra: str) -> tuple[str, ...]:
    return ("check", "bench-recommended", "--readings", path, *extra)


@functools.cache
def good_readings() -> str:
    """bench-recommended's static-check.csv with measured_V = expected_V on every row."""
    from patchgen.design.lqg import design_on
    from patchgen.patch.static_check import static_check, static_check_csv
    from patchgen.pipeline.inputs import load_inputs
    from patchgen.pipeline.scaling import scaled_patch

    sp, machine, bench = load_inputs("bench-recommended")
    net = scaled_patch(design_on(sp, machine, bench), machine, bench).netlist  # the patch check builds
    rows = list(csv.reader(io.StringIO(static_check_csv(static_check(net, machine)))))
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows([rows[0]] + [r[:-1] + [r[2]] for r in rows[1:]])
    return out.getvalue()


def _measured(text: str, row: int, value: str) -> str:
    """The readings with the measured_V of ``row`` (the header is row 1) set to ``value``."""
    lines = text.splitlines()
    lines[row - 1] = lines[row - 1].rsplit(",", 1)[0] + "," + value
    return "\n".join(lines) + "\n"


def _cell(text: str, row: int, column: int, value: str) -> str:
    lines = text.splitlines()
    cells = lines[row - 1].split(",")
    cells[column] = value
    lines[row - 1] = ",".join(cells)
    return "\n".join(lines) + "\n"


def readings_cases() -> list[Case]:
    good = good_readings()
    lines = good.splitlines()
    third = lines[2]
    bad = {  # name -> (file text, field)
        "measured-empty": (_measured(good, 3, ""), "row 3: measured_V"),
        "measured-blank": (_measured(good, 3, "   "), "row 3: measured_V"),
        "measured-word": (_measured(good, 3, "about 1"), "row 3: measured_V"),
        "measured-nan": (_measured(good, 3, "nan"), "row 3: measured_V"),
        "measured-inf": (_measured(good, 3, "-inf"), "row 3: measured_V"),
        "measured-1e151": (_measured(good, 3, "1e151"), "row 3: measured_V"),
        "measured-1e308": (_measured(good, 4, "-1.7e308"), "row 4: measured_V"),
        "measured-millivolts": (_measured(good, 5, "-350"), "row 5: measured_V"),
        "measured-hex": (_measured(good, 3, "0x1p3"), "row 3: measured_V"),
        "measured-units": (_measured(good, 3, "1.2 V"), "row 3: measured_V"),
        "decimal-comma-quoted": (_measured(good, 3, '"0,25"'), "row 3: measured_V"),
        "decimal-comma": (_measured(good, 3, "0,25"), "row 3"),
        "semicolons": (good.replace(",", ";"), "header"),
        "tabs": (good.replace(",", "\t"), "header"),
        "no-header": ("\n".join(lines[1:]) + "\n", "header"),
        "header-misspelt": (good.replace("measured_V", "measured", 1), "header"),
        "header-column-twice": (good.replace("point", "point,point", 1), "header"),
        "unknown-row": (good + "IC,A99,0.0,0.001,,0.0\n", f"row {len(lines) + 1}"),
        "unknown-condition": (_cell(good, 3, 0, "OP"), "row 3"),
        "row-missing": ("\n".join(lines[:-1]) + "\n", "measured_V"),
        "rows-missing": ("\n".join(lines[:3]) + "\n", "measured_V"),
        "header-only": (lines[0] + "\n", "measured_V"),
        "row-twice-different": (good + third.rsplit(",", 1)[0] + ",7.5\n", f"row {len(lines) + 1}: measured_V"),
        "expected-from-another-patch": (_cell(good, 3, 2, "9.9999"), "row 3: expected_V"),
        "open-quote": (good.replace(third, '"' + third, 1), "row 3"),
        "cell-too-long": (good.replace(third, third + "," + "x" * 140_000, 1), "row 3"),
        "too-many-cells": (good.replace(third, third + ",1,2", 1), "row 3"),
        "empty-file": ("", ""),
        "blank-lines-only": ("\n\n\n", ""),
        "too-large": (good + "#" * (4 << 20) + "\n", ""),
        "nul-byte": (good.replace(third, third[:3] + "\0" + third[3:], 1), ""),
        "latin1": ((good + "IC,A1,0,0,r\xe9glage,0\n").encode("latin-1"), ""),
        "utf16": (good.encode("utf-16"), ""),
    }
    out = [Case(f"check-readings-{k}", check_argv(), READ, f, {"r.csv": text}) for k, (text, f) in bad.items()]
    for name, kind in {"fifo": FIFO, "directory": DIRECTORY, "symlink-loop": LOOP}.items():
        out.append(Case(f"check-readings-{name}", check_argv(), READ, "", {"r.csv": kind}))
    out += [
        Case("check-readings-dev-zero", check_argv("/dev/zero"), "/dev/zero", ""),
        Case("check-readings-dev-null", check_argv("/dev/null"), "/dev/null", ""),
        Case("check-readings-missing-file", check_argv(), READ, ""),
        Case("check-readings-under-a-file", check_argv("@TMP@/afile/r.csv"), "@TMP@/afile/r.csv", "",
             {"afile": b"x"}),
        Case("check-readings-empty-name", check_argv(""), "--readings", ""),
        Case("check-readings-json-1e151", check_argv(READ, "--json"), READ, "row 2: measured_V",
             {"r.csv": _measured(good, 2, "1e151")}),
        Case("check-readings-option-missing", ("check", "bench-recommended"), "--readings", "", usage=True),
    ]
    return out


def scenario_time_cases() -> list[Case]:
    """Times a scenario allows alone that make no simulation: a run of less than a few steps."""
    cases = {
        "duration-1e-300": ("duration_s = 1e-300\n", "duration_s"),
        "duration-1e-22": ("duration_s = 1e-22\n", "duration_s"),
        "duration-one-step": ("duration_s = 0.01\n", "duration_s"),
        "duration-below-dt": ("duration_s = 0.01\ndt_s = 0.005\n", "duration_s"),
        "duration-tiny-with-dt": ("duration_s = 1e-12\ndt_s = 1e-6\n", "duration_s"),
        "duration-tiny-record": ("duration_s = 1e-300\nrecord_dt_s = 1e-6\n", "duration_s"),
        "duration-tiny-push": ("duration_s = 1e-9\n[[disturbances]]\nkind = 'force_impulse'\ntime_s = 0.0\n"
                               "duration_s = 1e-10\nforce_N = 1.0\nat = 'cart'\n", "duration_s"),
    }
    sim = ("simulate", "bench-recommended", "--scenario", "@TMP@/sc.toml", "-o", "@TMP@/out", "--runs", "1")
    out = [Case(f"check-scenario-{k}", sim, "@TMP@/sc.toml", f, {"sc.toml": t}) for k, (t, f) in cases.items()]
    for cmd, argv in (("spice", ("spice", "bench-recommended", "--scenario", "@TMP@/sc.toml", "-o", "@TMP@/out")),
                      ("recommend", ("recommend", "bench-recommended", "--scenario", "@TMP@/sc.toml", "-o",
                                     "@TMP@/out", "--runs", "1")),
                      ("sweep", ("sweep", "bench-recommended", "--scenario", "@TMP@/sc.toml"))):
        out.append(Case(f"check-scenario-{cmd}-duration-1e-300", argv, "@TMP@/sc.toml", "duration_s",
                        {"sc.toml": "duration_s = 1e-300\n"}))
    return out


def _lag_zero(zero: float) -> dict:
    lz = with_field(with_field(KAL, "actuator.model", "lag_zero"), "actuator.tau", 0.2)
    return with_field(with_field(lz, "actuator.zero", zero), "weights.Q.actuator", 1.0)


def _few_inputs(x1: int, x10: int) -> str:
    """The GP-6 profile with every amplifier's inputs cut to x1 and x10."""
    gp6 = shipped("profiles/machines", "gp6")
    for a in gp6["amplifiers"]:
        a["inputs"] = {"x1": x1, "x10": x10}
    return dumps(gp6)


def design_cases() -> list[Case]:
    """Finite values each field allows that no design can use: blamed on the field, not the machine."""
    sim = ("simulate", SPEC, "--scenario", "offset-10deg", "-o", "@TMP@/out", "--runs", "1")
    rho = lambda v: with_field(KAL, "estimator.rho", v)  # noqa: E731
    cases = {  # name -> (spec, field, argv)
        "rho-1e-300": (rho(1e-300), "estimator.rho", patch_argv()),
        "rho-1e-300-design": (rho(1e-300), "estimator.rho", ("design", SPEC)),
        "rho-1e-300-simulate": (rho(1e-300), "estimator.rho", sim),
        "rho-1e-30": (rho(1e-30), "estimator.rho", patch_argv()),
        "rho-1e-16": (rho(1e-16), "estimator.rho", patch_argv()),
        "rho-1e-12": (rho(1e-12), "estimator.rho", patch_argv()),
        "rho-1e-9": (rho(1e-9), "estimator.rho", patch_argv()),
        "W-zero": (with_field(KAL, "estimator.W", 0.0), "estimator.W", patch_argv()),
        "W-zero-matrix": (with_field(KAL, "estimator.W", [[0.0]]), "estimator.W", ("design", SPEC)),
        "W-1e-300": (with_field(KAL, "estimator.W", 1e-300), "estimator.rho", patch_argv()),
        "W-huge": (with_field(KAL, "estimator.W", 1e12), "estimator.rho", ("design", SPEC)),
        "Gamma-zero": (with_field(KAL, "estimator.Gamma", [0.0, 0.0, 0.0, 0.0]), "estimator.Gamma", patch_argv()),
        "Gamma-huge": (with_field(KAL, "estimator.Gamma", [1e6] * 4), "estimator.rho", ("design", SPEC)),
        "rho_max-1e-300": (with_field(rho("auto"), "estimator.rho_max", 1e-300), "estimator.rho_max",
                           patch_argv()),
        "rho_max-half": (with_field(rho("auto"), "estimator.rho_max", 0.5), "estimator.rho_max", ("design", SPEC)),
        "zero-1e-300": (_lag_zero(1e-300), "actuator.zero", patch_argv()),
        "zero-1e-300-design": (_lag_zero(1e-300), "actuator.zero", ("design", SPEC)),
        "zero-1e-9": (_lag_zero(1e-9), "actuator.zero", patch_argv()),
        "int_s_leak-1": (with_field(KAL, "integrators.int_s_leak", 1.0), "integrators.int_s_leak", patch_argv()),
        "int_theta_leak-0.5": (with_field(KAL, "integrators.int_theta_leak", 0.5), "integrators.int_theta_leak",
                               patch_argv()),
        "compensator-of-a-differentiator": (with_field(LAG, "patch.realization", "compensator"),
                                            "patch.realization", patch_argv()),
    }
    out = [Case(f"check-design-{k}", argv, SPEC, f, {"spec.toml": dumps(d)}) for k, (d, f, argv) in cases.items()]
    # a patch that does not fit the machine: the spec (the design that asks too much) is named
    for name, (x1, x10, base) in {"no-x10-inputs": (4, 0, LAG), "one-x10-input": (3, 1, LAG),
                                  "one-x1-input": (1, 2, shipped("designs", "thesis-ch5"))}.items():
        spec = dumps(with_field(base, "machine", "@TMP@/m.toml"))
        out.append(Case(f"check-design-machine-{name}", patch_argv(), SPEC, "machine",
                        {"spec.toml": spec, "m.toml": _few_inputs(x1, x10)}))
    return out


def check_cases() -> list[Case]:
    return readings_cases() + scenario_time_cases() + design_cases()
