"""python-control as an independent oracle for every shipped design, and the API's systems
(patchgen.design.lti) checked to be what they say they are.

Tolerances: gains and frequencies relative 1e-6, phase margins 1e-5 deg, poles 1e-6 relative to
max(1, |pole|) (repeated poles near -1e-5 allow the usual square-root sensitivity). Thesis
figures are compared to half a unit of the last digit printed.
"""

from __future__ import annotations

import math
import subprocess
import sys
from functools import cache

import control as ct
import numpy as np
import pytest

import patchgen
from patchgen.inputs.resources import shipped

SHIPPED = shipped("design")
KALMAN = [n for n in SHIPPED if patchgen.load_spec(n).estimator.kind == "kalman"]
RTOL = 1e-6
PM_ATOL_DEG = 1e-5  # the frd route interpolates between grid points
# crossovers are sought in this band (every shipped loop crosses between 0.1 and 300 rad/s);
# outside it python-control's polynomial method reports roundoff (a "gain margin" of 1e15 at 1e10 rad/s)
W_BAND = (1e-3, 1e4)
W_FRD = np.logspace(-3, 4, 1000)


@cache
def _design(name: str, rho: float | None = None):
    return patchgen.load_design(name, rho=rho)


def _match(got, want, rtol=RTOL) -> float:
    """Assert two pole sets are equal as multisets; return the worst deviation relative to max(1, |p|)."""
    got, want = list(np.asarray(got, complex)), np.asarray(want, complex)
    assert len(got) == len(want)
    worst = 0.0
    for w in want:
        j = int(np.argmin([abs(g - w) for g in got]))
        dev = abs(got.pop(j) - w) / max(1.0, abs(w))
        assert dev <= rtol, f"pole {w} matched by one {dev:.2e} away"
        worst = max(worst, dev)
    return worst


def _control_margins(L, method: str) -> dict:
    """Every margin python-control finds for L in the band, reduced to patchgen's report."""
    if method == "frd":
        # stability_margins(L, method="frd") on a continuous-time LTI system raises in 0.10.2
        # (its FRD is built without interpolation); an interpolating FRD works
        gm, pm, _, wpc, wgc, _ = ct.stability_margins(ct.frd(L, W_FRD, smooth=True), returnall=True)
    else:
        gm, pm, _, wpc, wgc, _ = ct.stability_margins(L, returnall=True, method="poly")
    gm, pm, wpc, wgc = map(np.atleast_1d, (gm, pm, wpc, wgc))
    inband = lambda w: (w >= W_BAND[0]) & (w <= W_BAND[1])
    gm, wpc = gm[inband(wpc)], wpc[inband(wpc)]
    pm, wgc = pm[inband(wgc)], wgc[inband(wgc)]
    i = int(np.argmin(np.abs(pm)))
    return {
        "lower_gm": max((g for g in gm if g < 1), default=None),
        "upper_gm": min((g for g in gm if g > 1), default=None),
        "pm_deg": abs(pm[i]),
        "pm_freq": wgc[i],
        "delay_margin_s": min(math.radians(p % 360.0) / w for p, w in zip(pm, wgc)),
        "phase_crossovers": np.sort(wpc),
        "gain_crossovers": np.sort(wgc),
    }


def _loops():
    """(name, law, rho): every shipped design's LQR loop and implemented loop, and case 1's LQG
    loop before loop transfer recovery (the thesis's rho = 1 figures)."""
    out = []
    for n in SHIPPED:
        out.append((n, "lqr", None))
        if patchgen.load_spec(n).estimator.kind != "none":
            out.append((n, "compensator", None))
    return out + [("thesis-case1", "compensator", 1.0)]


def _reported(d, law):
    return d.lqr_margins if law == "lqr" else d.lqg_margins


def _fresp(sys, w):
    """outputs x inputs x frequencies (FrequencyResponseData.complex is new in 0.10.2)."""
    return sys(1j * w, squeeze=False)


def _stable(sys) -> bool:
    return bool(np.max(sys.poles().real) < 0)


