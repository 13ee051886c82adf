"""The bad-input corpus, continued: scenarios (through ``simulate --runs 1``) and machine and bench
profiles (given by path in a spec)."""

from __future__ import annotations

import copy
import math

from .badinput_cases import LAG, Case, Num, field_cases, patch_argv, shipped
from .badinput_toml import DELETE, INT_MUTATIONS, dumps, number_mutations, with_field

SC = "@TMP@/sc.toml"
SC_ARGV = ("simulate", "bench-recommended", "--scenario", SC, "-o", "@TMP@/out", "--runs", "1")
OFFSET = shipped("sims", "offset-10deg")
PUSH = shipped("sims", "finger-push")
STEP = shipped("sims", "step-cart")


def sc_case(name: str, data: dict, field_path: str) -> Case:
    return Case(f"scenario-{name}", SC_ARGV, SC, field_path, {"sc.toml": dumps(data)})


SCENARIO_FIELDS = {
    "duration_s": Num(0, 1e5, open_lo=True), "dt_s": Num(1e-6, 0.05, required=False),
    "record_dt_s": Num(1e-6, 1e3, required=False), "fall_angle_deg": Num(0, 180, open_lo=True, required=False),
    "initial.theta_deg": Num(None, 180, symmetric=True, required=False),
    "initial.s": Num(None, 100, symmetric=True, required=False),
    "initial.s_dot": Num(None, 100, symmetric=True, required=False),
    "initial.theta_dot": Num(None, 1000, symmetric=True, required=False),
    "name": str, "description": str,
}
NOISE = with_field(OFFSET, "noise", {"s": 0.002, "theta": 0.002, "s_dot": 0.005, "amplifier": 0.0005})


def _disturbance(base: dict, key: str, new) -> dict:
    out = copy.deepcopy(base)
    out["disturbances"][0][key] = new
    return out


