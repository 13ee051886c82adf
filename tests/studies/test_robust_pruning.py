"""The robust search drops a grid point as soon as its corners so far rank no better than the best
point's, and still chooses what running every point at every corner would choose.

The bench's runs are replaced by a table (runs held and cart excursion per point, scenario and
corner, drawn from a seed), so the real search and the real corner study are checked against a
brute-force ranking of the whole table."""

import random
from types import SimpleNamespace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.spec import load_spec
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.studies import bench_corners, robust
from tests.conftest import design_path

SPEC = load_spec(design_path("bench-recommended"))
GP6 = load_machine("gp6")
UNCERTAIN = load_bench("uw-1991-uncertain")
SCENARIOS = [load_scenario(n) for n in ("offset-10deg", "finger-push", "step-cart", "hold-120s")]


def _table(seed: int, point: int, scenario: str, corner: tuple) -> tuple[int, float]:
    """Runs held (of SEARCH_RUNS) and the cart excursion (m) at one corner: few values, so ties happen."""
    p = random.Random(f"{seed}/{point}")  # each point its own worst deficit and excursion
    most, base = p.choice((0, 1, 2)), p.choice((0.1, 0.2, 0.3))
    r = random.Random(f"{seed}/{point}/{scenario}/{corner}")
    return robust.SEARCH_RUNS - r.choice(range(most + 1)), base + r.choice((0.0, 0.0, 0.0, 0.01, 0.02))


def _corner(bench) -> tuple:
    a = bench.actuator
    return a.K_U, a.tau, a.dead_zone_V


def _fake_bench(monkeypatch, seed: int) -> list:
    """Replace design, patch and simulation by the table; returns the list of simulations run."""
    points, ran = iter(range(10 ** 6)), []
    monkeypatch.setattr(robust, "design_on", lambda sp, machine, bench: SimpleNamespace(spec=sp))
    monkeypatch.setattr(robust, "build_patch", lambda d, machine, units: SimpleNamespace(point=next(points)))
    monkeypatch.setattr(robust, "plant_params", lambda spec: None)

    def simulate(net, plant, bench, machine, scenario, *, runs, **_):
        held, excursion = _table(seed, net.point, scenario.name, _corner(bench))
        ran.append((net.point, scenario.name, _corner(bench)))
        return SimpleNamespace(runs=[SimpleNamespace(held=i < held, overloads=(), fall_time_s=None,
                                                     trip_time_s=None, max_abs_s_m=excursion, max_abs_u_c_V=1.0)
                                     for i in range(runs)])

    monkeypatch.setattr(bench_corners, "simulate", simulate)
    return ran


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10 ** 9))
def test_the_pruned_search_chooses_what_the_full_table_ranks_first(seed):
    with pytest.MonkeyPatch.context() as mp:
        ran = _fake_bench(mp, seed)
        choice = robust.search(SPEC, GP6, UNCERTAIN, SCENARIOS)
    grid = robust.grid_specs(SPEC, UNCERTAIN)
    corners = [tuple(c[k] for k in ("K_U", "tau", "dead_zone_V"))
               for c in bench_corners.corner_values(UNCERTAIN, UNCERTAIN.uncertainty.ranges)[0]]
    keys = []
    for point in range(len(grid)):
        cells = [_table(seed, point, sc.name, c) for sc in SCENARIOS for c in corners]
        keys.append((min(h for h, _ in cells), -round(max(e for _, e in cells), 4)))
    best = max(range(len(grid)), key=lambda i: (keys[i], -i))  # ties: the first point
    factors, integral, _ = grid[best]
    assert (choice.factors, choice.integral_s, choice.held) == (factors, integral, keys[best][0])
    assert choice.tried == len(grid)
    assert len(ran) < len(grid) * len(SCENARIOS) * len(corners)  # points were dropped early