@pytest.mark.parametrize("name", SHIPPED)
def test_lqr_gain_and_poles_equal_control_lqr(name):
    d = _design(name)
    K, S, E = ct.lqr(d.model.A, d.model.B, d.Q, d.R)
    np.testing.assert_allclose(d.K, K, rtol=RTOL, atol=RTOL * np.abs(K).max())
    np.testing.assert_allclose(d.S, S, rtol=RTOL, atol=RTOL * np.abs(S).max())
    _match(d.closed_loop_poles, E)


@pytest.mark.parametrize("name", SHIPPED)
def test_lqr_gain_from_the_hamiltonian(name):
    """Without slycot, control.lqr calls the same scipy Riccati solver as patchgen; the stable
    invariant subspace of the Hamiltonian [[A, -B R^-1 B^T], [-Q, -A^T]] is a second route."""
    d = _design(name)
    A, B, Q, R = d.model.A, d.model.B, d.Q, d.R
    lam, V = np.linalg.eig(np.block([[A, -B @ np.linalg.solve(R, B.T)], [-Q, -A.T]]))
    Vs, n = V[:, lam.real < 0], len(A)
    assert Vs.shape[1] == n
    S = np.real(Vs[n:] @ np.linalg.inv(Vs[:n]))
    K = np.linalg.solve(R, B.T @ S)
    np.testing.assert_allclose(d.K, K, rtol=RTOL, atol=RTOL * np.abs(K).max())


@pytest.mark.parametrize("name", KALMAN)
def test_kalman_gain_equals_control_lqe(name):
    d = _design(name)
    e, sp = d.estimator, d.spec.estimator
    Ae, Be, Ce = d.model.submodel(d.model.estimated)
    G = Be if sp.Gamma == "B" else np.array(sp.Gamma, float).reshape(len(Ae), -1)
    # lqe(A, G, C, QN, RN) forms G QN G^T and rejects it as unsymmetric by roundoff at rho = 1e7
    # (conventions.md): pass G = I and the symmetrised rho Gamma W Gamma^T
    QN = e.rho * G @ np.atleast_2d(sp.W) @ G.T
    V = np.array(sp.V, float)
    L, _, poles = ct.lqe(Ae, np.eye(len(Ae)), Ce, (QN + QN.T) / 2, np.diag(V) if V.ndim == 1 else V)
    np.testing.assert_allclose(e.L, L, rtol=RTOL, atol=RTOL * np.abs(L).max())
    _match(e.poles, poles)


@pytest.mark.parametrize("name", SHIPPED)
def test_closed_loops_of_the_api_agree_with_patchgen_poles(name):
    d = _design(name)
    _match(ct.feedback(patchgen.loop_ss(d, "lqr"), 1).poles(), d.closed_loop_poles)
    # the implemented loop: broken at the plant input, or plant and compensator interconnected
    broken = ct.feedback(patchgen.loop_ss(d), 1)
    joined = ct.feedback(patchgen.plant_ss(d), patchgen.compensator_ss(d), sign=1)
    _match(joined.poles(), broken.poles())
    if d.estimator is not None and d.estimator.kind == "kalman":  # separation principle
        _match(broken.poles(), np.concatenate([d.closed_loop_poles, d.estimator.poles]))
    assert _stable(broken) == d.lqg_margins.stable
    # the named closed loop equals python-control's interconnection, and its u is C(s) y
    closed = patchgen.closed_loop_ss(d)
    _match(closed.poles(), joined.poles())
    w = np.logspace(-2, 3, 25)
    rows = [closed.output_labels.index(y) for y in patchgen.plant_ss(d).output_labels]  # feedback renames
    cl = _fresp(closed, w)[:, 0]
    np.testing.assert_allclose(cl[rows], _fresp(joined, w)[:, 0], rtol=1e-8, atol=1e-12)
    u = np.einsum("iw,iw->w", _fresp(patchgen.compensator_ss(d), w)[0], cl[rows])
    np.testing.assert_allclose(cl[closed.output_labels.index("u")], u, rtol=1e-8, atol=1e-12)


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")  # poly method, 12 states
@pytest.mark.parametrize("method", ["poly", "frd"])
@pytest.mark.parametrize(("name", "law", "rho"), _loops())
def test_margins_agree_with_control_stability_margins(name, law, rho, method):
    d = _design(name, rho)
    L = patchgen.loop_ss(d, law)
    got = _control_margins(L, method)
    want = _reported(d, law)
    assert want.stable and _stable(ct.feedback(L, 1))
    for key in ("lower_gm", "upper_gm", "pm_freq", "delay_margin_s"):
        w, g = getattr(want, key), got[key]
        assert (w is None) == (g is None), key
        if w is not None:
            assert g == pytest.approx(w, rel=RTOL), key
    assert got["pm_deg"] == pytest.approx(want.pm_deg, abs=PM_ATOL_DEG)
    for key in ("phase_crossovers", "gain_crossovers"):
        np.testing.assert_allclose(got[key], np.sort(getattr(want, key)), rtol=RTOL, err_msg=key)


