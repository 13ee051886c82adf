"""The linear verdict of the wired loop on the bench: stable, marginal or unstable."""

from __future__ import annotations

import numpy as np
import pytest

from patchgen.bench.diagnosis import MARGINAL_TOL, LoopPoles, diagnose
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine


def _patch(name):
    spec = load_spec(name)
    machine, bench = load_machine(spec.machine), load_bench(spec.bench)
    d = design_on(spec, machine, bench)
    return build_patch(d, machine), plant_params(d.spec), bench


def test_the_recommended_bench_patch_is_stable_with_either_actuator():
    net, plant, bench = _patch("bench-recommended")
    assert [lp.verdict for lp in diagnose(net, plant, bench)] == ["stable", "stable"]


@pytest.mark.parametrize("real, verdict", [(-1e-3, "stable"), (-MARGINAL_TOL / 2, "marginal"), (0.0, "marginal"),
                                           (MARGINAL_TOL / 2, "marginal"), (1e-3, "unstable")])
def test_the_verdict_has_three_values(real, verdict):
    assert LoopPoles("x", np.array([-2.0, real + 1j, real - 1j])).verdict == verdict


def test_the_verdict_reads_the_bench_sensors_not_the_netlists():
    net, plant, bench = _patch("thesis-ch5")
    data = net.model_dump(by_alias=True)
    for s in data["sensors"]:
        s["volts_per_unit"] *= 2.0
    rescaled = type(net).model_validate(data)
    a = [np.sort_complex(lp.poles) for lp in diagnose(net, plant, bench)]
    b = [np.sort_complex(lp.poles) for lp in diagnose(rescaled, plant, bench)]
    for x, y in zip(a, b):
        np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-12)


def test_the_hold_scenario_fails_a_patch_that_cannot_balance_and_passes_one_that_can():
    """hold-120s starts off upright and pushes twice: 'held' means the patch balanced the pendulum."""
    from patchgen.bench.simulate import simulate
    from patchgen.inputs.scenario import load_scenario

    sc = load_scenario("hold-120s")
    assert sc.initial.vector()[1] != 0.0 and len(sc.disturbances) >= 2
    machine = load_machine("gp6")
    for name, held in (("thesis-ch5", 0.0), ("bench-recommended", 1.0)):
        net, plant, bench = _patch(name)
        r = simulate(net, plant, bench, machine, sc, runs=8, keep_history=False)
        assert r.distribution.fraction_held == held, name