def scenario_cases() -> list[Case]:
    out = field_cases("", OFFSET, SCENARIO_FIELDS, sc_case)
    rad = with_field(OFFSET, "initial.theta_deg", DELETE)
    out += field_cases("rad-", rad, {"initial.theta": Num(None, math.pi, symmetric=True, required=False)}, sc_case)
    out += field_cases("", NOISE, {f"noise.{k}": Num(0, 100, required=False)
                                    for k in ("s", "theta", "s_dot", "amplifier")}, sc_case)
    for name, new in {**INT_MUTATIONS, "negative": -1, "too-big": 2**63}.items():
        out.append(sc_case(f"seed-{name}", with_field(OFFSET, "seed", new), "seed"))
    for name, new in {"word": "lots", "negative": -0.1, "nan": math.nan, "inf": math.inf, "huge": 1e300,
                      "bool": True, "list": [0.1]}.items():
        out.append(sc_case(f"drift-{name}", with_field(OFFSET, "drift", new), "drift"))
    for name, new in {"word": "loud", "number": 0.1, "bool": False, "list": [0.1]}.items():
        out.append(sc_case(f"noise-{name}", with_field(OFFSET, "noise", new), "noise"))
    push = {"time_s": Num(0, 1e5), "duration_s": Num(0, 1e5, open_lo=True), "force_N": Num(None, 1e4, symmetric=True),
            "arm_m": Num(0, 100, open_lo=True, required=False)}
    for key, kind in push.items():
        for mname, new in number_mutations(kind).items():
            if mname == "missing":
                continue
            out.append(sc_case(f"push-{key}-{mname}", _disturbance(PUSH, key, new), f"disturbances[0].{key}"))
    for key in ("duration_s", "force_N", "at"):
        d = copy.deepcopy(PUSH)
        del d["disturbances"][0][key]
        out.append(sc_case(f"push-missing-{key}", d, f"disturbances[0].{key}"))
    for name, new in number_mutations(Num(None, 100, symmetric=True)).items():
        if name != "missing":
            out.append(sc_case(f"step-size_m-{name}", _disturbance(STEP, "size_m", new), "disturbances[0].size_m"))
    cross = {
        "both-angles": (with_field(OFFSET, "initial.theta", 0.1), "initial.theta_deg"),
        "s-outside-track": (with_field(OFFSET, "initial.s", 0.6), "initial.s"),
        "s-on-switch": (with_field(OFFSET, "initial.s", -0.545), "initial.s"),
        "theta-past-180": (with_field(OFFSET, "initial.theta_deg", 181.0), "initial.theta_deg"),
        "push-after-end": (_disturbance(PUSH, "time_s", 20.0), "disturbances[0].time_s"),
        "push-kind": (_disturbance(PUSH, "kind", "kick"), "disturbances[0].kind"),
        "push-at": (_disturbance(PUSH, "at", "nose"), "disturbances[0].at"),
        "push-with-size": (_disturbance(PUSH, "size_m", 0.1), "disturbances[0].size_m"),
        "step-with-force": (_disturbance(STEP, "force_N", 1.0), "disturbances[0].force_N"),
        "arm-on-the-cart": (_disturbance(_disturbance(PUSH, "at", "cart"), "arm_m", 0.3), "disturbances[0].arm_m"),
        "step-with-arm": (_disturbance(STEP, "arm_m", 0.3), "disturbances[0].arm_m"),
        "step-missing-size": ({**STEP, "disturbances": [{"kind": "step", "time_s": 1.0}]}, "disturbances[0].size_m"),
        "disturbances-table": (with_field(OFFSET, "disturbances", {"kind": "step"}), "disturbances"),
        "unknown-top": (with_field(OFFSET, "bogus", 1), "bogus"),
        "unknown-initial": (with_field(OFFSET, "initial.phi", 1.0), "initial.phi"),
        "unknown-noise": (with_field(NOISE, "noise.hum", 1.0), "noise.hum"),
        "unknown-disturbance": (_disturbance(PUSH, "colour", "red"), "disturbances[0].colour"),
        "duration-absurd": (with_field(OFFSET, "duration_s", 1e7), "duration_s"),
        "step-absurd": (with_field(with_field(OFFSET, "duration_s", 1e4), "dt_s", 1e-7), "dt_s"),
        "history-absurd": (with_field(with_field(OFFSET, "duration_s", 1e4), "record_dt_s", 1e-3), "record_dt_s"),
    }
    out += [sc_case(k, data, f) for k, (data, f) in cross.items()]
    return out


# ---- machine and bench profiles, given by path in a spec -------------------------------------

GP6 = shipped("profiles/machines", "gp6")
THAT = shipped("profiles/machines", "the-analog-thing")
UW = shipped("profiles/benches", "uw-1991")
IP02 = shipped("profiles/benches", "quanser-ip02")
MP, BP = "@TMP@/m.toml", "@TMP@/b.toml"
WITH_M = dumps(with_field(LAG, "machine", MP))
WITH_B = dumps(with_field(LAG, "bench", BP))


def _steps(which: str, i: int, **update) -> dict:
    """GP6 with step ``i`` of its procedure's ``which`` list updated."""
    data = copy.deepcopy(GP6)
    data["procedure"][which][i].update(update)
    return data


def machine_case(name: str, data: dict, field_path: str) -> Case:
    return Case(f"machine-{name}", patch_argv(), MP, field_path, {"spec.toml": WITH_M, "m.toml": dumps(data)})


def bench_case(name: str, data: dict, field_path: str) -> Case:
    return Case(f"bench-{name}", patch_argv(), BP, field_path, {"spec.toml": WITH_B, "b.toml": dumps(data)})