@pytest.mark.parametrize(("name", "law", "rho"), _loops())
def test_gain_margins_are_stability_limits(name, law, rho):
    """Just inside each reported limit the loop closed by python-control is stable, just outside
    unstable; with no limit it stays stable at 1e-3 and 1e3 times the gain."""
    d = _design(name, rho)
    L, m = patchgen.loop_ss(d, law), _reported(d, law)
    for limit, far in ((m.lower_gm, 1e-3), (m.upper_gm, 1e3)):
        if limit is None:
            assert _stable(ct.feedback(far * L, 1))
            continue
        inside, outside = (1.001, 0.999) if limit < 1 else (0.999, 1.001)
        assert _stable(ct.feedback(limit * inside * L, 1))
        assert not _stable(ct.feedback(limit * outside * L, 1))


@pytest.mark.parametrize("name", SHIPPED)
def test_loops_are_what_they_say(name):
    """The LQR loop is K (sI - A)^-1 B; the implemented loop is -C(s) P(s) of the API's own
    compensator and plant; both at 40 frequencies, relative 1e-9."""
    d = _design(name)
    w = np.logspace(-2, 3, 40)
    A, B, K = d.model.A, d.model.B, d.K
    direct = np.array([(K @ np.linalg.solve(1j * x * np.eye(len(A)) - A, B))[0, 0] for x in w])
    lqr = _fresp(patchgen.loop_ss(d, "lqr"), w).ravel()
    np.testing.assert_allclose(lqr, direct, rtol=1e-9)
    P = _fresp(patchgen.plant_ss(d), w)  # outputs x 1 x w
    C = _fresp(patchgen.compensator_ss(d), w)  # 1 x inputs x w
    product = -np.einsum("iw,iw->w", C[0], P[:, 0])
    loop = _fresp(patchgen.loop_ss(d), w).ravel()
    np.testing.assert_allclose(loop, product, rtol=1e-9)


@pytest.mark.parametrize("name", KALMAN)
def test_kalman_compensator_is_the_estimator_law(name):
    """U = -K_e Xhat - K_i Xi with Xi = (sI - A_i)^-1 E Y (integrators of s and theta) and
    Xhat = (sI - A_e + B_e K_e + L C_e)^-1 (L Y - B_e K_i Xi), written out with numpy."""
    d = _design(name)
    m = d.model
    Ae, Be, Ce = m.submodel(m.estimated)
    ie = [m.index(s) for s in m.estimated]
    ii = [i for i, s in enumerate(m.states) if s.startswith("int_")]
    Ai = m.A[np.ix_(ii, ii)]
    E = m.A[np.ix_(ii, [m.index(s) for s in m.measured])]
    Ke, Ki, L = d.K[:, ie], d.K[:, ii], d.estimator.L
    comp = patchgen.compensator_ss(d)
    assert comp.input_labels == list(m.measured) and comp.output_labels == ["u"]
    for x in (0.1, 1.0, 10.0, 100.0):
        s = 1j * x
        Xi = np.linalg.solve(s * np.eye(len(ii)) - Ai, E) if ii else np.zeros((0, 3))
        Xhat = np.linalg.solve(s * np.eye(len(ie)) - Ae + Be @ Ke + L @ Ce, L - Be @ Ki @ Xi)
        want = -Ke @ Xhat - Ki @ Xi
        np.testing.assert_allclose(comp(s), want, rtol=1e-9)


