"""A rotary bench identified: bench.toml (a rotary bench profile whose ``[measured_plant]`` holds
every figure of the plant measured or identified, so every bench stage simulates the plant as measured while a spec's
design keeps its own) and plant.toml (a ``[plant]`` table for a spec). Each value carries its 95 %
interval and origin as a comment, as patchgen.identify.profile writes a cart's."""

from __future__ import annotations

import json

from patchgen.identify.profile import SIGNIFICANT, _comment, _line, _num
from patchgen.inputs.validation import validate
from patchgen.plant.rotary_pendulum import MEASURED, PARAMETER_NAMES
from patchgen.profiles.bench import RotaryBenchProfile, check_bench


def _round(x: float) -> float:
    return float(f"{x:.{SIGNIFICANT}g}")


def rotary_profile_data(result, base, bench_id: str, name: str) -> dict:
    """The identified rotary bench as data (RotaryBenchProfile's shape), checked."""
    b, p = result.bench, result.plant
    sens = {q: _round(b[f"sensors.{q}"].value) for q in MEASURED}
    sens["noise_V_rms"] = {q: _round(b[f"sensors.noise_V_rms.{q}"].value) for q in MEASURED
                           if f"sensors.noise_V_rms.{q}" in b}
    sens["noise_bandwidth_Hz"] = _round(b["sensors.noise_bandwidth_Hz"].value)
    sens["counts_per_rev"] = dict(base.sensors.counts_per_rev)
    act = base.actuator.model_dump(exclude_none=True)
    data = {"id": bench_id, "name": name, "plant": base.plant, "actuator": act, "sensors": sens,
            "disturbance": base.disturbance.model_dump(), "scenarios": list(base.scenarios),
            "measured_plant": {k: _round(p[k].value) for k in PARAMETER_NAMES if k in p}}
    check_bench(validate(RotaryBenchProfile, data, "the identified bench"), "the identified bench")
    return data


def rotary_bench_toml(result, base, bench_id: str, name: str, sources: list[str]) -> str:
    """bench.toml for a rotary bench (load_bench reads it)."""
    data = rotary_profile_data(result, base, bench_id, name)
    b, p = result.bench, result.plant
    out = ["# A rotary pendulum's bench profile identified by patchgen identify from " + ", ".join(sources) + ".",
           "# Intervals are 95 %; docs/identify.md says how each value was fitted.",
           f"# Not identified (from the base profile {base.id}): the amplifier, the encoders' counts, the random "
           "forces.", "", f"id = {json.dumps(bench_id)}", f"name = {json.dumps(name)}",
           f'plant = "{base.plant}"', "scenarios = [" + ", ".join(json.dumps(s) for s in data["scenarios"]) + "]",
           "recordings = [", *(f"    {json.dumps(s)}," for s in sources), "]", "",
           f"[actuator]   # base profile {base.id}"]
    for key, v in data["actuator"].items():
        out.append(f"{key} = {json.dumps(v) if isinstance(v, str) else _num(v)}")
    out += ["", "[sensors]"]
    for q in MEASURED:
        out.append(_line(f"{q} = {_num(data['sensors'][q])}", _comment(b[f"sensors.{q}"])))
    noise = data["sensors"]["noise_V_rms"]
    out.append("noise_V_rms = { " + ", ".join(f"{k} = {_num(v)}" for k, v in noise.items()) + " }")
    out += [f"#   {k}: {_comment(b[f'sensors.noise_V_rms.{k}'])}" for k in noise]
    out.append(_line(f"noise_bandwidth_Hz = {_num(data['sensors']['noise_bandwidth_Hz'])}",
                     _comment(b["sensors.noise_bandwidth_Hz"])))
    counts = data["sensors"]["counts_per_rev"]
    out.append("counts_per_rev = { " + ", ".join(f"{k} = {_num(v)}" for k, v in counts.items())
               + f" }}   # base profile {base.id}")
    out += ["", "[disturbance]   # assumed levels, as the base profile's"]
    out += [f"{k} = {_num(v)}" for k, v in data["disturbance"].items()]
    out += ["", "[measured_plant]   # the plant as identified: the bench's stages simulate it, a spec keeps its own"]
    out += [_line(f"{k} = {_num(v)}", _comment(p[k])) for k, v in data["measured_plant"].items()]
    return "\n".join(out) + "\n"


def rotary_plant_toml(result, sources: list[str]) -> str:
    """plant.toml: a ``[plant]`` table of the rotary pendulum as measured and identified."""
    p = result.plant
    out = ["# The rotary pendulum identified by patchgen identify from " + ", ".join(sources) + ".",
           "# Paste the [plant] table into a spec; intervals are 95 %.", "", "[plant]", 'model = "rotary-pendulum"']
    out += [_line(f"{k} = {_num(float(p[k].value))}", _comment(p[k])) for k in PARAMETER_NAMES if k in p]
    return "\n".join(out) + "\n"