OHM, FARAD = Num(1, 1e12), Num(1e-15, 1)
MACHINE_FIELDS = {
    "id": str, "name": str, "procedure.pot_setting": str, "procedure.pot_reading": str,
    "imperfections.drift_source": str,
    "reference_V": Num(0, 1000, open_lo=True), "time_scale_s": Num(1e-6, 1e6),
    "pot_resolution": Num(1e-9, 0.5), "pot_max": Num(0, 100, open_lo=True),
    "pot_count": int, "max_units": int,
    "components.input_resistor_x1_ohm": OHM, "components.input_resistor_x10_ohm": OHM,
    "components.feedback_resistor_ohm": OHM, "components.pot_resistance_ohm": OHM,
    "components.integrator_capacitor_F": FARAD, "components.differentiator_capacitor_F": FARAD,
    "components.opamp_open_loop_gain": Num(1, 1e12, open_lo=True),
    "components.opamp_output_resistance_ohm": Num(0, 1e6),
    "imperfections.integrator_offset_V": Num(0, 1), "imperfections.integrator_bias_A": Num(0, 1e-3),
    "imperfections.saturation_V": Num(0, 1000, open_lo=True), "imperfections.amplifier_noise_V_rms": Num(0, 10),
    "imperfections.noise_bandwidth_Hz": Num(1e-3, 1e9), "imperfections.differentiator_rolloff_s": Num(1e-4, 1),
}
BENCH_FIELDS = {
    "id": str, "name": str, "actuator.model": "word",
    "actuator.K_U": Num(0.01, 1000), "actuator.tau": Num(0, 10, required=False),
    "actuator.dead_zone_V": Num(0, 100, required=False), "actuator.force_limit_N": Num(0, 1e4, open_lo=True),
    "sensors.s": Num(1e-3, 1e3), "sensors.theta": Num(1e-3, 1e3), "sensors.s_dot": Num(1e-3, 1e3),
    "sensors.noise_V_rms.s": Num(0, 100, required=False),
    "sensors.noise_bandwidth_Hz": Num(1e-3, 1e9, required=False), "track.limit_switches": bool,
}
BENCH_FIELDS_MOTOR = {  # a motor, encoders, a filtered velocity
    "actuator.R_m": Num(1e-3, 1e3), "actuator.K_t": Num(1e-5, 10), "actuator.K_m": Num(1e-5, 10),
    "actuator.r_pinion": Num(1e-4, 1), "actuator.V_limit": Num(1e-3, 1e4),
    "actuator.amp_gain": Num(0.01, 100, required=False),
    "sensors.counts_per_m.s": Num(1, 1e9, required=False), "sensors.counts_per_rev.theta": Num(4, 1e9, required=False),
    "sensors.velocity_filter.s_dot.wn_rad_s": Num(1, 1e5), "sensors.velocity_filter.s_dot.zeta": Num(0.05, 10),
}


def _modes(edit) -> dict:
    """THE ANALOG THING's profile with its integrator modes edited."""
    out = copy.deepcopy(THAT)
    edit(out["integrator_modes"])
    return out


def _amps(edit) -> dict:
    out = copy.deepcopy(GP6)
    edit(out["amplifiers"])
    return out


