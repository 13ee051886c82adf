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


def test_a_patch_judged_on_the_bench_is_python_controls_loop_with_the_bench_actuator():
    """thesis-case2 on four units, on the uw-1991 bench: the read-back law in volts, the bench's
    sensor constants, its K_U and 0.2 s lag (the design assumed 0.1 s), the plant of eq. 2.28."""
    import control

    from patchgen.bench.circuit import sensor_constants
    from patchgen.bench.diagnosis import as_patched_on_bench
    from patchgen.patch.readback import wired_law
    from patchgen.plant.equations import linear_matrices
    from tests.patch.test_as_patched import control_margins

    spec = load_spec("thesis-case2")
    machine, bench = load_machine(spec.machine), load_bench(spec.bench)
    d = design_on(spec, machine, bench)
    net = build_patch(d, machine)
    j = as_patched_on_bench(d, net, machine, bench)
    law = wired_law(net)
    Ap, Bp = linear_matrices(plant_params(d.spec))
    y = np.zeros((3, 4))
    for r, (s, k) in enumerate(zip(net.sensors, sensor_constants(net, bench))):
        y[r, ["s", "theta", "s_dot", "theta_dot"].index(s.quantity)] = k
    act = bench.actuator
    plant = control.series(control.tf([act.K_U], [act.tau, 1.0]), control.ss(Ap, Bp, y, 0))  # u_c -> volts
    L = -control.series(plant, control.ss(law.Ac, law.Bc, law.Cc, law.Dc))
    lower, upper, pm = control_margins(L)
    m = j.bench.margins
    assert (m.lower_gm_db, m.upper_gm_db, m.pm_deg) == (pytest.approx(lower, abs=1e-6), pytest.approx(upper, abs=1e-6),
                                                      pytest.approx(pm, abs=1e-6))
    assert (lower, upper, pm) == (pytest.approx(-7.40, abs=0.01), pytest.approx(23.69, abs=0.01),
                                  pytest.approx(29.12, abs=0.01))
    np.testing.assert_allclose(np.sort_complex(j.bench.poles), np.sort_complex(control.feedback(L, 1).poles()),
                               rtol=1e-7, atol=1e-9)
    assert j.bench.loop == "uw-1991 bench, linearised (actuator lag 0.2 s)"
    # the same poles as the simulator's linear verdict
    np.testing.assert_allclose(np.sort_complex(j.bench.poles), np.sort_complex(diagnose(net, plant_params(d.spec),
                                                                                        bench)[-1].poles), rtol=1e-9)
