"""A bench profile may name the scenarios it is judged in (``scenarios``): the sheet's prediction
and recommend use them in place of the shipped set; a relative path is read beside the profile;
a scenario that cannot be found or read is one line naming the profile's field or the scenario's."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest
import tomli_w

from patchgen.bench.prediction import STANDARD, predict
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.resources import resolve
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import bench_scenarios, load_bench
from patchgen.profiles.machine import load_machine
from tests.cli_run import run_patchgen

GENTLE = {"name": "gentle-5deg", "description": "5 deg release, held 20 s", "duration_s": 20.0,
          "initial": {"theta_deg": 5.0}}


def _bench(folder: Path, scenarios, own: dict | None = GENTLE) -> Path:
    data = tomllib.loads(resolve("bench", "uw-1991").read_text())
    data["scenarios"] = scenarios
    (folder / "benches").mkdir()
    if own is not None:
        (folder / "benches" / "gentle.toml").write_text(tomli_w.dumps(own))
    path = folder / "benches" / "lab.toml"
    path.write_text(tomli_w.dumps(data))
    return path


def test_a_bench_without_scenarios_is_judged_in_every_shipped_one():
    assert bench_scenarios(load_bench("uw-1991")) == STANDARD == (
        "offset-10deg", "finger-push", "step-cart", "hold-120s")


def test_the_bench_s_own_scenarios_are_read_beside_it_and_predicted(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # not beside the profile: the path is found beside it all the same
    path = _bench(tmp_path, ["gentle.toml", "offset-10deg"])
    bench = load_bench(str(path))
    assert bench_scenarios(bench) == (str(tmp_path / "benches" / "gentle.toml"), "offset-10deg")
    spec = load_spec("bench-recommended")
    machine = load_machine("gp6")
    net = build_patch(design_on(spec, machine, bench), machine)
    preds = predict(net, plant_params(spec), bench, machine)
    assert [p.scenario for p in preds] == ["gentle-5deg", "offset-10deg"]
    assert preds[0].fraction_held == 1.0 and preds[0].max_theta_deg == pytest.approx(5.0, abs=0.5)


def test_the_sheet_predicts_in_the_bench_s_scenarios(tmp_path):
    bench = _bench(tmp_path, ["gentle.toml"])
    spec = tomllib.loads(resolve("design", "bench-recommended").read_text())
    spec["bench"] = str(bench)
    (tmp_path / "spec.toml").write_text(tomli_w.dumps(spec))
    ran = run_patchgen("patch", tmp_path / "spec.toml", "-o", tmp_path / "out", "--json", cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr
    sheet = (tmp_path / "out" / "patch-sheet.md").read_text()
    section = sheet[sheet.index("## Predicted on the bench"):]
    assert "gentle-5deg" in section
    assert not any(name in section for name in STANDARD)


@pytest.mark.parametrize("scenarios, own, field", [
    (["nowhere.toml"], GENTLE, "scenarios[0]"),
    (["offset-10deg", "no-such-scenario"], GENTLE, "scenarios[1]"),
    (["gentle.toml"], {**GENTLE, "duration_s": -1.0}, "duration_s"),
    ([3], GENTLE, "scenarios[0]"),
    ([""], GENTLE, "scenarios[0]"),
])
def test_a_scenario_the_bench_cannot_have_is_one_line(tmp_path, scenarios, own, field):
    path = _bench(tmp_path, scenarios, own)
    with pytest.raises(InputError) as exc:
        load_bench(str(path))
    line = exc.value.line()
    assert "\n" not in line and f": {field}: " in line
    spec = tomllib.loads(resolve("design", "bench-recommended").read_text())
    spec["bench"] = str(path)
    (tmp_path / "spec.toml").write_text(tomli_w.dumps(spec))
    ran = run_patchgen("patch", tmp_path / "spec.toml", "-o", tmp_path / "out", cwd=tmp_path)
    assert ran.returncode == 2 and len(ran.stderr.strip().splitlines()) == 1 and field in ran.stderr
    assert not (tmp_path / "out").exists()


def test_recommend_judges_in_the_bench_s_scenarios(tmp_path):
    bench = _bench(tmp_path, ["gentle.toml"])
    ran = run_patchgen("recommend", "bench-recommended", "--bench", bench, "-o", tmp_path / "out", "--runs", "40",
                       "--json", cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr
    rec = json.loads((tmp_path / "out" / "recommendation.json").read_text())
    assert [s if isinstance(s, str) else s["name"] for s in rec["scenarios"]] == ["gentle-5deg"]


QUIET = {"name": "quiet", "duration_s": 5.0, "noise": "off"}  # upright at rest, nothing pushes it


@pytest.mark.parametrize("scenario, judged", [
    (QUIET, False),
    ({**QUIET, "initial": {"theta_deg": 1.0}}, True),
    ({**QUIET, "initial": {"s_track": 0.1}}, True),
    ({**QUIET, "disturbances": [{"kind": "step", "time_s": 1.0, "size_m": 0.05}]}, True),
    ({**QUIET, "noise": {"mode": "explicit", "tip_force_N": 0.01}}, True),
    ({**QUIET, "noise": "profile"}, True),
    ({**QUIET, "noise": {"mode": "off", "tip_force_N": 0.01}}, False),  # levels count only when explicit
])
def test_only_a_scenario_that_disturbs_the_pendulum_can_judge_a_patch(tmp_path, scenario, judged):
    path = _bench(tmp_path, ["gentle.toml"], scenario)
    if judged:
        assert bench_scenarios(load_bench(str(path))) == (str(tmp_path / "benches" / "gentle.toml"),)
        return
    with pytest.raises(InputError) as exc:
        load_bench(str(path))
    assert exc.value.line().endswith("give it noise") and ": initial: nothing disturbs the pendulum" in exc.value.line()


def test_recommend_refuses_a_scenario_that_never_disturbs_the_pendulum(tmp_path):
    (tmp_path / "quiet.toml").write_text(tomli_w.dumps(QUIET))
    ran = run_patchgen("recommend", "bench-recommended", "--scenario", tmp_path / "quiet.toml", "-o",
                       tmp_path / "out", cwd=tmp_path)
    assert ran.returncode == 2 and "nothing disturbs the pendulum" in ran.stderr
    assert len(ran.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists()
