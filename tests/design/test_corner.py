"""The estimator corner rule on its own: the bench's noise in SI units, the force-error variance
against an integral over frequency, and the grid search against a brute-force one."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from patchgen.design import corner
from patchgen.design.controller import Controller
from patchgen.design.lqg import design, differentiator_controller, loop_with_controller
from patchgen.design.margins import loop_margins
from patchgen.inputs.spec import load_spec
from patchgen.profiles.bench import load_bench

BENCH = load_bench("uw-1991")


def _designed(name: str):
    spec = load_spec(name)
    d = design(spec, BENCH)
    return spec, d, corner.noise_model(spec, BENCH, d.model)


def _frequency_variance(model, K, ctl: Controller, noise: corner.NoiseModel) -> float:
    """Var(u - u_ideal) as (1/2 pi) int |H(jw)|^2 S(w) dw: the loop solved at each frequency, each
    input's first-order spectrum S(w) = 2 sigma^2 wb / (w^2 + wb^2) (variance sigma^2)."""
    keep = [i for i, s in enumerate(model.states) if not s.startswith("int_")]
    Ap, Bp, Cp = model.A[np.ix_(keep, keep)], model.B[keep], model.C[:, keep]
    Ki = np.array([[K[0, model.index(s)] if s.startswith("int_") else 0.0 for s in ctl.states]])
    n, nc = Ap.shape[0], ctl.Ac.shape[0]
    # inputs: the sensor noises, then the force disturbance; unknowns: x (plant), xc (controller)
    M0 = np.block([[Ap + Bp @ ctl.Dc @ Cp, Bp @ ctl.Cc], [ctl.Bc @ Cp, ctl.Ac]])
    Nin = np.block([[Bp @ ctl.Dc, Bp], [ctl.Bc, np.zeros((nc, 1))]])
    e_state = np.hstack([ctl.Dc @ Cp + K[:, keep], ctl.Cc + Ki])  # u + K x, through x and xc
    e_direct = np.hstack([ctl.Dc, np.zeros((1, 1))])
    w = np.logspace(-4, 8, 120001)
    resolvent = np.linalg.solve(1j * w[:, None, None] * np.eye(n + nc) - M0, Nin)
    H = e_state @ resolvent + e_direct  # len(w) x 1 x (ny + 1)
    sigma2 = np.append(noise.sensor_rms, noise.force_rms) ** 2
    wb = noise.bandwidth
    integrand = (np.abs(H[:, 0, :]) ** 2 @ sigma2) * 2 * wb / (w**2 + wb**2)
    # one-sided in w, integrated in log w (dw = w dlog w); the two sides are mirror images
    return float(np.trapezoid(integrand * w, np.log(w)) / math.pi)


def test_noise_model_is_the_bench_in_si_units():
    spec, d, noise = _designed("bench-recommended")
    assert d.model.measured == ("s", "theta", "s_dot")
    # uw-1991: 2 mV, 2 mV, 5 mV rms through table A.2's 5.000 V/m, 4.190 V/rad, 0.5941 V/(m/s)
    np.testing.assert_allclose(noise.sensor_rms, [0.002 / 5.0, 0.002 / 4.19, 0.005 / 0.5941], rtol=1e-12)
    assert noise.bandwidth == pytest.approx(2 * math.pi * 200.0, rel=1e-12)
    # a dead zone of +/-0.2 V at 14.01 N/V, uniform: 2.802 N / sqrt(3)
    assert noise.force_rms == pytest.approx(1.6177, abs=1e-4)


@pytest.mark.parametrize("name", ["bench-recommended", "thesis-ch5"])
def test_force_error_matches_an_integral_over_frequency(name):
    _, d, noise = _designed(name)
    want = _frequency_variance(d.model, d.K, d.controller, noise)
    got = corner.force_error_rms(d.model, d.K, d.controller, noise)
    assert got == pytest.approx(math.sqrt(want), rel=1e-4)  # the trapezoid on a 1e-4 step in log w agrees to ~5e-6
    assert got > 0.1  # newtons: the dead zone alone pushes the loop by more than that