def profile_cases() -> list[Case]:
    out = field_cases("", GP6, MACHINE_FIELDS, machine_case)
    for name, new in {"negative": -1, "huge": 10**6}.items():
        out.append(machine_case(f"pot_count-{name}", with_field(GP6, "pot_count", new), "pot_count"))
    for name, new in {"zero": 0, "huge": 17}.items():
        out.append(machine_case(f"max_units-{name}", with_field(GP6, "max_units", new), "max_units"))
        out.append(machine_case(f"units-{name}", with_field(GP6, "units", new), "units"))
    shapes = {
        "weights-empty": (with_field(GP6, "input_weights", []), "input_weights"),
        "weights-zero": (with_field(GP6, "input_weights", [0, 10]), "input_weights[0]"),
        "weights-float": (with_field(GP6, "input_weights", [1, 2.5]), "input_weights[1]"),
        "weights-string": (with_field(GP6, "input_weights", ["x1"]), "input_weights[0]"),
        "weights-scalar": (with_field(GP6, "input_weights", 10), "input_weights"),
        "amps-empty": (with_field(GP6, "amplifiers", []), "amplifiers"),
        "amps-table": (with_field(GP6, "amplifiers", {"id": "A1"}), "amplifiers"),
        "amp-roles-empty": (_amps(lambda a: a[0].update(roles=[])), "amplifiers[0].roles"),
        "amp-role-unknown": (_amps(lambda a: a[2].update(roles=["multiplier"])), "amplifiers[2].roles[0]"),
        "amp-input-weight": (_amps(lambda a: a[1].update(inputs={"x3": 1})), "amplifiers[1].inputs.x3"),
        "amp-input-negative": (_amps(lambda a: a[0].update(inputs={"x1": -1})), "amplifiers[0].inputs.x1"),
        "amp-input-float": (_amps(lambda a: a[0].update(inputs={"x1": 1.5})), "amplifiers[0].inputs.x1"),
        "amp-id-twice": (_amps(lambda a: a[1].update(id="A1")), "amplifiers[1].id"),
        "amp-id-empty": (_amps(lambda a: a[0].update(id="")), "amplifiers[0].id"),
        "amp-unknown": (_amps(lambda a: a[0].update(colour="red")), "amplifiers[0].colour"),
        "amp-missing-id": (_amps(lambda a: a[3].pop("id")), "amplifiers[3].id"),
        "unknown-top": (with_field(GP6, "bogus", 1), "bogus"),
        "unknown-components": (with_field(GP6, "components.bogus", 1.0), "components.bogus"),
        "scalar-imperfections": (with_field(GP6, "imperfections", 3), "imperfections"),
        "procedure-missing": (with_field(GP6, "procedure", DELETE), "procedure"),
        "procedure-no-steps": (with_field(GP6, "procedure.checklist", []), "procedure.checklist"),
        "pot-reading-missing": (with_field(GP6, "procedure.pot_reading", DELETE), "procedure.pot_reading"),
        "pot-reading-long": (with_field(GP6, "procedure.pot_reading", "d" * 101), "procedure.pot_reading"),
        "step-unknown-placeholder": (_steps("operation", 1, text="Set {pots} now."), "procedure.operation[1].text"),
        "step-bad-brace": (_steps("checklist", 0, text="Patch {machine"), "procedure.checklist[0].text"),
        "step-positional": (_steps("checklist", 2, text="Set {0}."), "procedure.checklist[2].text"),
        "step-empty": (_steps("operation", 0, text=""), "procedure.operation[0].text"),
        "step-when-unknown": (_steps("checklist", 3, when="sometimes"), "procedure.checklist[3].when"),
        "step-unknown-key": (_steps("operation", 2, colour="red"), "procedure.operation[2].colour"),
        "step-not-table": (with_field(GP6, "procedure.operation", ["Patch it."]), "procedure.operation[0]"),
        "modes-and-time-scale": (with_field(THAT, "time_scale_s", 0.1), "time_scale_s"),
        "modes-empty": (with_field(THAT, "integrator_modes", []), "time_scale_s"),
        "mode-k0-zero": (_modes(lambda m: m[0].update(k0_per_s=0.0)), "integrator_modes[0].k0_per_s"),
        "mode-k0-string": (_modes(lambda m: m[1].update(k0_per_s="fast")), "integrator_modes[1].k0_per_s"),
        "mode-k0-nan": (_modes(lambda m: m[1].update(k0_per_s=math.nan)), "integrator_modes[1].k0_per_s"),
        "mode-k0-missing": (_modes(lambda m: m[0].pop("k0_per_s")), "integrator_modes[0].k0_per_s"),
        "mode-name-twice": (_modes(lambda m: m[1].update(name="SLOW")), "integrator_modes[1].name"),
        "mode-no-jumpers": (_modes(lambda m: m[0].pop("jumper")), "integrator_modes"),
        "mode-jumper-empty": (_modes(lambda m: m[0].update(jumper="")), "integrator_modes[0].jumper"),
        "mode-unknown-key": (_modes(lambda m: m[0].update(colour="red")), "integrator_modes[0].colour"),
    }
    out += [machine_case(k, data, f) for k, (data, f) in shapes.items()]
    out += field_cases("", UW, BENCH_FIELDS, bench_case)
    out += field_cases("ip02-", IP02, BENCH_FIELDS_MOTOR, bench_case)
    out += [bench_case("ip02-force-limit-given", with_field(IP02, "actuator.force_limit_N", 5.0),
                       "actuator.force_limit_N"),
            bench_case("ip02-counts-of-a-rate", with_field(IP02, "sensors.counts_per_m.s_dot", 100.0),
                       "sensors.counts_per_m.s_dot"),
            bench_case("ip02-filter-of-a-position", with_field(IP02, "sensors.velocity_filter.theta",
                                                               {"wn_rad_s": 60.0, "zeta": 0.9}),
                       "sensors.velocity_filter.theta"),
            bench_case("ip02-inductance-on-lag", with_field(UW, "actuator.L_m", 1e-3), "actuator.L_m")]
    out += [bench_case("tau-short", with_field(UW, "actuator.tau", 1e-5), "actuator.tau"),
            bench_case("noise-unknown-sensor", with_field(UW, "sensors.noise_V_rms.theta_dot", 0.1),
                       "sensors.noise_V_rms.theta_dot"),
            bench_case("noise-nan", with_field(UW, "sensors.noise_V_rms.s", math.nan), "sensors.noise_V_rms.s"),
            bench_case("unknown-track", with_field(UW, "track.length", 1.0), "track.length"),
            bench_case("missing-actuator", {k: v for k, v in UW.items() if k != "actuator"}, "actuator")]
    out += [bench_case(f"range-{name}", {**UW, "uncertainty": table}, f"uncertainty.{key}")
            for name, key, table in RANGE_CASES]
    out += [bench_case("range-distribution", {**UW, "uncertainty": {"distribution": "triangular"}},
                       "uncertainty.distribution")]
    return out


