"""The bench and plant the identify tests record on: unlike uw-1991 and table B.1 in every value
identify fits, with the profile's random forces."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchProfile, load_bench

TRUE_PLANT = PlantParams(M=3.552, m=0.324, l=0.40, g=9.807, b_VF=3.5, c=0.002, d=1.090)
TRUE_BENCH = {"actuator.K_U": 11.0, "actuator.tau": 0.3, "actuator.dead_zone_V": 0.35,
              "sensors.s": 4.5, "sensors.theta": 3.8, "sensors.s_dot": 0.62,
              "sensors.noise_V_rms.s": 0.003, "sensors.noise_V_rms.theta": 0.0015,
              "sensors.noise_V_rms.s_dot": 0.008, "sensors.noise_bandwidth_Hz": 150.0}


def true_bench(**actuator) -> BenchProfile:
    """uw-1991 with every identified value changed (TRUE_BENCH), the actuator's fields as given."""
    b = load_bench("uw-1991").model_dump()
    b["id"], b["name"] = "test-bench", "a bench unlike uw-1991"
    for key, value in TRUE_BENCH.items():  # the one place the true values are written
        *path, last = key.split(".")
        table = b
        for part in path:
            table = table[part]
        table[last] = value
    b["actuator"].update(**actuator)
    return BenchProfile.model_validate(b)


def bench_toml(path: Path) -> Path:
    """true_bench() as a profile file."""
    b = true_bench()
    a, s, d = b.actuator, b.sensors, b.disturbance
    noise = ", ".join(f"{k} = {v}" for k, v in s.noise_V_rms.items())
    path.write_text(f'id = "test-bench"\nname = "a bench unlike uw-1991"\n\n[actuator]\nmodel = "{a.model}"\n'
                    f"K_U = {a.K_U}\ntau = {a.tau}\ndead_zone_V = {a.dead_zone_V}\n"
                    f"force_limit_N = {a.force_limit_N}\n\n"
                    f"[sensors]\ns = {s.s}\ntheta = {s.theta}\ns_dot = {s.s_dot}\nnoise_V_rms = {{ {noise} }}\n"
                    f"noise_bandwidth_Hz = {s.noise_bandwidth_Hz}\n\n[disturbance]\n"
                    f"cart_force_N_rms = {d.cart_force_N_rms}\ntip_force_N_rms = {d.tip_force_N_rms}\n"
                    f"bandwidth_Hz = {d.bandwidth_Hz}\n")
    return path


def spec_toml(path: Path, bench: str, plant: str | None = None) -> Path:
    """bench-recommended with the true plant (or a [plant] table's text) on ``bench``."""
    from tests.conftest import DESIGNS

    text = (DESIGNS / "bench-recommended.toml").read_text().replace('bench = "uw-1991"', f'bench = "{bench}"')
    start, end = text.index("[plant]"), text.index("[sensors]")
    p = TRUE_PLANT
    table = plant or (f"[plant]\nM = {p.M}\nm = {p.m}\nl = {p.l}\ng = {p.g}\nb_VF = {p.b_VF}\nc = {p.c}\n"
                      f"d = {p.d}\n")
    path.write_text(text[:start] + table + "\n" + text[end:])
    return path


def csv(path: Path, test: str, columns: dict[str, np.ndarray]) -> Path:
    """A recording file of ``test`` with the given columns."""
    names = list(columns)
    rows = "\n".join(", ".join(f"{v:.10g}" for v in row) for row in zip(*columns.values()))
    path.write_text(f"# test = {test}\n{', '.join(names)}\n{rows}\n")
    return path
