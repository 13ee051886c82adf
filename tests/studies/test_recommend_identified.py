"""recommend on a bench identify fitted: nine ranges (the 95 % intervals of its fits), the worst
corner searched for rather than 512 enumerated; progress on stderr when piped, from the start; a
choice whose verdict line says what its table row says, and that holds over the fitted ranges."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from patchgen.cli import cli
from patchgen.profiles.bench import bench_scenarios, load_bench
from patchgen.studies import worst_case

pytestmark = pytest.mark.heavy(40)  # seconds, roughly: see tests/conftest.py

MC_RUNS = 200  # the Monte Carlo over the fitted ranges the choice must hold in


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    root = tmp_path_factory.mktemp("identified")
    runner = CliRunner()
    for argv in (["bench-test", "bench-recommended", "-o", str(root / "rec")],
                 ["identify", str(root / "rec"), "-o", str(root / "fitted")]):
        r = runner.invoke(cli, argv)
        assert r.exit_code == 0, r.output
    bench = root / "fitted" / "bench.toml"
    r = runner.invoke(cli, ["recommend", "bench-recommended", "--bench", str(bench), "-o", str(root / "out")])
    assert r.exit_code == 0, r.output
    return root, load_bench(str(bench)), r


def test_nine_ranges_are_searched_not_enumerated(fitted):
    root, bench, _ = fitted
    assert len(bench.uncertainty.ranges) == 9
    rec = json.loads((root / "out" / "recommendation.json").read_text())
    chosen = next(c for c in rec["candidates"] if c["realisation"] == rec["chosen"])
    corner = chosen["worst_corner"]
    assert corner["fraction_held"] >= 0.95 and corner["runs"] == 64
    assert set(corner["values"]) == set(bench.uncertainty.ranges)  # every range at one of its ends
    assert all(v in bench.uncertainty.ranges[k] for k, v in corner["values"].items())
    # no corner-robust search: the spec's own realisations hold at their worst corner
    assert not any(c["robust"] for c in rec["candidates"])


def test_progress_is_on_stderr_from_the_start_when_piped(fitted):
    _, _, result = fitted
    lines = result.stderr.splitlines()
    assert lines[0].startswith("recommend [0:0") and "designing" in lines[0]
    assert any("worst corner of the bench's ranges" in line for line in lines)
    assert result.stdout.count("recommend [") == 0  # progress never mixes into the report


def test_the_verdict_line_says_what_the_table_says(fitted):
    root, _, result = fitted
    rec = json.loads((root / "out" / "recommendation.json").read_text())
    chosen = next(c for c in rec["candidates"] if c["realisation"] == rec["chosen"])
    assert chosen["rank"] == 1 and chosen["decision"] == "holds"
    assert rec["verdict"].startswith(f"Chosen: {rec['chosen']}: wired loop stable on the bench; holds in every")
    assert "at the worst corner of the bench's ranges it held 64/64" in rec["verdict"]


def test_the_choice_holds_over_the_fitted_ranges(fitted):
    """A Monte Carlo of MC_RUNS runs per scenario, each run's bench drawn from the fitted ranges."""
    root, bench, _ = fitted
    for scenario in bench_scenarios(bench):
        r = CliRunner().invoke(cli, ["simulate", str(root / "out" / "recommended.toml"), "--scenario", scenario,
                                     "--bench", str(root / "fitted" / "bench.toml"), "--bench-spread", "--runs",
                                     str(MC_RUNS), "--corner-runs", str(worst_case.SCREEN_RUNS), "--json",
                                     "-o", str(root / f"mc-{scenario}")])
        assert r.exit_code == 0, r.output
        drawn = json.loads(r.stdout)["bench_spread"]["drawn"]
        assert drawn["runs"] == MC_RUNS and drawn["fraction_held"] >= 0.95, (scenario, drawn)
