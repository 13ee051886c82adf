"""record, identify, design, patch, predict: `patchgen bench-test` then `patchgen identify` from the
command line, and the fitted profile as a drop-in bench for the other commands."""

from __future__ import annotations

import json
import tomllib

import pytest

from patchgen.profiles.bench import load_bench
from tests.cli_run import run_patchgen
from tests.identify.benches import TRUE_BENCH, TRUE_PLANT, bench_toml, spec_toml

run = run_patchgen


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """bench-test on the test bench and plant, then identify the folder whole."""
    tmp = tmp_path_factory.mktemp("e2e")
    spec = spec_toml(tmp / "true.toml", str(bench_toml(tmp / "true-bench.toml")))
    r = run("bench-test", str(spec), "--seed", "5", "-o", str(tmp / "rec"))
    assert r.returncode == 0, r.stderr
    r = run("identify", str(tmp / "rec"), "-o", str(tmp / "fit"), "--json")
    assert r.returncode == 0, r.stderr
    return tmp, json.loads(r.stdout)


def test_bench_test_writes_every_standard_test_and_is_deterministic(fitted, tmp_path):
    tmp, _ = fitted
    names = sorted(p.name for p in (tmp / "rec").iterdir())
    assert names == sorted(["masses.toml", "calibration.csv", "actuator-step.csv", "actuator-ramp.csv",
                            "coast-down-1.csv", "coast-down-2.csv", "incline.toml", "free-swing.csv", "quiet.csv",
                            "integrator-drift.csv"])
    r = run("bench-test", str(tmp / "true.toml"), "--seed", "5", "-o", str(tmp_path / "again"))
    assert r.returncode == 0, r.stderr
    for n in names:  # same spec and seed, same bytes
        assert (tmp_path / "again" / n).read_bytes() == (tmp / "rec" / n).read_bytes(), n
    r = run("bench-test", str(tmp / "true.toml"), "--seed", "6", "-o", str(tmp_path / "other"))
    assert (tmp_path / "other" / "quiet.csv").read_bytes() != (tmp / "rec" / "quiet.csv").read_bytes()


def test_identify_writes_a_profile_and_a_plant_table_that_read_back(fitted):
    tmp, report = fitted
    fit = tmp / "fit"
    for f in ("bench.toml", "plant.toml", "report.md", "report.json"):
        assert (fit / f).is_file(), f
    assert {p.name for p in fit.glob("fit-*.png")} >= {"fit-actuator-step.png", "fit-free-swing.png"}
    bench = load_bench(str(fit / "bench.toml"))
    K_U, tau = TRUE_BENCH["actuator.K_U"], TRUE_BENCH["actuator.tau"]  # the bench the recordings were made on
    assert bench.actuator.K_U == pytest.approx(K_U, rel=0.02) and bench.actuator.tau == pytest.approx(tau, rel=0.05)
    assert len(bench.recordings) == 10 and all(r.startswith(str(tmp / "rec")) for r in bench.recordings)
    # the intervals as the bench's ranges, for simulate --bench-spread and recommend
    ranges = bench.uncertainty.ranges
    assert bench.uncertainty.distribution == "normal"
    assert set(ranges) == {"K_U", "tau", "dead_zone_V", "sensors.s", "sensors.theta", "sensors.s_dot",
                           "noise_V_rms.s", "noise_V_rms.theta", "noise_V_rms.s_dot"}
    e = report["bench"]["actuator.tau"]["interval_95"]
    assert ranges["tau"] == pytest.approx(tuple(e), rel=1e-5)
    plant = tomllib.loads((fit / "plant.toml").read_text())["plant"]
    assert plant["l"] == pytest.approx(TRUE_PLANT.l, rel=0.01)
    assert plant["b_VF"] == pytest.approx(TRUE_PLANT.b_VF, rel=0.1)
    low, high = report["bench"]["actuator.K_U"]["interval_95"]
    assert low <= K_U <= high


def test_the_fitted_bench_predicts_what_the_true_bench_does(fitted):
    """The fitted profile and plant as a drop-in: simulate on them and on the truth, same seeds."""
    tmp, _ = fitted
    plant = (tmp / "fit" / "plant.toml").read_text()
    spec = spec_toml(tmp / "fitted.toml", str(tmp / "fit" / "bench.toml"), plant=plant[plant.index("\n[plant]") + 1:])
    out = {}
    for name in ("true", "fitted"):
        r = run("simulate", str(tmp / f"{name}.toml"), "--scenario", "finger-push", "--runs", "8",
                "-o", str(tmp / f"sim-{name}"), "--json")
        assert r.returncode == 0, r.stderr
        out[name] = json.loads(r.stdout)["distribution"]
    assert out["fitted"]["fraction_held"] == out["true"]["fraction_held"]
    assert out["fitted"]["fraction_tripped"] == out["true"]["fraction_tripped"]
    for q in ("max_abs_theta_deg", "rms_theta_deg"):
        assert out["fitted"]["percentiles"][q]["p50"] == pytest.approx(out["true"]["percentiles"][q]["p50"], rel=0.25)
    r = run("patch", str(spec), "-o", str(tmp / "patch"), "--runs", "4")
    assert r.returncode == 0, r.stderr
    sheet = (tmp / "patch" / "patch-sheet.md").read_text()
    assert "identified bench (identified from 10 recordings in " in sheet and "free-swing.csv" in sheet


def test_identify_never_overwrites(fitted):
    tmp, _ = fitted
    before = (tmp / "fit" / "bench.toml").read_bytes()
    r = run("identify", str(tmp / "rec"), "-o", str(tmp / "fit"))
    assert r.returncode == 2 and "--force" in r.stderr and len(r.stderr.splitlines()) == 1
    assert (tmp / "fit" / "bench.toml").read_bytes() == before


def test_a_spec_names_the_fitted_bench_relative_to_its_own_folder(fitted, tmp_path):
    tmp, _ = fitted
    spec = spec_toml(tmp / "beside.toml", "fit/bench.toml")  # tmp/fit/bench.toml, from tmp_path's cwd
    r = run("simulate", str(spec), "--scenario", "finger-push", "-o", str(tmp_path / "o"), "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["bench"] == "identified"
