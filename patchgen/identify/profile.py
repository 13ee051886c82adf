"""The identified bench as a bench profile (bench.toml, which patchgen.profiles.bench.load_bench reads,
so a spec takes it as ``bench = "path/bench.toml"``) and the plant as a ``[plant]`` table to paste
into a spec (plant.toml). Each value carries its 95 % interval and origin as a comment.

Values are written to SIGNIFICANT digits, a few more than any interval resolves.
"""

from __future__ import annotations

import json

from patchgen.identify.identify import MIN_LAG_S, Identification, Parameter
from patchgen.identify.plausible import field_bounds
from patchgen.inputs.spec import PlantSpec
from patchgen.inputs.validation import validate
from patchgen.plant.cart_pendulum import MEASURED, PARAMETER_NAMES, UNCERTAIN
from patchgen.profiles.bench import BenchActuator, BenchProfile, BenchSensors, check_bench
from patchgen.profiles.uncertainty import RANGE_FIELDS as RANGED_FIELDS

# identified value (Identification key) -> its [uncertainty] key (patchgen.profiles.uncertainty)
RANGED = {"actuator.K_U": "K_U", "actuator.tau": "tau", "actuator.dead_zone_V": "dead_zone_V",
          "sensors.s": "sensors.s", "sensors.theta": "sensors.theta", "sensors.s_dot": "sensors.s_dot",
          "sensors.noise_V_rms.s": "noise_V_rms.s", "sensors.noise_V_rms.theta": "noise_V_rms.theta",
          "sensors.noise_V_rms.s_dot": "noise_V_rms.s_dot"}

SIGNIFICANT = 6
PLANT_ORDER = PARAMETER_NAMES  # the [plant] table's order (patchgen.plant.cart_pendulum)


def _num(x: float) -> str:
    text = f"{x:.{SIGNIFICANT}g}"
    return text if any(ch in text for ch in ".en") else text + ".0"


def _line(text: str, comment: str) -> str:
    return f"{text:<27} # {comment}"


def _comment(p: Parameter) -> str:
    if p.estimate is None:
        return f"{p.unit}, {p.origin}".strip(", ")
    e = p.estimate
    return f"{p.unit}, 95 %: {e.low:.4g} to {e.high:.4g} ({e.source})"


def profile_data(result: Identification, base: BenchProfile, bench_id: str, name: str) -> dict:
    """The bench profile as data (the shape patchgen.profiles.bench.BenchProfile reads).

    Parameters
    ----------
    result : Identification
        What identify found.
    base : BenchProfile
        The profile the rest comes from (track, random forces).
    bench_id, name : str
        The new profile's id and name.

    Returns
    -------
    dict
        Checked by BenchProfile: a bug, not bad input, if it fails.
    """
    b = result.bench
    act = {k.removeprefix("actuator."): p.value for k, p in b.items() if k.startswith("actuator.")}
    noise = {k.rsplit(".", 1)[1]: p.value for k, p in b.items() if k.startswith("sensors.noise_V_rms.")}
    sens = {**{q: b[f"sensors.{q}"].value for q in MEASURED},
            "noise_V_rms": noise, "noise_bandwidth_Hz": b["sensors.noise_bandwidth_Hz"].value,
            **_read_as(base)}
    data = {"id": bench_id, "name": name, "actuator": act, "sensors": sens,
            "track": base.track.model_dump(), "disturbance": base.disturbance.model_dump()}
    data = json.loads(json.dumps(data), parse_float=lambda s: float(f"{float(s):.{SIGNIFICANT}g}"))
    data["uncertainty"] = _ranges(result, data)
    check_bench(validate(BenchProfile, data, "the identified bench"), "the identified bench")
    return data


def _read_as(base: BenchProfile) -> dict:
    """How the base bench reads its sensors (encoders' counts, a filtered velocity): its hardware,
    not identified, kept as the base profile states it."""
    s = base.sensors
    out = {k: dict(getattr(s, k)) for k in ("counts_per_m", "counts_per_rev") if getattr(s, k)}
    if s.velocity_filter:
        out["velocity_filter"] = {q: f.model_dump() for q, f in s.velocity_filter.items()}
    return out


def _ranges(result: Identification, data: dict) -> dict:
    """The [uncertainty] table from the 95 % intervals: a normal draw whose +/-2 sigma is the interval
    (the range the simulator and recommend draw benches from). Ends are rounded outward to
    SIGNIFICANT digits, then kept within what the profile's field takes (a lag's low end at
    least MIN_LAG_S, a sensor constant's at least its floor)."""
    out: dict = {"distribution": "normal"}
    for key, name in RANGED.items():
        p = result.bench.get(key)
        e = p.estimate if p is not None else None
        if e is None or isinstance(p.value, str) or (key == "actuator.tau" and data["actuator"]["model"] == "gain"):
            continue
        v = float(p.value)
        lo, hi = min(e.low, v), max(e.high, v)
        lo = float(f"{max(lo, 0.0) * (1 - 1e-6):.{SIGNIFICANT}g}")
        hi = float(f"{hi * (1 + 1e-6):.{SIGNIFICANT}g}")
        # within what the profile's field takes (a lag at least MIN_LAG_S): the interval may reach past it
        floor, top = _bounds(name)
        out[name] = [min(max(lo, floor), v), max(min(hi, top), v)]
    return out


