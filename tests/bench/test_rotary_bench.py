"""The rotary pendulum on its bench: the compiled kernel's runs of the QUBE-Servo 2's patch against
scipy's solve_ivp of the numpy equations closed by the design's own controller (an independent
integrator and an independent form of the equations), with a push at the pendulum's tip, a push
on the arm and a step of the arm's command; the cable's wind-up ending a run; and the QUBE's own
scenarios held over a Monte Carlo of its bench."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.inputs.scenario import Scenario, load_scenario
from patchgen.patch.build import build_patch
from patchgen.pipeline.inputs import load_inputs
from patchgen.plant.plant_model import PLANT_MODELS
from patchgen.plant.rotary_equations import nonlinear_rhs
from patchgen.profiles.bench import bench_scenarios
from patchgen.profiles.measured_plant import as_on_bench
from tests.conftest import ROOT, run_patchgen

QUBE = "qube-servo-2"


@pytest.fixture(scope="module")
def qube():
    """The QUBE's design and its patch at the sensor constants (the patch command's scaling for
    signal-to-noise runs on this bench too; here the law's own scale is the point)."""
    inputs = load_inputs(QUBE, plants=tuple(PLANT_MODELS))
    spec = inputs.spec.changed("patch.scaling", "sensors")
    d = design_on(spec, inputs.machine, inputs.bench)
    return d, build_patch(d, inputs.machine), inputs


def _reference(d, scenario: Scenario, t_eval: np.ndarray, bench) -> np.ndarray:
    """The nonlinear plant as the bench has it (rotary_equations.nonlinear_rhs, a torque and a tip
    force added as their generalised forces) closed by the design's controller, its filters settled
    on the start."""
    p, c = as_on_bench(d.plant, bench), d.controller
    meas = [d.model.states.index(m) for m in d.model.measured]
    x0 = np.array(scenario.initial.vector(d.spec.plant_model))
    pushes = [(x.time_s, x.time_s + x.duration_s, x.at, x.force_N, x.arm_m or p.L_p) for x in scenario.disturbances
              if x.kind == "force_impulse"]
    steps = [(x.time_s, x.step_size()) for x in scenario.disturbances if x.kind == "step"]

    def y_of(t, x):
        y = x[meas].copy()
        y[0] -= sum(size for t0, size in steps if t >= t0)  # the arm's command: an offset on its sensor
        return y

    def rhs(t, z):
        x, xc = z[:4], z[4:]
        y = y_of(t, x)
        u = (c.Cc @ xc + c.Dc @ y).item()
        f = nonlinear_rhs(x, u, p)
        on = [(at, F, r) for t0, t1, at, F, r in pushes if t0 <= t < t1]
        if on:  # generalised forces M q'' = Q: a push r along the pendulum (L_r, r cos theta), on the arm (L_r, 0)
            s, co = math.sin(x[1]), math.cos(x[1])
            J_2 = p.pendulum_inertia() + p.m_p * p.pendulum_com() ** 2
            J_0 = p.arm_inertia() + p.m_r * p.arm_com() ** 2 + p.m_p * p.L_r ** 2
            K = p.m_p * p.L_r * p.pendulum_com()
            M = np.array([[J_0 + J_2 * s * s, K * co], [K * co, J_2]])
            Q = sum(np.array([F * p.L_r, F * r * co if at == "pendulum_tip" else 0.0]) for at, F, r in on)
            f[2:] += np.linalg.solve(M, Q)
        return np.concatenate([f, c.Ac @ xc + c.Bc @ y])

    xc0 = -np.linalg.solve(c.Ac, c.Bc @ y_of(0.0, x0))
    breaks = sorted({0.0, scenario.duration_s} | {t for p_ in pushes for t in p_[:2]} | {t for t, _ in steps})
    ys = []
    z = np.concatenate([x0, xc0])
    for a, b in zip(breaks, breaks[1:]):  # integrate piecewise: a push's edges are not smoothed over
        inside = t_eval[(t_eval >= a) & (t_eval < b)] if b < breaks[-1] else t_eval[t_eval >= a]
        sol = solve_ivp(rhs, (a, b), z, t_eval=inside, rtol=1e-9, atol=1e-11, method="LSODA")
        ys.append(sol.y)
        z = solve_ivp(rhs, (a, b), z, rtol=1e-9, atol=1e-11, method="LSODA").y[:, -1]
    return np.hstack(ys)


def _scenario(text: str) -> Scenario:
    import tomllib

    from patchgen.inputs.validation import validate

    return validate(Scenario, tomllib.loads(text), "test")


RELEASE = 'duration_s = 6.0\nnoise = "off"\ndrift = "off"\n[initial]\ntheta_deg = 5.0\n'
PUSHES = ('duration_s = 6.0\nnoise = "off"\ndrift = "off"\n'
          '[[disturbances]]\nkind = "force_impulse"\nat = "pendulum_tip"\ntime_s = 0.5\nduration_s = 0.1\n'
          'force_N = 0.02\n'
          '[[disturbances]]\nkind = "force_impulse"\nat = "arm"\ntime_s = 3.0\nduration_s = 0.1\nforce_N = 0.1\n')
MIDWAY = ('duration_s = 6.0\nnoise = "off"\ndrift = "off"\n'
          '[[disturbances]]\nkind = "force_impulse"\nat = "pendulum_tip"\ntime_s = 0.5\nduration_s = 0.1\n'
          'force_N = 0.03\narm_m = 0.05\n')
STEP = ('duration_s = 8.0\nnoise = "off"\ndrift = "off"\n'
        '[[disturbances]]\nkind = "step"\ntime_s = 0.5\nsize_deg = 10.0\n')


