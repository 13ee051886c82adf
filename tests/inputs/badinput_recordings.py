"""The bad-input corpus, continued: recordings and test figures given to ``patchgen identify``
(a missing column, a wrong unit, too few samples, numbers that are not, a test that does not
excite what it fits) and the options of identify and bench-test.

The good recordings are bench-test's own for bench-recommended on uw-1991 (seed 0); each case
breaks one file and gives identify that file alone, or the whole folder.
"""

from __future__ import annotations

import functools

import numpy as np

from .badinput_cases import SPEC, Case
from .badinput_options import GOOD_SPEC

REC = "@TMP@/rec"


@functools.cache
def good_files() -> dict[str, str]:
    """bench-test's recordings, file name -> text."""
    from patchgen.identify.benchtest import bench_test_files
    from patchgen.plant.equations import PlantParams
    from patchgen.profiles.bench import load_bench
    from patchgen.profiles.machine import load_machine

    plant = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)
    files = bench_test_files(plant, load_bench("uw-1991"), load_machine("gp6"), 0)
    return {k: v.decode() for k, v in files.items()}


def _rows(text: str) -> tuple[list[str], list[str], list[list[float]]]:
    """A recording's comment lines, header names and numbers."""
    lines = text.splitlines()
    notes = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if not ln.startswith("#")]
    names = [n.strip() for n in body[0].split(",")]
    return notes, names, [[float(c) for c in ln.split(",")] for ln in body[1:]]


def _write(notes: list[str], names: list[str], rows) -> str:
    return "\n".join(notes + [", ".join(names)] + [", ".join(f"{v:.10g}" for v in r) for r in rows]) + "\n"


@functools.cache
def _table(text: str) -> tuple[list[str], list[str], np.ndarray]:
    """_rows as an array, read once per recording (many cases start from the same one)."""
    notes, names, rows = _rows(text)
    return notes, names, np.array(rows)


def _with_column(text: str, column: str, f) -> str:
    """The recording with ``column`` replaced by f(t, column)."""
    notes, names, a = _table(text)
    a = a.copy()
    i = names.index(column)
    a[:, i] = f(a[:, names.index("t_s")] if "t_s" in names else None, a[:, i])
    return _write(notes, names, a)


def _case(name: str, file: str, text: str, field_name: str, whole_folder: bool = False) -> Case:
    files = dict(good_files()) if whole_folder else {}
    files = {f"rec/{k}": v for k, v in files.items()}
    files[f"rec/{file}"] = text
    target = REC if whole_folder else f"{REC}/{file}"
    return Case(f"recording-{name}", ("identify", target, "-o", "@TMP@/out"), f"{REC}/{file}", field_name, files)