def _bounds(key: str) -> tuple[float, float]:
    """The [low, high] a bench profile takes for an [uncertainty] key (a lag: at least MIN_LAG_S)."""
    path = RANGED_FIELDS[key]
    model = {"actuator": BenchActuator, "sensors": BenchSensors}[path[0]]
    lo, hi = field_bounds(model, path[1]) if len(path) == 2 else (0.0, 100.0)
    return (max(lo, MIN_LAG_S) if key == "tau" else max(lo, 0.0)), hi


def bench_toml(result: Identification, base: BenchProfile, bench_id: str, name: str, sources: list[str]) -> str:
    """bench.toml: the identified bench profile with each value's interval and origin.

    Parameters
    ----------
    result : Identification
        What identify found.
    base : BenchProfile
        The profile the rest comes from.
    bench_id, name : str
        The new profile's id and name.
    sources : list of str
        The recordings, named in the header.

    Returns
    -------
    str
        TOML text load_bench reads.
    """
    data = profile_data(result, base, bench_id, name)
    b = result.bench
    motor = data["actuator"]["model"] == "dc_motor"
    kept = ("the motor's figures and the amplifier's limit (the force limit follows from them)" if motor
            else "the force limit") + (", the encoders and the velocity filter" if _read_as(base) else "")
    out = ["# A bench profile identified by patchgen identify from " + ", ".join(sources) + ".",
           "# Intervals are 95 %; docs/identify.md says how each value was fitted.",
           f"# Not identified (from the base profile {base.id}): {kept}, the track, the random forces.",
           *(["# The measured force per command volt K_U is written as amp_gain = K_U / a (K_U follows from the",
              "# motor for a dc_motor); the plant's b_VF is the coast-down's total damping less the back-EMF's."]
             if motor else []),
           "", f"id = {json.dumps(bench_id)}", f"name = {json.dumps(name)}",
           "recordings = [", *(f"    {json.dumps(s)}," for s in sources), "]", "", "[actuator]"]
    for key, v in data["actuator"].items():
        p = b[f"actuator.{key}"]
        out.append(_line(f"{key} = {json.dumps(v) if isinstance(v, str) else _num(v)}", _comment(p)))
    out += ["", "[sensors]"]
    for key in MEASURED:
        out.append(_line(f"{key} = {_num(data['sensors'][key])}", _comment(b[f"sensors.{key}"])))
    noise = data["sensors"]["noise_V_rms"]
    out.append("noise_V_rms = { " + ", ".join(f"{k} = {_num(v)}" for k, v in noise.items()) + " }")
    for k in noise:
        out.append(f"#   {k}: {_comment(b[f'sensors.noise_V_rms.{k}'])}")
    out.append(_line(f"noise_bandwidth_Hz = {_num(data['sensors']['noise_bandwidth_Hz'])}",
                     _comment(b["sensors.noise_bandwidth_Hz"])))
    for key in ("counts_per_m", "counts_per_rev"):
        if key in data["sensors"]:
            out.append(f"{key} = {{ " + ", ".join(f"{k} = {_num(v)}" for k, v in data["sensors"][key].items())
                       + f" }}   # base profile {base.id}")
    for q, f in data["sensors"].get("velocity_filter", {}).items():
        out.append(f"velocity_filter = {{ {q} = {{ wn_rad_s = {_num(f['wn_rad_s'])}, zeta = {_num(f['zeta'])} }} }}"
                   f"   # base profile {base.id}")
    out += ["", "[track]", f"limit_switches = {'true' if data['track']['limit_switches'] else 'false'}",
            "", "[disturbance]   # assumed levels, as the base profile's"]
    for k, v in data["disturbance"].items():
        out.append(f"{k} = {_num(v)}")
    out += ["", "[uncertainty]   # the 95 % intervals above as ranges: simulate --bench-spread and recommend draw "
            "from them", f'distribution = "{data["uncertainty"]["distribution"]}"   # the range is +/-2 sigma']
    for k, v in data["uncertainty"].items():
        if k != "distribution":
            out.append(f'{json.dumps(k) if "." in k else k} = [{_num(v[0])}, {_num(v[1])}]')
    return "\n".join(out) + "\n"


def plant_toml(result: Identification, sources: list[str]) -> str:
    """plant.toml: a ``[plant]`` table with what was measured and identified, to paste into a spec.

    Parameters
    ----------
    result : Identification
        What identify found.
    sources : list of str
        The recordings, named in the header.

    Returns
    -------
    str
        TOML text; a comment names any parameter no recording gave (the spec must supply it).
    """
    p = result.plant
    missing = [k for k in UNCERTAIN if k not in p]
    out = ["# The plant identified by patchgen identify from " + ", ".join(sources) + ".",
           "# Paste the [plant] table into a spec; intervals are 95 %."]
    if missing:
        out.append(f"# Not given by the recordings (the spec must supply them): {', '.join(missing)}.")
    else:
        validate(PlantSpec, {k: float(f"{p[k].value:.{SIGNIFICANT}g}") for k in p}, "the identified plant")
    out += ["", "[plant]"]
    for k in PLANT_ORDER:
        if k in p:
            out.append(_line(f"{k} = {_num(float(p[k].value))}", _comment(p[k])))
    return "\n".join(out) + "\n"
