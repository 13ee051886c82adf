"""The compiled loop: same plant equations as patchgen.plant.equations, the noise model, and the step."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config
from patchgen.bench.engine import LANES, SPLIT_FROM, default_step, noise_process, plan_blocks
from patchgen.bench.simulate import simulate
from patchgen.inputs.scenario import Scenario, load_scenario
from patchgen.patch.netlist import read_netlist
from patchgen.plant.compiled import plant_rhs, plant_vector
from patchgen.plant.equations import PlantParams, nonlinear_rhs
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine

ROOT = Path(__file__).resolve().parents[2]
# thesis table B.1
PLANT = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)
P = plant_vector(PLANT)  # the whole vector: the compiled code reads every entry, unchecked


def test_plant_rhs_is_eq_2_16_to_2_19():
    rng = np.random.default_rng(0)
    for _ in range(50):
        x = rng.normal(size=4) * [0.3, 1.0, 1.0, 3.0]
        f = float(rng.normal() * 10)
        assert plant_rhs(P, x[1], x[2], x[3], f, 0.0) == pytest.approx(
            tuple(nonlinear_rhs(PLANT, x, f)), rel=1e-12, abs=1e-12)


def test_tip_force_upright_turns_the_pendulum_not_the_cart():
    """A horizontal push at the tip of the upright point-mass pendulum: the rod carries no
    horizontal force, so s_ddot = 0 and theta_ddot = F / (m l)."""
    _, _, sdd, thdd = plant_rhs(P, 0.0, 0.0, 0.0, 0.0, 1.0)
    assert sdd == 0.0
    assert thdd == pytest.approx(1.0 / (PLANT.m * PLANT.l))


@pytest.mark.parametrize("dt", [1e-3, 2e-3, 1e-2])
def test_noise_process_keeps_the_low_frequency_density(dt):
    """White noise of rms sigma over bandwidth B has one-sided density sigma^2 / B."""
    sigma, band = 0.002, 200.0
    a, std = noise_process(sigma, band, dt)
    # low-frequency one-sided density of x' = a x + std w: 2 dt std^2 / (1 - a)^2
    density = 2.0 * dt * std**2 / (1.0 - a) ** 2
    assert density == pytest.approx(sigma**2 / band, rel=1e-2 if a == 0.0 else 0.15)
    assert noise_process(0.0, band, dt) == (0.0, 0.0)


@pytest.mark.parametrize("name", ["offset-10deg", "finger-push", "step-cart"])
@pytest.mark.parametrize("ideal", [True, False])
def test_halving_the_default_step_moves_theta_less_than_1e_4_rad_rms(name, ideal):
    """The step's accuracy rule, measured with noise off (a noise realisation depends on the
    step); the bench runs include dead zone, lag, clipping and the limit switches."""
    net = read_netlist(ROOT / "tests/fixtures/thesis-ch5.netlist.json")
    bench, gp6 = load_bench("uw-1991"), load_machine("gp6")
    base = load_scenario(ROOT / "sims" / f"{name}.toml").model_dump()
    _, settings = engine_config(compile_circuit(net, gp6, bench), PLANT, bench, gp6,
                                Scenario.model_validate(base), ideal=ideal)
    step = settings.dt_s
    assert step == (0.01 if ideal else 0.002)  # the defaults this test measures
    runs = []
    for dt in (step, step / 2):
        sc = Scenario.model_validate({**base, "noise": "off", "dt_s": dt, "record_dt_s": 0.01})
        h = simulate(net, PLANT, bench, gp6, sc, ideal=ideal).history
        runs.append((np.round(h["t"], 9), h["theta"]))
    _, i, j = np.intersect1d(runs[0][0], runs[1][0], return_indices=True)
    assert len(i) > 100
    rms = math.sqrt(np.mean((runs[0][1][i] - runs[1][1][j]) ** 2))
    assert rms < 1e-4


def test_default_step_resolves_the_fastest_time_constant():
    assert default_step([], ideal=False) == 0.002
    assert default_step([], ideal=True) == 0.01
    assert default_step([0.001, 0.2], ideal=True) == 0.001


@settings(max_examples=300, deadline=None)
@given(runs=st.integers(1, 5000), threads=st.integers(1, 8))
def test_blocks_cover_the_runs_evenly_and_fill_the_threads(runs, threads):
    """Every run in exactly one block, in order; at most LANES a block, sizes within one of each
    other but the last; a multiple of the threads whenever each block still holds SPLIT_FROM."""
    blocks = plan_blocks(runs, threads)
    assert [lo for lo, _ in blocks] == list(np.cumsum([0] + [n for _, n in blocks[:-1]]))
    sizes = [n for _, n in blocks]
    assert sum(sizes) == runs and max(sizes) <= LANES and min(sizes) >= 1
    assert len(set(sizes[:-1])) <= 1 and sizes[-1] <= sizes[0]
    fewest = -(-runs // LANES)
    whole = -(-fewest // threads) * threads
    assert len(blocks) == (whole if runs >= whole * SPLIT_FROM else fewest)