@pytest.mark.parametrize("text", [RELEASE, PUSHES, MIDWAY, STEP], ids=["release", "pushes", "midway", "arm-step"])
def test_the_kernel_is_the_equations_closed_by_the_design_s_law(qube, text):
    """Ideal bench (no noise, lag, limit or count): the patch's run equals the reference to 0.5 % of
    each signal's peak (the pots' 0.001 steps move the law by about 0.05 %)."""
    d, net, inputs = qube
    sc = _scenario(text)
    res = simulate(net, d.plant, inputs.bench, inputs.machine, sc, seed=1, runs=1, ideal=True)
    h = res.history
    assert set(h) >= {"alpha", "theta", "alpha_dot", "theta_dot", "alpha_ref", "u_c", "V_m"}
    ref = _reference(d, sc, h["t"], inputs.bench)
    for i, name in enumerate(("alpha", "theta", "alpha_dot", "theta_dot")):
        peak = np.abs(ref[i]).max()
        assert peak > 1e-3, name  # each signal moves: the comparison is not of zeros
        assert np.abs(h[name] - ref[i]).max() <= 5e-3 * peak, name
    assert res.runs[0].held


def test_the_arm_goes_where_its_command_steps(qube):
    d, net, inputs = qube
    res = simulate(net, d.plant, inputs.bench, inputs.machine, _scenario(STEP), seed=1, runs=1, ideal=True)
    h = res.history
    assert h["alpha_ref"][-1] == pytest.approx(math.radians(10.0))
    assert h["alpha"][-1] == pytest.approx(math.radians(10.0), abs=math.radians(0.5))


def test_the_cable_s_wind_up_ends_the_run(qube):
    """With the cable at 0.1 rad, a 5 deg release swings the arm past it (0.2 rad otherwise): the
    run ends there, as a trip, at the first step past it."""
    d, net, inputs = qube
    short = d.plant.__class__(**{**d.plant.__dict__, "alpha_limit": 0.1})
    res = simulate(net, short, inputs.bench, inputs.machine, _scenario(RELEASE), seed=1, runs=1, ideal=True)
    run, h = res.runs[0], res.history
    assert run.limit_switch_tripped and not run.held
    k = int(np.argmax(np.abs(h["alpha"]) >= 0.1))
    assert abs(h["alpha"][k]) >= 0.1 > np.abs(h["alpha"][:k]).max()
    assert run.trip_time_s == pytest.approx(h["t"][k], abs=0.02)
    free = simulate(net, d.plant, inputs.bench, inputs.machine, _scenario(RELEASE), seed=1, runs=1, ideal=True)
    assert free.runs[0].held and free.runs[0].max_abs_s_m > 0.15


def test_the_qube_s_patch_holds_in_its_own_scenarios_on_its_bench(qube):
    """The QUBE's scenarios with the bench's noise, counts, random forces and 10 V limit, 40 runs
    each: every one held; with its pendulum encoder reversed, none."""
    d, net, inputs = qube
    names = bench_scenarios(inputs.bench)
    assert names == ("qube-release-5deg", "qube-tap", "qube-arm-step", "qube-hold-60s")
    for name in names:
        res = simulate(net, d.plant, inputs.bench, inputs.machine, load_scenario(name), seed=7, runs=40)
        assert all(r.held for r in res.runs), name
        assert res.settings.sensor_noise_V_rms == {"alpha": 0.001, "theta": 0.001}
    # the pendulum's encoder wired the other way round: the law pushes the pendulum further over
    reversed_encoder = inputs.bench.model_copy(update={"sensors": inputs.bench.sensors.model_copy(
        update={"theta": -inputs.bench.sensors.theta})})
    res = simulate(net, d.plant, reversed_encoder, inputs.machine, load_scenario("qube-release-5deg"), seed=7,
                   runs=10)
    assert not any(r.held for r in res.runs)


@pytest.mark.parametrize("spec, scenario, field", [
    ("qube-servo-2", "step-cart", "disturbances[0].size_m"),
    ("qube-servo-2", "ip02-hold-60s", "disturbances[1].at"),
    ("bench-recommended", "qube-arm-step", "disturbances[0].size_rad"),
    ("bench-recommended", "qube-hold-60s", "disturbances[1].at"),
])
def test_another_plant_s_scenario_is_named_not_run(spec, scenario, field, tmp_path):
    from tests.conftest import run_patchgen

    r = run_patchgen("simulate", spec, "--scenario", scenario, "-o", str(tmp_path / "out"))
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert f"{scenario}: {field}:" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "out").exists()


def test_an_arm_without_a_cable_limit_simulates_and_says_so(tmp_path):
    """A slip ring (no alpha_limit): the run never ends at the arm, and summary.json says so with
    null, not an infinity JSON cannot carry."""
    spec = (ROOT / "designs" / "qube-servo-2.toml").read_text()
    assert "alpha_limit = 3.141592653589793" in spec
    path = tmp_path / "slip-ring.toml"
    path.write_text(spec.replace("alpha_limit = 3.141592653589793", ""))
    r = run_patchgen("simulate", str(path), "--scenario", "qube-release-5deg", "--runs", "3", "-o", str(tmp_path / "o"))
    assert r.returncode == 0, r.stderr
    got = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert got["settings"]["half_track_m"] is None and got["distribution"]["fraction_held"] == 1.0
    # the arm's largest excursion is named as the arm's, in rad (a cart's is max_abs_s_m)
    assert 0.0 < got["first_run"]["max_abs_alpha_rad"] < 1.0 and "max_abs_s_m" not in got["first_run"]
    assert set(got["distribution"]["percentiles"]["max_abs_alpha_rad"]) >= {"p50", "p95"}
