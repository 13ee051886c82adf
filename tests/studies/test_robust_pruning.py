"""The robust search runs best first (the point whose corners so far rank highest runs its next
few) and still chooses what running every point at every corner would choose; the corners it
ran on the chosen patch are taken up by recommend's corner study of that patch, not run again.

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


def _fake_bench(monkeypatch, seed: int) -> list:
    """Replace design, patch and simulation by the table; returns the list of simulations run."""
    points, ran = iter(range(10 ** 6)), []
    monkeypatch.setattr(robust, "design_on", lambda sp, machine, bench: SimpleNamespace(spec=sp, plant=None))
    monkeypatch.setattr(robust, "build_patch", lambda d, machine, units: SimpleNamespace(point=next(points)))

    def at(net, scenario, corner, runs):
        held, excursion = _table(seed, net.point, scenario.name, corner)
        ran.append((net.point, scenario.name, corner))
        return [SimpleNamespace(held=i < held, overloads=(), fall_time_s=None, trip_time_s=None,
                                max_abs_s_m=excursion, max_abs_u_c_V=1.0, actuator_limit_time_s=0.0)
                for i in range(runs)]

    def simulate_points(net, plant, bench, machine, scenario, points, *, runs, **_):
        return [at(net, scenario, tuple(p[k] for k in ("K_U", "tau", "dead_zone_V")), runs) for p in points]

    monkeypatch.setattr(bench_corners, "simulate_points", simulate_points)
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


def test_a_study_takes_known_corners_as_they_are_and_runs_the_rest():
    """Corners already run (the robust search's, on the same patch) are not run again, and the
    study is the one a fresh run gives."""
    from patchgen.design.lqg import design_on
    from patchgen.design.model import plant_params
    from patchgen.patch.build import build_patch

    d = design_on(SPEC, GP6, UNCERTAIN)
    net, plant = build_patch(d, GP6), plant_params(d.spec)
    push = load_scenario("finger-push").model_copy(update={"duration_s": 2.0})
    fresh = bench_corners.study(net, plant, UNCERTAIN, GP6, push, corner_runs=8, ends=True)
    ran = []
    with pytest.MonkeyPatch.context() as mp:
        real = bench_corners.simulate_points
        mp.setattr(bench_corners, "simulate_points", lambda *a, **k: ran.extend(a[5]) or real(*a, **k))
        again = bench_corners.study(net, plant, UNCERTAIN, GP6, push, corner_runs=8, ends=True,
                                    known=fresh.corners[:5])
    assert again.as_dict() == fresh.as_dict()
    assert len(ran) == len(fresh.corners) - 5 + len(fresh.ends)
    assert not any(k.values in ran for k in fresh.corners[:5])
    # run together or a few at a time (as the robust search runs them), the same figures
    steps = list(bench_corners.study_in_steps(net, plant, UNCERTAIN, GP6, push, corner_runs=8))
    assert [whole for _, whole in steps] == [False] * (len(steps) - 1) + [True] and len(steps) > 1
    assert all(st.corners == fresh.corners[:len(st.corners)] for st, _ in steps)
    assert steps[-1][0].corners == fresh.corners and not steps[-1][0].ends


def test_the_robust_candidate_brings_its_corners_only_for_the_patch_they_were_run_on(monkeypatch):
    from patchgen.design.lqg import design_on
    from patchgen.patch.build import build_patch
    from patchgen.studies import recommend

    d = design_on(SPEC.model_copy(update={"actuator": SPEC.actuator.model_copy(update={
        "model": UNCERTAIN.actuator.model, "K_U": UNCERTAIN.actuator.K_U, "tau": UNCERTAIN.actuator.tau,
        "dead_zone_V": UNCERTAIN.actuator.dead_zone_V})}), GP6, UNCERTAIN)
    net = build_patch(d, GP6, 1)
    marker = (bench_corners.BenchStudy("finger-push", {}, "uniform", None, (), ()),)
    other = net.model_copy(update={"notes": [*net.notes, "another patch"]})
    for patch_of_search, brought in ((net, marker), (other, ())):
        choice = robust.RobustChoice(d.spec, {"u": 1.0}, False, 64, 64, {}, 1, "finger-push", patch_of_search, marker)
        monkeypatch.setattr(robust, "search", lambda *a, c=choice, **k: c)
        (cand,) = recommend.extra_candidates(SPEC, GP6, UNCERTAIN, SCENARIOS)
        assert cand.netlist == net and cand.searched == brought
