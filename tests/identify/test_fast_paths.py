"""The compiled paths of writing, reading and fitting against the plain code they stand for: tables
formatted against Python's %-format, the recording's automaton against the regular expression of
a plain number, the likelihood at many points against one point at a time, the batched curvature
against its central differences one by one, the actuator's start grid against its search cell by
cell."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy.optimize import minimize
from scipy.signal import lfilter

from patchgen.identify import actuator, filters, kalman, lag_grid
from patchgen.identify.cells import PLAIN, read_plain

ALPHABET = list("0123456789") * 3 + list(".+-eE ,\t\n") + ["x", "_", "#"]


def _regex_lines(text: str, ncols: int) -> bool:
    cell = rf"[ \t]*{PLAIN.pattern}[ \t]*"
    line = cell + ("," + cell) * (ncols - 1)
    return re.fullmatch(rf"(?:{line}\n)*{line}", text) is not None


def _reads(text: str, ncols: int) -> bool:
    """Whether read_plain takes the text as lines of ncols plain numbers."""
    return read_plain(np.frombuffer(text.encode("ascii"), np.uint8), ncols, np.empty(0)) != 0


@pytest.mark.parametrize("text, ncols, expected", [
    ("0.5, -1e-3,+2.", 3, True), (".5,1.e5\n 3 ,\t4E+07", 2, True), ("1,2\n", 2, False), ("1,2\n\n3,4", 2, False),
    ("1 2", 1, False), (".", 1, False), ("1e", 1, False), ("-.e1", 1, False), ("1,2,3", 2, False), ("1", 2, False),
    ("nan", 1, False), ("1_000", 1, False), ("", 1, False)])
def test_read_plain_takes_what_the_regular_expression_matches(text, ncols, expected):
    assert _regex_lines(text, ncols) is expected
    assert _reads(text, ncols) is expected


def test_read_plain_agrees_with_the_regular_expression_on_random_text():
    rng = np.random.default_rng(5)
    agree = matched = 0
    for _ in range(20000):
        ncols = int(rng.integers(1, 4))
        text = "".join(rng.choice(ALPHABET, size=int(rng.integers(0, 14))))
        want = _regex_lines(text, ncols)
        matched += want
        agree += want == _reads(text, ncols)
    assert agree == 20000 and matched > 500


def _swing_case():
    rng = np.random.default_rng(2)
    t = np.arange(1500) * 0.02
    y = 0.5 * np.exp(-0.03 * t) * np.cos(5.0 * t) + 0.01 + 1e-3 * rng.standard_normal(t.size)
    P = np.array([[0.06, 25.0, 0.01, 0.5 / 2.3, 0.0, math.log(1e-3), math.log(1e-6)],
                  [0.05, 25.1, 0.012, 0.48 / 2.3, 0.01, math.log(3e-3), math.log(2e-6)]])
    return y, P


def test_swing_nll_many_is_swing_nll_row_by_row():
    y, P = _swing_case()
    pred, terms, out = np.empty(y.size), np.empty(y.size), np.empty(len(P))
    filters.swing_nll_many(y, 0.02, 40.0, 2.3, P, pred, terms, out)
    for row, value in zip(P, out):
        beta, w2, off, phi0, om0, lq, lr = row
        assert value == filters.swing_nll(y, 0.02, beta, w2, 0.0, 40.0, math.exp(lq), math.exp(lr), 2.3, off, phi0,
                                          om0, pred, terms)
    with_gam = np.column_stack([P, [0.0, 0.02]])
    filters.swing_nll_many(y, 0.02, 40.0, 2.3, with_gam, pred, terms, out)
    assert out[1] == filters.swing_nll(y, 0.02, *with_gam[1, :2], 0.02, 40.0, math.exp(with_gam[1, 5]),
                                       math.exp(with_gam[1, 6]), 2.3, *with_gam[1, 2:5], pred, terms)


def test_coast_nll_many_is_coast_nll_row_by_row():
    rng = np.random.default_rng(4)
    t = np.arange(400) * 0.02
    w = 2.0 * np.exp(-0.8 * t) + 0.01 * rng.standard_normal(t.size)
    z = 0.3 + 1.5 * (1 - np.exp(-0.8 * t)) + 0.002 * rng.standard_normal(t.size)
    P = np.array([[0.8, 0.6, 0.3, 2.0, 0.0, math.log(0.1), math.log(4e-6), math.log(1e-4), 0.05]])
    pred, terms, out = np.empty(t.size), np.empty(t.size), np.empty(1)
    filters.coast_nll_many(z, w, 0.02, 40.0, -1.0, 3, P, pred, terms, out)
    a, rho, z0, w0, off, lq, lr1, lr2, f = P[0]
    assert out[0] == filters.coast_nll(z, w, 0.02, a, -f, rho, math.exp(lq), 40.0, math.exp(lr1), math.exp(lr2), off,
                                       z0, w0, -1.0, 3, pred, terms)


def test_batched_hessian_is_the_central_differences():
    A = np.array([[2.0, 0.3, -0.1], [0.3, 1.0, 0.2], [-0.1, 0.2, 3.0]])
    f = lambda p: 0.5 * p @ A @ p + math.sin(p[0])
    p, h = np.array([0.1, -0.2, 0.3]), np.array([1e-3, 2e-3, 1e-3])
    H = kalman.hessian(lambda P: np.array([f(q) for q in P]), p, h)
    exact = A.copy()
    exact[0, 0] -= math.sin(p[0])
    assert np.allclose(H, exact, atol=1e-5)
    e = np.eye(3) * h
    by_one = (f(p + e[2] + e[1]) - f(p + e[2] - e[1]) - f(p - e[2] + e[1]) + f(p - e[2] - e[1])) / (4 * h[2] * h[1])
    assert H[1, 2] == by_one


@pytest.mark.parametrize("with_zero", [True, False])
def test_grid_start_is_the_cell_by_cell_search(with_zero):
    rng = np.random.default_rng(8)
    dt = 0.005
    u = np.repeat([0.0, 1.2, 0.0, -1.2, 0.0, 0.6, 0.0, -0.6], 300)
    v = lag_grid.dead_zone(u, 0.3)
    f = 9.0 * lag_grid.lag_state(v, dt, 0.25) + 0.1 + 0.02 * rng.standard_normal(u.size)
    taus = np.geomspace(2 * lag_grid.MIN_TAU_S, 5.0, lag_grid.GRID_TAUS)
    dzs = np.linspace(0, 0.9 * 1.2, lag_grid.GRID_DEAD_ZONES)
    best = (np.inf, None)
    for tau in taus:
        V = np.array([lag_grid.dead_zone(u, dz) for dz in dzs])
        approx, bound = lag_grid.approximate_rss(V, f, dt, tau, with_zero)
        for dz, a, e in zip(dzs, approx, bound):
            rss, c = lag_grid.cell(lag_grid.dead_zone(u, dz), f, dt, tau, with_zero)
            assert a == pytest.approx(rss, rel=1e-9) and abs(a - rss) <= e + 1e-12 * rss
            if rss < best[0]:
                best = (rss, [c[0], c[1] if with_zero else 0.0, tau, dz, c[-1]])
    assert np.array_equal(lag_grid.grid_start(u, f, dt, with_zero), np.array(best[1]))


def test_ml_fit_minimises_as_l_bfgs_b_with_its_own_differences():
    f = lambda p: (p[0] - 1.0) ** 4 + 3 * (p[1] + 0.5) ** 2 + p[0] * p[1] + math.exp(0.3 * p[2]) - p[2]
    f_many_calls = []

    def f_many(P):
        f_many_calls.append(len(P))
        return np.array([f(p) for p in P])

    p0, scale, lower = np.array([0.2, 0.1, 2.0]), np.array([0.5, 0.2, 1.0]), np.array([-np.inf, -0.3, 1.5])
    fit = kalman.ml_fit(f, p0, scale, lower, covariance=False, nll_many=f_many)
    z_lo = (lower - p0) / scale
    ref = minimize(lambda z: f(p0 + scale * z), np.zeros(3), method="L-BFGS-B",
                   bounds=[(None if not math.isfinite(b) else b, None) for b in z_lo],
                   options={"maxiter": 500, "ftol": 1e-10, "gtol": 1e-3, "maxcor": 20})
    assert np.array_equal(fit.p, p0 + scale * ref.x) and fit.nll == ref.fun
    assert max(f_many_calls) == 3  # each gradient's points in one call


def test_read_plain_gives_what_float_gives():
    rng = np.random.default_rng(12)
    cells = [f"{v:.7g}" for v in rng.standard_normal(5000) * 10.0 ** rng.uniform(-12, 12, 5000)]
    cells += [f"{v:.10g}" for v in np.arange(5000) * 0.005]
    cells += ["0", "-0", "+0.0e3", ".5", "5.", "-.25E-2", " 7 ", "\t1e22", "1e23", "9007199254740993",
              "123456789012345678901", "1e-400"]
    want = [float(c) for c in cells]
    values = np.empty(len(cells))
    assert read_plain(np.frombuffer("\n".join(cells).encode(), np.uint8), 1, values) == 2  # some left to float
    for cell, expected in zip(cells, want):
        one = np.empty(1)
        status = read_plain(np.frombuffer(cell.encode(), np.uint8), 1, one)
        assert status in (1, 2)
        if status == 1:
            assert one[0] == expected and np.signbit(one[0]) == np.signbit(expected), cell
    table = np.empty(4)
    assert read_plain(np.frombuffer(b"1.5, -2\n3e-3,4", np.uint8), 2, table) == 1
    assert list(table) == [1.5, -2.0, 3e-3, 4.0]


def test_actuator_models_are_their_numpy_form_to_the_bit():
    rng = np.random.default_rng(13)
    dt, u = 0.005, np.repeat(rng.uniform(-2, 2, 30), 100) + 0.01 * rng.standard_normal(3000)
    direction = np.sign(rng.standard_normal(u.size))
    for K, KZ, tau, dz, F0, h in [(9.0, 0.3, 0.2, 0.3, 0.05, 0.04), (-3.0, 0.0, 2e-4, 0.0, 0.0, 0.0),
                                  (11.0, -1.0, 4.0, 1.5, -0.2, -0.1)]:
        a = np.exp(-dt / tau)
        v = np.where(u > dz, u - dz, np.where(u < -dz, u + dz, 0.0))
        y = lfilter([0.0, 1.0 - a], [1.0, -a], v, zi=[v[0]])[0]
        assert np.array_equal(lag_grid.lag_state(v, dt, tau), y)
        expected = K * y + KZ / tau * (np.concatenate([v[:1], v[:-1]]) - y) + F0
        assert np.array_equal(actuator.force_model(np.array([K, KZ, tau, dz, F0]), u, dt), expected)
        w = u - 0.5 * h * direction
        v = np.where(w > dz, w - dz, np.where(w < -dz, w + dz, 0.0))
        expected = K * lfilter([0.0, 1.0 - a], [1.0, -a], v, zi=[v[0]])[0] + F0
        assert np.array_equal(actuator.ramp_model(np.array([K, tau, dz, F0, h]), u, direction, dt), expected)
