"""The bad-input corpus: what a case is, the field tables it is built from, and the spec cases
(scenarios and profiles: badinput_inputs.py; files and options: badinput_options.py).

Each case is files to lay out in a fresh folder (``@TMP@`` in a path or text is that folder), the
command line, and what the one line on stderr must name: the file (or option) and the field.
Field tables follow the models' declared types and bounds (patchgen/spec.py, scenario.py,
machine.py, bench.py); every value tried is outside them.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from .badinput_toml import (
    BOOL_MUTATIONS,
    DELETE,
    INT_MUTATIONS,
    STR_MUTATIONS,
    WORD_MUTATIONS,
    Num,
    dumps,
    number_mutations,
    sub_field,
    with_field,
)

ROOT = Path(__file__).resolve().parents[2]
FIFO, DIRECTORY, LOOP = "<fifo>", "<directory>", "<symlink loop>"  # special files to lay out


def shipped(folder: str, name: str) -> dict:
    """A shipped file's TOML: designs and sims at the repository's top level, profiles in the package."""
    base = ROOT / "patchgen" if folder.startswith("profiles/") else ROOT
    return tomllib.loads((base / folder / f"{name}.toml").read_text())


@dataclass(frozen=True)
class Case:
    id: str
    argv: tuple[str, ...]
    source: str  # the file (or option) the line must name
    field: str  # the field path it must name ("" for the file as a whole)
    files: dict[str, object] = field(default_factory=dict)
    usage: bool = False  # refused by the option parser: "patchgen CMD: ... 'OPTION' ..."
    existing: tuple[str, ...] = ()  # output files already there (the folder must stay unchanged)
    out: str = "@TMP@/out"


SPEC = "@TMP@/spec.toml"
LAG = shipped("designs", "bench-recommended")  # lag actuator, Bryson weights, filtered differentiator
KAL = shipped("designs", "thesis-case1")  # gain actuator, Q and R, integrators, Kalman estimator
MOT = shipped("designs", "quanser-ip02")  # a DC motor driven by voltage, a rigid pendulum, R_V


def patch_argv(spec: str = SPEC) -> tuple[str, ...]:
    return ("patch", spec, "-o", "@TMP@/out", "--no-predict")


def spec_case(name: str, data: dict, field_path: str, argv=None) -> Case:
    return Case(f"spec-{name}", argv or patch_argv(), SPEC, field_path, {"spec.toml": dumps(data)})


def field_cases(prefix: str, base: dict, table: dict, make) -> list[Case]:
    """Every wrong value of every field in ``table`` (path -> Num, int, str, bool or word)."""
    out = []
    for path, kind in table.items():
        if isinstance(kind, Num):
            muts = number_mutations(kind)
        else:
            muts = {int: INT_MUTATIONS, str: STR_MUTATIONS, bool: BOOL_MUTATIONS, "word": WORD_MUTATIONS}[kind]
        for mname, new in muts.items():
            where = path + (sub_field(kind, mname) if isinstance(kind, Num) else "")
            out.append(make(f"{prefix}{path}-{mname}", with_field(base, path, new), where))
    return out


SPEC_FIELDS_LAG = {
    "plant.M": Num(0.01, 100), "plant.m": Num(1e-3, 10), "plant.l": Num(0.01, 10),
    "plant.g": Num(1, 30, required=False), "plant.b_VF": Num(0, 1000), "plant.c": Num(0, 10),
    "plant.d": Num(0.05, 20, required=False), "plant.J": Num(0, 10, required=False),
    "plant.F_C": Num(0, 1e3, required=False),
    "sensors.s": Num(1e-3, 1e3), "sensors.theta": Num(1e-3, 1e3), "sensors.s_dot": Num(1e-3, 1e3),
    "sensors.theta_dot": Num(1e-3, 1e3, required=False),
    "actuator.K_U": Num(0.01, 1000), "actuator.tau": Num(0, 10, required=False),
    "actuator.state_scale": Num(1e-3, 1e3, required=False), "actuator.zero": Num(0, 1e3, required=False),
    "actuator.dead_zone_V": Num(0, 100, required=False), "actuator.model": "word",
    "weights.bryson.s": Num(1e-4, 1e4, required=False), "weights.bryson.theta": Num(1e-4, 1e4, required=False),
    "weights.bryson.u": Num(1e-4, 1e4),
    "estimator.kind": "word", "estimator.rolloff_s": Num(1e-4, 1, required=False),
    "name": str, "description": str, "source": str, "machine": str, "bench": str,
    "patch.below_resolution": "word",
}
SPEC_FIELDS_KAL = {
    "weights.Q.s": Num(0, 1e8, required=False), "weights.Q.theta": Num(0, 1e8, required=False),
    "weights.R": Num(1e-8, 1e8),
    "integrators.int_s": bool, "integrators.int_theta": bool,
    "integrators.int_s_leak": Num(0, 1, required=False), "integrators.int_theta_leak": Num(0, 1, required=False),
    "estimator.W": Num(-1e12, 1e12, required=False, matrix=True),
    "estimator.rho_max": Num(0, 1e12, open_lo=True, required=False),
}


SPEC_FIELDS_MOTOR = {
    "actuator.R_m": Num(1e-3, 1e3), "actuator.K_t": Num(1e-5, 10), "actuator.K_m": Num(1e-5, 10),
    "actuator.r_pinion": Num(1e-4, 1), "actuator.K_g": Num(0.01, 1e3, required=False),
    "actuator.J_m": Num(0, 1, required=False), "actuator.eta_g": Num(0.01, 1, required=False),
    "actuator.eta_m": Num(0.01, 1, required=False), "actuator.amp_gain": Num(0.01, 100, required=False),
    "weights.R_V": Num(1e-8, 1e8, required=False),  # missing: named at weights.R (either will do)
}


def spec_cases() -> list[Case]:
    out = field_cases("lag-", LAG, SPEC_FIELDS_LAG, spec_case)
    out += field_cases("kal-", KAL, SPEC_FIELDS_KAL, spec_case)
    out += field_cases("motor-", MOT, SPEC_FIELDS_MOTOR, spec_case)
    # numbers whose field is a union with a word
    for name, new in {"zero": 0.0, "negative": -1.0, "nan": math.nan, "inf": math.inf, "string": "fast",
                      "bool": True, "huge": 1e300}.items():
        out.append(spec_case(f"kal-rho-{name}", with_field(KAL, "estimator.rho", new), "estimator.rho"))
    for name, new in {"zero": 0, "many": 17, "float": 1.5, "string": "2", "bool": True, "word": "most"}.items():
        out.append(spec_case(f"lag-units-{name}", with_field(LAG, "patch.units", new), "patch.units"))
    obs = with_field(LAG, "estimator.kind", "reduced_observer")
    for name, new in number_mutations(Num(1e-2, 1e4, required=False)).items():
        out.append(spec_case(f"obs-observer_pole-{name}", with_field(obs, "estimator.observer_pole", new),
                             "estimator.observer_pole"))
    for section in ("plant", "sensors", "actuator", "weights"):
        out.append(spec_case(f"missing-{section}", with_field(LAG, section, DELETE), section))
        out.append(spec_case(f"scalar-{section}", with_field(LAG, section, 3), section))
    for section in ("plant", "sensors", "actuator", "weights", "integrators", "estimator", "patch"):
        out.append(spec_case(f"unknown-{section}", with_field(LAG, f"{section}.bogus", 1.0), f"{section}.bogus"))
    out.append(spec_case("unknown-top", with_field(LAG, "bogus", 1), "bogus"))
    out.append(spec_case("missing-name", with_field(LAG, "name", DELETE), "name"))
    out += _crossfield_cases()
    out += _matrix_cases()
    return out


def _crossfield_cases() -> list[Case]:
    """Values fine alone, wrong together (or only wrong once the design runs)."""
    bry = "weights.bryson"
    cases = {
        "lag-tau-zero": (with_field(LAG, "actuator.tau", 0.0), "actuator.tau"),
        "lag-tau-short": (with_field(LAG, "actuator.tau", 1e-5), "actuator.tau"),
        "bryson-and-Q": (with_field(LAG, "weights.Q", {"theta": 1.0}), "weights"),
        "bryson-unknown-state": (with_field(LAG, f"{bry}.int_s", 1.0), f"{bry}.int_s"),
        "bryson-no-u": (with_field(LAG, f"{bry}.u", DELETE), f"{bry}.u"),
        "Q-unknown-state": (with_field(KAL, "weights.Q.actuator", 1.0), "weights.Q.actuator"),
        "Q-negative": (with_field(KAL, "weights.Q.theta", -1.0), "weights.Q.theta"),
        "Q-tiny": (with_field(KAL, "weights.Q.int_theta", 1e-300), "weights.Q.int_theta"),
        "Q-subnormal": (with_field(KAL, "weights.Q.int_s", 2.2e-311), "weights.Q.int_s"),
        "plant-c-subnormal": (with_field(LAG, "plant.c", 5e-324), "plant.c"),
        "int_theta-no-leak": (with_field(KAL, "integrators.int_theta_leak", 0.0), "integrators.int_theta_leak"),
        "Q-missing": (with_field(KAL, "weights.Q", DELETE), "weights.Q"),
        "R-missing": (with_field(KAL, "weights.R", DELETE), "weights.R"),
        "Q-all-zero": (with_field(KAL, "weights.Q", {"s": 0.0}), "weights.Q"),
        "bryson-only-u": (with_field(LAG, bry, {"u": 3.0}), bry),
        "K_U-floor": (with_field(LAG, "actuator.K_U", 1e3) | {"sensors": dict.fromkeys(LAG["sensors"], 1e3)},
                      "actuator.K_U"),
        "kalman-theta_dot-none": (with_field(KAL, "estimator.kind", "none"), "estimator.kind"),
    }
    lz = with_field(with_field(KAL, "actuator.model", "lag_zero"), "actuator.tau", 0.2)
    lz = with_field(with_field(lz, "actuator.zero", 0.0), "weights.Q.actuator", 1.0)
    cases["lag_zero-at-origin"] = (lz, "actuator.zero")
    cases |= {  # a DC motor's figures: K_U follows from them, only a dc_motor has them, it has no lag
        "motor-K_U-given": (with_field(MOT, "actuator.K_U", 3.0), "actuator.K_U"),
        "motor-tau": (with_field(MOT, "actuator.tau", 0.01), "actuator.tau"),
        "motor-figure-on-lag": (with_field(LAG, "actuator.R_m", 2.6), "actuator.R_m"),
        "motor-amp-on-gain": (with_field(KAL, "actuator.amp_gain", 1.0), "actuator.amp_gain"),
        "motor-R-and-R_V": (with_field(MOT, "weights.R", 0.1), "weights.R_V"),
    }
    return [spec_case(k, data, f) for k, (data, f) in cases.items()]


def _matrix_cases() -> list[Case]:
    """Ragged, wrong-shape, non-symmetric and non-numeric matrices (Q, W, V, Gamma)."""
    eye = [[1.0 if i == j else 0.0 for j in range(6)] for i in range(6)]
    qm = with_field(KAL, "weights.Q", eye)
    ragged = [row[:] for row in eye]
    ragged[3] = ragged[3][:4]
    skew = [row[:] for row in eye]
    skew[0][1] = 5.0
    bad_cell = [row[:] for row in eye]
    bad_cell[2][2] = "x"
    inf_cell = [row[:] for row in eye]
    inf_cell[1][1] = math.inf
    neg = [row[:] for row in eye]
    neg[0][0] = -1.0
    big = [row[:] for row in eye]
    big[0][0] = 1e300
    v3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    cases = {
        "Q-ragged": (with_field(qm, "weights.Q", ragged), "weights.Q[3]"),
        "Q-3x3": (with_field(qm, "weights.Q", v3), "weights.Q"),
        "Q-empty": (with_field(qm, "weights.Q", []), "weights.Q"),
        "Q-empty-row": (with_field(qm, "weights.Q", [[]]), "weights.Q"),
        "Q-nonsymmetric": (with_field(qm, "weights.Q", skew), "weights.Q"),
        "Q-indefinite": (with_field(qm, "weights.Q", neg), "weights.Q"),
        "Q-string-cell": (with_field(qm, "weights.Q", bad_cell), "weights.Q[2][2]"),
        "Q-inf-cell": (with_field(qm, "weights.Q", inf_cell), "weights.Q[1][1]"),
        "Q-huge-cell": (with_field(qm, "weights.Q", big), "weights.Q[0][0]"),
        "Q-tiny-cell": (with_field(qm, "weights.Q", [r[:3] + [1e-300] + r[4:] if i == 3 else r
                                                       for i, r in enumerate(eye)]), "weights.Q[3][3]"),
        "Q-flat": (with_field(qm, "weights.Q", [1.0, 2.0]), "weights.Q[0]"),
        "V-two": (with_field(KAL, "estimator.V", [1.0, 1.0]), "estimator.V"),
        "V-empty": (with_field(KAL, "estimator.V", []), "estimator.V"),
        "V-ragged": (with_field(KAL, "estimator.V", [v3[0], v3[1][:2], v3[2]]), "estimator.V[1]"),
        "V-negative": (with_field(KAL, "estimator.V", [1.0, -1.0, 1.0]), "estimator.V"),
        "V-tiny": (with_field(KAL, "estimator.V", [1.0, 1e-300, 1.0]), "estimator.V"),
        "V-nan": (with_field(KAL, "estimator.V", [1.0, math.nan, 1.0]), "estimator.V[1]"),
        "V-string": (with_field(KAL, "estimator.V", "diag"), "estimator.V"),
        "V-4x4": (with_field(KAL, "estimator.V", [[1.0] * 4] * 4), "estimator.V"),
        "W-ragged": (with_field(KAL, "estimator.W", [[1.0, 0.0], [0.0]]), "estimator.W[1]"),
        "W-2x2-for-B": (with_field(KAL, "estimator.W", [[1.0, 0.0], [0.0, 1.0]]), "estimator.W"),
        "W-negative": (with_field(KAL, "estimator.W", -1.0), "estimator.W"),
        "Gamma-rows": (with_field(KAL, "estimator.Gamma", [1.0, 2.0]), "estimator.Gamma"),
        "Gamma-empty": (with_field(KAL, "estimator.Gamma", []), "estimator.Gamma"),
        "Gamma-ragged": (with_field(KAL, "estimator.Gamma", [[1.0], [1.0], [1.0, 2.0], [1.0]]), "estimator.Gamma[2]"),
        "Gamma-word": (with_field(KAL, "estimator.Gamma", "C"), "estimator.Gamma"),
        "Gamma-nan": (with_field(KAL, "estimator.Gamma", [1.0, math.nan, 1.0, 1.0]), "estimator.Gamma[1]"),
        "Gamma-huge": (with_field(KAL, "estimator.Gamma", [1.0, 1e300, 1.0, 1.0]), "estimator.Gamma[1]"),
    }
    return [spec_case(k, data, f) for k, (data, f) in cases.items()]