def recording_cases() -> list[Case]:
    g = good_files()
    step, ramp, swing = g["actuator-step.csv"], g["actuator-ramp.csv"], g["free-swing.csv"]
    coast, quiet, cal = g["coast-down-1.csv"], g["quiet.csv"], g["calibration.csv"]
    notes, names, rows = _rows(step)
    cases = [
        _case("missing-column", "actuator-step.csv", step.replace(", force_N", "", 1), "force_N"),
        _case("missing-column-in-folder", "actuator-step.csv", _write(notes, names[:2], [r[:2] for r in rows]),
              "force_N", whole_folder=True),
        _case("wrong-unit-kN", "actuator-step.csv", step.replace("force_N", "force_kN", 1), "force_kN"),
        _case("wrong-unit-ms", "actuator-step.csv", step.replace("t_s", "t_ms", 1), "t_ms"),
        _case("wrong-unit-theta-deg", "free-swing.csv", swing.replace("theta_V", "theta_deg", 1), "theta_deg"),
        _case("unknown-column", "quiet.csv", quiet.replace("s_dot_V", "speed_V", 1), "speed_V"),
        _case("too-few-samples", "free-swing.csv", "\n".join(swing.splitlines()[:60]) + "\n", "t_s"),
        _case("nan", "actuator-step.csv", _write(notes, names, [rows[0], [rows[1][0], float("nan"), rows[1][2]]]
                                                 + rows[2:]), "u_c_V"),
        _case("inf", "coast-down-1.csv", _with_column(coast, "s_V", lambda t, x: np.where(t > 1, np.inf, x)),
              "s_V"),
        _case("text", "quiet.csv", quiet.replace("\n", "\nx, 0, 0, 0\n", 4).replace("\nx, 0, 0, 0\n", "\n", 3),
              "t_s"),
        _case("no-test-line", "actuator-step.csv", "\n".join(step.splitlines()[1:]) + "\n", "test"),
        _case("unknown-test", "actuator-step.csv", step.replace("actuator_step", "actuator_kick", 1), "test"),
        _case("clock-jumps", "free-swing.csv", _with_column(swing, "t_s", lambda t, x: np.where(t > 5, x + 0.5, x)),
              "t_s"),
        # tests that do not excite what they fit
        _case("step-never-steps", "actuator-step.csv", _with_column(step, "u_c_V", lambda t, x: 0 * x + 1.0), "u_c_V"),
        _case("step-one-level", "actuator-step.csv", _with_column(step, "u_c_V", lambda t, x: np.where(t > 1, 1.0, 0)),
              "u_c_V"),
        _case("step-no-response", "actuator-step.csv", _with_column(
            step, "force_N", lambda t, x: 0.02 * np.sin(37 * t)), "force_N"),
        _case("ramp-not-through-zero", "actuator-ramp.csv", _with_column(ramp, "u_c_V", lambda t, x: np.abs(x) + 0.5),
              "u_c_V"),
        _case("coast-never-moves", "coast-down-1.csv", _with_column(
            coast, "s_dot_V", lambda t, x: 0.005 * np.random.default_rng(1).standard_normal(x.size)), "s_dot_V"),
        _case("swing-at-rest", "free-swing.csv", _with_column(swing, "theta_V", lambda t, x: 0 * x + 0.001), "theta_V"),
        _case("quiet-not-quiet", "quiet.csv", _with_column(quiet, "s_V", lambda t, x: x + np.where(t > 1, 1.0, 0.0)),
              "s_V"),
        _case("calibration-one-mark", "calibration.csv", _with_column(cal, "s_m", lambda t, x: 0 * x + 0.1), "s_m"),
        # an encoder's counts: read with the bench profile's count, whole numbers only
        _case("counts-without-encoder", "coast-down-1.csv", _with_column(
            coast, "s_V", lambda t, x: np.round(1e4 * x)).replace("s_V", "s_counts", 1), "s_counts"),
        _case("counts-not-whole", "free-swing.csv", _with_column(
            swing, "theta_V", lambda t, x: 100 * x + 0.25).replace("theta_V", "theta_counts", 1), "theta_counts"),
        _case("counts-and-pot", "coast-down-1.csv", coast.replace("s_V, s_dot_V", "s_V, s_counts", 1), "s_counts"),
        # test figures
        _case("incline-faster-than-frictionless", "incline.toml",
              g["incline.toml"].replace("time_s = ", "time_s = 0.5 #"), "distance_m"),
        _case("masses-negative", "masses.toml", g["masses.toml"].replace("M_kg = ", "M_kg = -"), "M_kg"),
        _case("masses-nan", "masses.toml", g["masses.toml"].replace("m_kg = ", "m_kg = nan #", 1), "m_kg"),
        _case("figures-unknown-test", "masses.toml", g["masses.toml"].replace('"masses"', '"scales"'), "test"),
        _case("masses-twice", "weighed-again.toml", g["masses.toml"], "test", whole_folder=True),
    ]
    cases.append(Case("recording-no-such-file", ("identify", f"{REC}/none.csv", "-o", "@TMP@/out"),
                      f"{REC}/none.csv", ""))
    cases.append(Case("recording-empty-folder", ("identify", REC, "-o", "@TMP@/out"), REC, "",
                      {"rec/notes.txt": "nothing recorded\n"}))
    cases.append(Case("recording-wrong-suffix", ("identify", f"{REC}/step.txt", "-o", "@TMP@/out"),
                      f"{REC}/step.txt", "", {"rec/step.txt": step}))
    folder = {f"rec/{k}": v for k, v in g.items()}
    ident = lambda *extra: ("identify", REC, "-o", "@TMP@/out", *extra)  # noqa: E731
    cases.append(Case("identify-base-unknown", ident("--base", "no-such-bench"), "--base", "", folder))
    cases.append(Case("identify-id-empty", ident("--id", " "), "--id", "", folder))
    cases.append(Case("identify-out-exists", ident(), "@TMP@/out/bench.toml", "-o", folder, existing=("bench.toml",)))
    bt = lambda *extra: ("bench-test", SPEC, "-o", "@TMP@/out", *extra)  # noqa: E731
    spec = {"spec.toml": GOOD_SPEC}
    cases += [Case("bench-test-seed-negative", bt("--seed", "-1"), "--seed", "", spec, usage=True),
              Case("bench-test-seed-word", bt("--seed", "x"), "--seed", "", spec, usage=True),
              Case("bench-test-bench-unknown", bt("--bench", "no-such-bench"), "--bench", "", spec),
              Case("bench-test-spec-missing", ("bench-test", "@TMP@/none.toml", "-o", "@TMP@/out"),
                   "@TMP@/none.toml", ""),
              Case("bench-test-out-exists", bt(), "@TMP@/out/quiet.csv", "-o", spec, existing=("quiet.csv",))]
    return cases
