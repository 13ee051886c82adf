"""Scaling on its own: the u_c block's coefficients are conventions.md's wired gains, signs included."""

from __future__ import annotations

import pytest

from patchgen.design.lqg import design_on
from patchgen.inputs.errors import InputError
from patchgen.inputs.spec import load_spec
from patchgen.patch.realization import realize
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine

GP6 = load_machine("gp6")


def _realized(name):
    spec = load_spec(name)
    d = design_on(spec, GP6, load_bench(spec.bench))
    return spec, d, realize(d, GP6)


def test_ch5_coefficients_are_the_wired_gains():
    # conventions.md: the coefficient wired for state i is K_i / (K_sensor_i K_U) in size; with
    # u = -K x and u_c = F / K_U, its sign is that of -K_i
    spec, d, real = _realized("thesis-ch5")
    KU = spec.actuator.K_U
    k = {"s": spec.sensors.s, "theta": spec.sensors.theta, "s_dot": spec.sensors.s_dot}
    terms = {t.signal: t.wanted for t in real.block("u_c").terms}
    for i, s in enumerate(d.states):
        if s in k:
            assert terms[s] == pytest.approx(-d.K[0, i] / (k[s] * KU), rel=1e-12), s
    # section 5.3's wired theta gain needs the x10 input: between 1 and 10 V/V
    assert 1 < abs(terms["theta"]) < 10
    assert real.K_U == KU and real.sensors == k


def test_theta_dot_comes_from_a_differentiator_of_theta():
    spec, d, real = _realized("thesis-ch5")
    b = real.block("theta_dot")
    assert b.kind == "differentiate" and [t.signal for t in b.terms] == ["theta"]
    # its output carries theta_dot at the spec's scale: T_d = scale / K_theta seconds
    assert b.volts_per_unit == pytest.approx(spec.theta_dot_scale())
    assert b.T_d_s == pytest.approx(spec.theta_dot_scale() / spec.sensors.theta, rel=1e-12)
    assert b.rolloff_s == pytest.approx(d.estimator.rolloff_s)
    i = d.states.index("theta_dot")
    theta_dot = next(t for t in real.block("u_c").terms if t.signal == "theta_dot")
    assert theta_dot.wanted == pytest.approx(-d.K[0, i] / (b.volts_per_unit * spec.actuator.K_U), rel=1e-12)


def test_a_state_the_bench_cannot_measure_needs_an_estimator():
    spec = load_spec("thesis-ch5")
    bare = spec.model_copy(update={"estimator": spec.estimator.model_copy(update={"kind": "none"})})
    d = design_on(bare, GP6, load_bench(spec.bench))
    assert "theta_dot" in d.states
    with pytest.raises(InputError) as exc:
        realize(d, GP6)
    assert exc.value.field == "estimator.kind" and "theta_dot is not measured" in exc.value.message
