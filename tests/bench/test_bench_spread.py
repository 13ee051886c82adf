"""Each run's bench drawn from the profile's ranges: a drawn run is the run on that bench, the
other draws are untouched, the draws follow their distribution, and the whole is deterministic."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import stats

from patchgen.bench import bench_spread
from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config
from patchgen.bench.engine import draw_batch
from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.scenario import Scenario, load_scenario
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import BenchProfile, load_bench
from patchgen.profiles.machine import load_machine
from patchgen.profiles.uncertainty import BenchUncertainty, bench_at
from tests.conftest import design_path

GP6 = load_machine("gp6")
UNCERTAIN = load_bench("uw-1991-uncertain")
SPEC = load_spec(design_path("bench-recommended"))
DESIGN = design_on(SPEC, GP6, UNCERTAIN)
NET = build_patch(DESIGN, GP6)
PLANT = plant_params(DESIGN.spec)
PUSH = load_scenario("finger-push").model_copy(update={"duration_s": 4.0})


def _with(ranges: dict, distribution: str = "uniform") -> BenchProfile:
    return UNCERTAIN.model_copy(update={"uncertainty": BenchUncertainty(distribution=distribution, **ranges)})


EVERYTHING = _with({"K_U": [11.0, 17.0], "tau": [0.15, 0.3], "dead_zone_V": [0.1, 0.4], "force_limit_N": [12.0, 18.0],
                    "sensors.theta": [4.0, 4.4], "sensors.s": [4.8, 5.2], "noise_V_rms.theta": [0.0, 0.01],
                    "cart_force_N_rms": [0.05, 0.5], "tip_force_N_rms": [0.0, 0.05]})


def _config(bench: BenchProfile, scenario: Scenario = PUSH, **kw):
    return engine_config(compile_circuit(NET, GP6, bench), PLANT, bench, GP6, scenario, **kw)[0]


def _rngs(n: int, seed: int = 3):
    return [np.random.default_rng([seed, i]) for i in range(n)]


def test_a_drawn_run_is_the_run_on_the_bench_it_drew():
    """Run i with a bench spread is, summary for summary, run i without one on the bench it drew:
    every drawn value (actuator, sensor constant, noise level, random force) reaches the engine."""
    cfg = _config(EVERYTHING, bench_spread=True)
    draws = draw_batch(cfg, _rngs(3))
    spread = simulate(NET, PLANT, EVERYTHING, GP6, PUSH, seed=3, runs=3, keep_history=False, bench_spread=True)
    for i in range(3):
        rng = _rngs(i + 1)[i]
        rng.random(len(NET.amplifiers))
        rng.integers(0, 2**32, size=2)
        values = bench_spread.draw(cfg.bench_spread, rng)
        drawn = dict(zip(cfg.bench_spread.keys, values))
        assert draws.actuators[i, 0] == drawn["K_U"] and draws.actuators[i, 2] == drawn["dead_zone_V"]
        one = simulate(NET, PLANT, bench_at(EVERYTHING, drawn), GP6, PUSH, seed=3, runs=1, first_run=i,
                       keep_history=False)
        assert one.runs[0] == dataclasses.replace(spread.runs[i], drawn=())
        # and the run reports what it drew (runs.csv): every key, read back from the engine's arrays
        reported = dict(spread.runs[i].drawn)
        assert list(reported) == list(cfg.bench_spread.keys)
        assert reported == pytest.approx(drawn, rel=1e-12)
    # and the drawn benches differ from the nominal one: the spread is not a no-op
    nominal = simulate(NET, PLANT, EVERYTHING, GP6, PUSH, seed=3, runs=3, keep_history=False)
    assert [r.max_abs_theta_deg for r in nominal.runs] != [r.max_abs_theta_deg for r in spread.runs]


def test_the_bench_draw_leaves_the_other_draws_alone():
    """Noise keys, drift signs and the plant spread are the same bytes with and without a bench spread."""
    plain = draw_batch(_config(EVERYTHING, spread={"M": 0.1}), _rngs(8))
    spread = draw_batch(_config(EVERYTHING, spread={"M": 0.1}, bench_spread=True), _rngs(8))
    for name in ("keys", "signs", "plants"):
        assert np.array_equal(getattr(plain, name), getattr(spread, name))
    assert not np.array_equal(plain.actuators, spread.actuators)
    assert np.all(plain.actuators == plain.actuators[0])


def test_uniform_draws_fill_their_ranges():
    """Uniform: every draw inside its range; over 4000 runs the mean within 3 % of the width of the
    midpoint and the spread (std) that of a uniform distribution, width / sqrt(12), within 3 %."""
    sp = _config(EVERYTHING, bench_spread=True).bench_spread
    v = np.array([bench_spread.draw(sp, rng) for rng in _rngs(4000, seed=11)])
    width = sp.high - sp.low
    assert np.all(v >= sp.low) and np.all(v <= sp.high)
    assert np.all(np.abs(v.mean(axis=0) - (sp.low + sp.high) / 2) < 0.03 * width)
    assert np.all(np.abs(v.std(axis=0) / (width / np.sqrt(12)) - 1) < 0.03)


def test_normal_draws_are_a_truncated_normal():
    """Normal: the range is +/- 2 sigma, truncated; mean and std agree with scipy's truncnorm
    within 3 % of the width over 4000 runs."""
    b = _with({"K_U": [11.0, 17.0], "dead_zone_V": [0.1, 0.4]}, "normal")
    sp = _config(b, bench_spread=True).bench_spread
    v = np.array([bench_spread.draw(sp, rng) for rng in _rngs(4000, seed=5)])
    for k in range(2):
        lo, hi = sp.low[k], sp.high[k]
        oracle = stats.truncnorm(-2, 2, loc=(lo + hi) / 2, scale=(hi - lo) / 4)
        assert lo <= v[:, k].min() and v[:, k].max() <= hi
        assert abs(v[:, k].mean() - oracle.mean()) < 0.03 * (hi - lo)
        assert abs(v[:, k].std() - oracle.std()) < 0.03 * (hi - lo)
        # narrower than a uniform over the same range
        assert v[:, k].std() < 0.9 * (hi - lo) / np.sqrt(12)


def test_ranges_the_run_cannot_feel_are_not_drawn():
    """ideal keeps only K_U and the sensor constants; a scenario with explicit or no noise sets the
    noise levels and forces itself."""
    assert set(bench_spread.active_ranges(EVERYTHING, True, True)) == {"K_U", "sensors.theta", "sensors.s"}
    quiet = set(bench_spread.active_ranges(EVERYTHING, False, False))
    assert quiet == {"K_U", "tau", "dead_zone_V", "force_limit_N", "sensors.theta", "sensors.s"}


def test_a_bench_spread_is_deterministic_and_reported():
    a = simulate(NET, PLANT, EVERYTHING, GP6, PUSH, seed=9, runs=5, keep_history=False, bench_spread=True)
    b = simulate(NET, PLANT, EVERYTHING, GP6, PUSH, seed=9, runs=5, keep_history=False, bench_spread=True)
    assert a.summary() == b.summary() and a.runs == b.runs
    assert a.settings.bench_spread["dead_zone_V"] == [0.1, 0.4] and a.settings.bench_distribution == "uniform"


@pytest.mark.parametrize("dead_zone", [0.1, 0.4])
def test_a_range_of_one_value_is_that_value(dead_zone):
    """A range with low = high is that value in every run: the runs equal the bench at that value."""
    fixed = bench_at(UNCERTAIN, {"dead_zone_V": dead_zone})
    one = fixed.model_copy(update={"uncertainty": BenchUncertainty(dead_zone_V=[dead_zone, dead_zone])})
    a = simulate(NET, PLANT, one, GP6, PUSH, seed=2, runs=2, keep_history=False, bench_spread=True)
    c = simulate(NET, PLANT, fixed, GP6, PUSH, seed=2, runs=2, keep_history=False)
    assert [dataclasses.replace(r, drawn=()) for r in a.runs] == c.runs
    assert all(r.drawn == (("dead_zone_V", dead_zone),) for r in a.runs)
