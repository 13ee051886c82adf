"""`patchgen sweep`: thesis-style tables of gains against 10% parameter changes."""

import json

import numpy as np
import pytest
import scipy.linalg as sla

from patchgen.cli.options import parse_by, parse_vary
from patchgen.design.model import build_model
from patchgen.design.weights import q_matrix, r_matrix
from patchgen.inputs.spec import load_spec
from patchgen.plant.equations import PlantParams
from patchgen.profiles.machine import load_machine
from patchgen.studies.sweep import cases, sweep
from tests.cli_run import run_patchgen
from tests.conftest import design_path


def test_cases_layout():
    c = cases(["M", "l"], 0.1)
    assert [label for label, _ in c] == ["nominal", "M +10%", "M -10%", "l +10%", "l -10%", "all +10%"]
    assert c[-1][1] == {"M": 1.1, "l": 1.1}


def test_rows_are_true_designs_of_the_perturbed_plant():
    spec = load_spec(design_path("thesis-case1-noint"))
    rows = sweep(spec, load_machine("gp6"), ["M", "l"], 0.1, workers=1)
    assert rows[0].K == pytest.approx([-15.8114, -209.0301, -31.0045, -52.9470], abs=1e-4)
    p = spec.plant
    plant = PlantParams(M=p.M * 1.1, m=p.m, l=p.l, g=p.g, b_VF=p.b_VF, c=p.c, d=p.d)
    # rows[1] is the LQR of the heavier cart, checked by its fixed point (Kleinman): the cost of
    # u = -K x solves a Lyapunov equation, and the optimal K is the one that cost reproduces
    m = build_model(spec, plant)
    K = np.atleast_2d(rows[1].K)
    Q, R = q_matrix(spec), r_matrix(spec)
    Acl = m.A - m.B @ K
    assert np.max(np.linalg.eigvals(Acl).real) < 0
    P = sla.solve_continuous_lyapunov(Acl.T, -(Q + K.T @ R @ K))
    np.testing.assert_allclose(np.linalg.solve(R, m.B.T @ P), K, rtol=1e-6)
    # and it is not the nominal plant's gain
    assert np.abs(K - np.atleast_2d(rows[0].K)).max() > 1e-3
    # a heavier cart needs more gain on theta (thesis 4.6: the gains change little)
    assert abs(rows[1].K[1]) > abs(rows[0].K[1])
    assert all(abs(r.K[1] / rows[0].K[1] - 1) < 0.1 for r in rows)


def test_ch5_sweep_reports_pot_changes():
    spec = load_spec(design_path("thesis-ch5"))
    rows = sweep(spec, load_machine("gp6"), ["M", "m", "l", "b_VF", "c"], 0.1, workers=1)
    by = {r.label: r for r in rows}
    assert by["nominal"].pot_changes == {}
    assert "P2" in by["all +10%"].pot_changes  # the theta pot moves with all parameters up
    assert by["all +10%"].patch_error is None


def test_bad_options():
    from patchgen.inputs.errors import InputError

    with pytest.raises(InputError):
        parse_vary("M,mass")
    with pytest.raises(InputError):
        parse_by("ten")
    assert parse_by("10%") == pytest.approx(0.1)


def test_cli_json_and_bad_vary():
    r = run_patchgen("sweep", "thesis-case1", "--vary", "M,m,l,b_VF,c", "--by", "10%", "--json")
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout)
    assert len(rows) == 12 and rows[0]["case"] == "nominal"
    r = run_patchgen("sweep", "thesis-case1", "--vary", "Mx")
    assert r.returncode == 2 and "Mx" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_sweep_gives_the_wired_loops_bench_verdict():
    """Section 5.3's patch stays unstable on the bench with the cart 10 % heavier or lighter."""
    from patchgen.inputs.scenario import load_scenario
    from patchgen.profiles.bench import load_bench

    spec = load_spec(design_path("thesis-ch5"))
    rows = sweep(spec, load_machine("gp6"), ["M"], 0.1, workers=1, scenario=load_scenario("offset-10deg"), runs=1,
                 bench=load_bench("uw-1991"))
    assert [r.outcome["bench_loop"] for r in rows] == ["unstable"] * 4


def test_a_sweep_on_every_core_is_the_sweep_on_one():
    """The rows spread over two processes are the rows computed one after another, outcome and all."""
    from patchgen.inputs.scenario import load_scenario
    from patchgen.profiles.bench import load_bench

    spec = load_spec(design_path("bench-recommended"))
    args = (spec, load_machine("gp6"), ["M", "l"], 0.1)
    kw = {"scenario": load_scenario("step-cart"), "runs": 3, "bench": load_bench("uw-1991")}
    one, two = sweep(*args, workers=1, **kw), sweep(*args, workers=2, **kw)
    assert len(two) >= 4 and [r.as_dict() for r in two] == [r.as_dict() for r in one]
    assert all(r.outcome is not None and r.outcome["runs"] == 3 for r in one)
