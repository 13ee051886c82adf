"""`patchgen design`: JSON contract, every shipped design runs, bad specs give one line and exit 2."""

import json
import re
from pathlib import Path

import pytest

from tests.cli_run import run_patchgen
from tests.conftest import DESIGNS

SHIPPED = sorted(p.stem for p in DESIGNS.glob("*.toml"))


run = run_patchgen


def test_case1_json_contract():
    r = run("design", "thesis-case1", "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["states"] == ["s", "theta", "s_dot", "theta_dot", "int_s", "int_theta"]
    assert d["K"][1] == pytest.approx(-249.4119, abs=1e-4)
    assert len(d["closed_loop_poles"]) == 6 and all(len(p) == 2 for p in d["closed_loop_poles"])
    assert d["lqr_margins"]["lower_gm_db"] == pytest.approx(-11.19, abs=5e-3)
    assert d["lqr_margins"]["upper_gm_db"] is None
    assert d["lqr_margins"]["pm_deg"] == pytest.approx(79.12, abs=5e-3)
    est = d["estimator"]
    assert len(est["L"]) == 4 and all(len(r) == 3 for r in est["L"])
    assert len(est["poles"]) == 4
    assert set(d["lqg_margins"]) >= {"lower_gm_db", "upper_gm_db", "pm_deg"}


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_design_runs(name):
    r = run("design", name, "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert all(p[0] < 0 for p in d["closed_loop_poles"])


def test_text_report_has_tables():
    r = run("design", "thesis-case1")
    assert r.returncode == 0
    for s in ("LQR gain", "-249.4119", "Kalman gain", "Loop margins", "-11.19 dB", "79.12"):
        assert s in r.stdout


BASE = (DESIGNS / "thesis-case1.toml").read_text()


@pytest.mark.parametrize("edit,field,words", [
    (lambda t: t.replace("M = 3.552", "M = -3.552"), "plant.M", "at least"),
    (lambda t: t.replace("l = 0.429", "l = 0"), "plant.l", "at least"),
    (lambda t: t.replace("M = 3.552", "M = \"heavy\""), "plant.M", "number"),
    (lambda t: re.sub(r"(?m)^M = .*\n", "", t), "plant.M", "missing"),
    (lambda t: t.replace("[plant]", "[plant]\nmass_of_moon = 7"), "plant.mass_of_moon", "unknown field"),
    (lambda t: t.replace("R = 0.1", "R = 0"), "weights.R", "positive"),
    (lambda t: t.replace("R = 0.1", "R = -1.0"), "weights.R", "positive"),
    (lambda t: t.replace("s = 25.0,", "sx = 25.0,"), "weights.Q.sx", "unknown state name"),
    (lambda t: t.replace("theta = 100.0,", "theta = -100.0,"), "weights.Q.theta", ">= 0"),
    (lambda t: t.replace('kind = "kalman"', 'kind = "magic"'), "estimator.kind", "kalman"),
    (lambda t: t.replace("V = [1.0, 1.0, 1.0]", "V = [1.0, 1.0]"), "estimator.V", "3 values"),
    (lambda t: t.replace("V = [1.0, 1.0, 1.0]", "V = [1.0, -1.0, 1.0]"), "estimator.V", "positive definite"),
    (lambda t: t.replace('machine = "gp6"', 'machine = "eniac"'), "machine", "unknown machine"),
    (lambda t: t.replace("theta = 100.0, s_dot", "theta = 0.0, s_dot").replace("theta_dot = 100.0", "theta_dot = 0.0")
     .replace("s = 25.0, ", "s = 0.0, ").replace("s_dot = 25.0", "s_dot = 0.0").replace("int_s = 25.0", "int_s = 0.0")
     .replace("int_theta = 100.0", "int_theta = 0.0"), "weights.Q", "detectable"),
    (lambda t: t + "\n[broken\n", "", "not valid TOML"),
])
def test_bad_spec_one_line_exit_2(tmp_path: Path, edit, field, words):
    p = tmp_path / "bad.toml"
    p.write_text(edit(BASE))
    r = run("design", str(p))
    assert r.returncode == 2
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert str(p) in lines[0] and field in lines[0] and words in lines[0]
    assert "Traceback" not in r.stderr


def test_matrix_Q_must_be_psd(tmp_path: Path):
    diag = "Q = { s = 25.0, theta = 100.0, s_dot = 25.0, theta_dot = 100.0, int_s = 25.0, int_theta = 100.0 }"
    t = BASE.replace(diag, "Q = [[1,0,0,0,0,0],[0,1,0,0,0,0],[0,0,1,0,0,0],[0,0,0,1,0,0],[0,0,0,0,1,2],[0,0,0,0,2,1]]")
    p = tmp_path / "q.toml"
    p.write_text(t)
    r = run("design", str(p))
    assert r.returncode == 2 and "weights.Q" in r.stderr and "positive semi-definite" in r.stderr


def test_missing_file():
    r = run("design", "designs/nope.toml")
    assert r.returncode == 2 and "no such file" in r.stderr


def test_rho_auto_reports_each_try(tmp_path: Path):
    p = tmp_path / "auto.toml"
    p.write_text(re.sub(r"(?m)^rho = 1e7$", "rho = \"auto\"", BASE))
    r = run("design", str(p), "--json")
    assert r.returncode == 0, r.stderr
    tries = json.loads(r.stdout)["estimator"]["rho_tries"]
    assert [t["rho"] for t in tries] == [10.0**k for k in range(len(tries))]
    assert tries[-1]["accepted"] and not any(t["accepted"] for t in tries[:-1])


def test_zero_at_origin_is_not_stabilisable(tmp_path: Path):
    t = (DESIGNS / "thesis-case3.toml").read_text().replace("state_scale = 10.0", "state_scale = 10.0\nzero = 0.0")
    p = tmp_path / "z.toml"
    p.write_text(t)
    r = run("design", str(p))
    assert r.returncode == 2 and "actuator.zero" in r.stderr and "not stabilisable" in r.stderr


def test_usage_errors_are_one_line():
    for args in (["design"], ["nosuch"], ["simulate", "thesis-ch5", "--scenario", "hold-120s",
                                          "-o", "/tmp/never", "--runs", "0"]):
        r = run(*args)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