# [uncertainty] ranges that are wrong: (case, key named, table); uw-1991's tau is 0.2 s, dead zone 0.2 V
RANGE_CASES = [
    ("reversed", "tau", {"tau": [0.3, 0.15]}),
    ("inf", "K_U", {"K_U": [11.0, math.inf]}),
    ("nan", "dead_zone_V", {"dead_zone_V": [math.nan, 0.4]}),
    ("unknown", "M", {"M": [3.0, 4.0]}),
    ("unknown-sensor", "sensors.theta_dot", {"sensors.theta_dot": [4.0, 4.4]}),
    ("one-number", "tau", {"tau": 0.2}),
    ("three-numbers", "tau", {"tau": [0.1, 0.2, 0.3]}),
    ("strings", "tau", {"tau": ["0.1", "0.3"]}),
    ("nominal-outside", "dead_zone_V", {"dead_zone_V": [0.3, 0.4]}),
    ("negative", "dead_zone_V", {"dead_zone_V": [-0.1, 0.4]}),
    ("lag-zero", "tau", {"tau": [0.0, 0.3]}),
    ("noise-negative", "noise_V_rms.theta", {"noise_V_rms.theta": [-0.001, 0.004]}),
    ("K_U-below-floor", "K_U", {"K_U": [0.001, 17.0]}),
    ("bool", "K_U", {"K_U": [True, 17.0]}),
]


def spec_for_profile(field: str, target: str) -> dict:
    """A spec whose ``machine`` or ``bench`` names ``target``."""
    return {"spec.toml": dumps(with_field(LAG, field, target))}