def test_force_error_is_linear_in_the_noise_and_adds_in_variance():
    _, d, noise = _designed("bench-recommended")
    err = lambda nm: corner.force_error_rms(d.model, d.K, d.controller, nm)
    both = err(noise)
    sensors_only = err(replace(noise, force_rms=0.0))
    force_only = err(replace(noise, sensor_rms=np.zeros(3)))
    # independent inputs: their variances add
    assert both**2 == pytest.approx(sensors_only**2 + force_only**2, rel=1e-9)
    assert min(sensors_only, force_only) > 0
    scaled = replace(noise, sensor_rms=3 * noise.sensor_rms, force_rms=3 * noise.force_rms)
    assert err(scaled) == pytest.approx(3 * both, rel=1e-9)
    assert err(replace(noise, sensor_rms=np.zeros(3), force_rms=0.0)) == 0.0


def test_an_unstable_loop_has_no_force_error_figure():
    _, d, noise = _designed("bench-recommended")
    # no feedback at all: the upright pendulum falls, the variance does not exist
    idle = Controller(states=("z",), Ac=np.array([[-1.0]]), Bc=np.zeros((1, 3)), Cc=np.zeros((1, 1)),
                      Dc=np.zeros((1, 3)))
    assert corner.force_error_rms(d.model, d.K, idle, noise) == math.inf


def _grid_case():
    _, d, noise = _designed("bench-recommended")
    grid = np.logspace(-3, -1, 9)
    build = lambda r: differentiator_controller(d.model, d.K, r)
    scores = [corner.force_error_rms(d.model, d.K, build(float(v)), noise) for v in grid]
    return d, noise, grid, build, scores


def test_choose_is_the_grid_minimum():
    d, noise, grid, build, scores = _grid_case()
    got = corner.choose(d.model, d.K, build, noise, grid)
    best = int(np.argmin(scores))
    assert got.value == float(f"{grid[best]:.3g}")
    assert got.force_error_rms_N == pytest.approx(scores[best], rel=1e-12)
    assert got.tried == len(grid)


def test_choose_takes_the_next_best_the_margin_allows():
    d, noise, grid, build, scores = _grid_case()
    order = np.argsort(scores)
    refused = grid[order[0]]
    margin = lambda c: 10.0 if np.isclose(c.Ac[0, 0], -1.0 / refused, rtol=1e-12) else 45.0
    got = corner.choose(d.model, d.K, build, noise, grid, margin)
    assert got.value == float(f"{grid[order[1]]:.3g}")
    assert got.force_error_rms_N == pytest.approx(scores[order[1]], rel=1e-12)


def test_choose_skips_values_the_builder_refuses_and_says_when_none_pass():
    d, noise, grid, build, scores = _grid_case()
    best = int(np.argmin(scores))

    def picky(r):
        if r == grid[best]:
            raise ValueError("no such part")
        return build(r)

    got = corner.choose(d.model, d.K, picky, noise, grid)
    assert got.force_error_rms_N == pytest.approx(sorted(scores)[1], rel=1e-12)
    with pytest.raises(ValueError, match="30 deg of phase margin") as refused:
        corner.choose(d.model, d.K, build, noise, grid, lambda c: None)  # no loop stable
    assert refused.value.scored and all(s.pm_deg is None for s in refused.value.scored)
    assert refused.value.fallbacks() == [] and "the most is" not in str(refused.value)


def test_the_shipped_roll_off_is_the_least_error_among_robust_loops():
    _, d, noise = _designed("bench-recommended")
    chosen = d.estimator.rolloff_s
    ranked = []
    for r in corner.ROLLOFF_GRID_S:
        ctl = differentiator_controller(d.model, d.K, float(r))
        e = corner.force_error_rms(d.model, d.K, ctl, noise)
        if math.isfinite(e):
            m = loop_margins(*loop_with_controller(d.model, ctl), gain_limits=False)
            ranked.append((e, float(r), m.stable and m.pm_deg is not None and m.pm_deg >= corner.MIN_PM_DEG))
    ranked.sort()
    first_robust = next(r for e, r, ok in ranked if ok)
    assert chosen == float(f"{first_robust:.3g}")
    assert ranked[0][1] != first_robust  # the rule did skip a faster-error, thinner-margin roll-off
    assert d.estimator.force_error_rms_N == pytest.approx(
        corner.force_error_rms(d.model, d.K, differentiator_controller(d.model, d.K, chosen), noise), rel=1e-12)