def test_thesis_case1_figures_with_control():
    """conventions.md, 'Case 1 checks' (thesis section 4.5.1), reproduced on the API's systems."""
    d = _design("thesis-case1")
    # printed K (read as u = -K x; conventions.md), 4 decimals
    np.testing.assert_allclose(d.K[0], [-39.8530, -249.4119, -44.8988, -60.0125, -15.8106, 0.0], atol=5e-5)
    lqr = patchgen.loop_ss(d, "lqr")
    _match(ct.feedback(lqr, 1).poles(),
           [-22.2917, -1.7309 + 1.2205j, -1.7309 - 1.2205j, -0.8667 + 0.5163j, -0.8667 - 0.5163j, -0.00001],
           rtol=5e-5)
    np.testing.assert_allclose(np.sort(ct.zeros(patchgen.plant_ss(d, "s")).real), [-4.7896, 4.7729], atol=5e-5)
    gm, pm, *_ = ct.stability_margins(lqr)
    assert gm == pytest.approx(0.2757, abs=5e-5)
    assert 20 * math.log10(gm) == pytest.approx(-11.19, abs=5e-3)
    assert pm == pytest.approx(79.12, abs=5e-3)
    gm, pm, *_ = ct.stability_margins(patchgen.loop_ss(_design("thesis-case1-noint"), "lqr"))
    assert 20 * math.log10(gm) == pytest.approx(-11.47, abs=5e-3)
    assert pm == pytest.approx(80.14, abs=5e-3)
    # LQG with W = 1, V = I, Gamma = B before recovery: its upper gain margin and phase margin
    rho1 = _control_margins(patchgen.loop_ss(_design("thesis-case1", 1.0)), "poly")
    assert 20 * math.log10(rho1["upper_gm"]) == pytest.approx(1.03, abs=5e-3)
    assert rho1["pm_deg"] == pytest.approx(5.7, abs=0.05)


def test_rho_override_is_the_reported_lqg_before_recovery():
    """load_design(rho=1) gives the loop whose margins the rho = 10^k design reports as margins_rho1."""
    before, after = _design("thesis-case1", 1.0).lqg_margins, _design("thesis-case1").estimator.margins_rho1
    for key in ("lower_gm", "upper_gm", "pm_deg", "pm_freq"):
        assert getattr(before, key) == pytest.approx(getattr(after, key), rel=1e-12), key


def _variant(base: str, **estimator):
    spec = patchgen.load_spec(base)
    return spec.model_copy(update={"estimator": spec.estimator.model_copy(update=estimator)})


@pytest.mark.parametrize("estimator", [{"kind": "none"}, {"kind": "reduced_observer", "observer_pole": 20.0}])
def test_other_estimators(estimator):
    """Plain state feedback (the compensator reads every plant state) and the reduced observer,
    which no shipped design uses; their closed loops as python-control interconnects them."""
    d = patchgen.load_design(_variant("bench-recommended", **estimator))
    plant, comp = patchgen.plant_ss(d), patchgen.compensator_ss(d)
    assert plant.output_labels == comp.input_labels
    poles = ct.feedback(plant, comp, sign=1).poles()
    want = d.closed_loop_poles if d.estimator is None else np.concatenate([d.closed_loop_poles, d.estimator.poles])
    _match(poles, want)
    _match(ct.feedback(patchgen.loop_ss(d), 1).poles(), poles)
    _match(patchgen.closed_loop_ss(d).poles(), poles)


def test_api_rejects_what_it_cannot_do():
    d = _design("thesis-ch5")
    with pytest.raises(ValueError, match="not plant states"):
        patchgen.plant_ss(d, ("int_theta",))
    with pytest.raises(ValueError, match="law"):
        patchgen.loop_ss(d, "lqg")
    with pytest.raises(ValueError, match="Kalman"):
        patchgen.load_design("thesis-ch5", rho=10.0)


def test_patchgen_and_its_cli_do_not_import_control():
    code = (
        "import sys, contextlib, io\n"
        "import patchgen\n"
        "from patchgen.cli import main\n"
        "for args in (['--help'], ['design', 'thesis-case1', '--json']):\n"
        "    sys.argv = ['patchgen', *args]\n"
        "    with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
        "        main()\n"
        "assert 'control' not in sys.modules, 'imported control'\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
