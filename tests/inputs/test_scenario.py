"""Scenario files: the shipped ones load, a bad field gets one line naming file and field."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import NoiseLevels, load_scenario

SIMS = Path(__file__).resolve().parents[2] / "sims"


@pytest.mark.parametrize("name", ["offset-10deg", "finger-push", "step-cart", "hold-120s"])
def test_shipped_scenarios_load(name):
    sc = load_scenario(SIMS / f"{name}.toml")
    assert sc.name == name and sc.duration_s > 0


def test_offset_scenario_values():
    sc = load_scenario(SIMS / "offset-10deg.toml")
    assert sc.initial.vector()[1] == pytest.approx(math.radians(10.0))
    assert sc.duration_s == 10.0
    assert load_scenario(SIMS / "hold-120s.toml").duration_s == 120.0
    step = load_scenario(SIMS / "step-cart.toml").disturbances[0]
    assert (step.kind, step.size_m) == ("step", 0.2)


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "bad.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("text, field", [
    ("duration_s = 10\nduraton = 3\n", "duraton"),
    ("duration_s = -1\n", "duration_s"),
    ("duration_s = 1\nnoise = 'loud'\n", "noise"),
    ("duration_s = 1\ndrift = 'lots'\n", "drift"),
    ("duration_s = 1\n[noise]\ntheta = 'x'\n", "noise.theta"),
    ("duration_s = 1\n[initial]\ntheta = 0.1\ntheta_deg = 5\n", "initial.theta_deg"),
    ("duration_s = 1\n[[disturbances]]\nkind = 'force_impulse'\ntime_s = 1\nat = 'cart'\n"
     "duration_s = 0.1\nforce_N = 'big'\n", "disturbances[0].force_N"),
    ("duration_s = 2\n[[disturbances]]\nkind = 'step'\ntime_s = 1\n", "disturbances[0].size_m"),
    ("duration_s = 1\n[[disturbances]]\nkind = 'kick'\ntime_s = 1\n", "disturbances[0].kind"),
])
def test_bad_field_is_one_line_with_file_and_field(tmp_path, text, field):
    path = _write(tmp_path, text)
    with pytest.raises(InputError) as exc:
        load_scenario(path)
    err = exc.value
    assert err.source == str(path) and err.field == field
    assert err.exit_status == 2 and "\n" not in err.line()


def test_noise_levels_explicit(tmp_path):
    sc = load_scenario(_write(tmp_path, "duration_s = 1\n[noise]\ntheta = 0.01\n"))
    assert sc.noise == NoiseLevels(mode="explicit", theta=0.01)
    assert load_scenario(_write(tmp_path, "duration_s = 1\nnoise = 'off'\n")).noise.mode == "off"
    assert load_scenario(_write(tmp_path, "duration_s = 1\ndrift = 0.004\n")).drift == 0.004


def test_the_shortest_run_is_a_few_of_the_engines_steps(tmp_path):
    """COARSEST_STEP_S is the engine's coarsest own step; a run of MIN_RUN_STEPS of them loads."""
    from patchgen.bench.engine import BENCH_DT_S, IDEAL_DT_S
    from patchgen.inputs.scenario import COARSEST_STEP_S, MIN_RUN_STEPS

    assert COARSEST_STEP_S == max(BENCH_DT_S, IDEAL_DT_S)
    p = tmp_path / "short.toml"
    p.write_text(f"duration_s = {MIN_RUN_STEPS * COARSEST_STEP_S}\n")
    assert load_scenario(p).duration_s == pytest.approx(0.05)
    p.write_text("duration_s = 2e-5\ndt_s = 4e-6\n")
    assert load_scenario(p).duration_s == 2e-5
