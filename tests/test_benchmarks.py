"""The benchmarks measure what they say, checked without timing anything: the latency rows are
the speed issue's table (every shipped design patched), each row's command line is one the CLI
accepts with its names resolving to shipped inputs, a failed or empty run is refused rather than
timed, the design benchmark gives no result when it had nothing to time, the --json result has
its stated shape, and every patchgen name a benchmark imports exists."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import json
import shutil
import sys
import textwrap

import click
import pytest

from patchgen.cli import cli
from patchgen.inputs.resources import shipped
from tests.conftest import DESIGNS, ROOT

BENCHMARKS = ROOT / "benchmarks"


def _benchmark(name: str):
    """A script of benchmarks/ as a module (the scripts import one another by name, as run)."""
    if str(BENCHMARKS) not in sys.path:
        sys.path.insert(0, str(BENCHMARKS))
    return importlib.import_module(name)


latency = _benchmark("bench_latency")
design_bench = _benchmark("bench_design")
ROWS = latency.rows()
SHIPPED = latency.shipped_designs()  # the designs patchgen patches

# the speed issue's table: command line -> (median wall target s, peak memory target MiB); "seconds"
# and "under 200 MiB" for spice read as 10 s and 200 MiB
ISSUE_TABLE = {
    "patchgen design bench-recommended": (0.5, None),
    **{f"patchgen patch {name} -o DIR": (1.5, None) for name in SHIPPED},
    "patchgen simulate bench-recommended --scenario hold-120s --runs 1 -o DIR": (1.5, None),
    "patchgen simulate bench-recommended --scenario hold-120s --runs 1000 -o DIR": (5.0, None),
    "patchgen recommend bench-recommended --bench uw-1991-uncertain -o DIR": (15.0, None),
    "patchgen spice bench-recommended --scenario hold-120s -o DIR": (10.0, 200.0),
}


def test_every_shipped_design_is_patched_in_a_row():
    assert SHIPPED, "no design in designs/"
    assert set(SHIPPED) <= set(shipped("design"))  # the folder is what the CLI ships
    assert "qube-servo-2" in SHIPPED and "bench-recommended" in SHIPPED  # both plants are patched
    patched = sorted(r.args[1] for r in ROWS if r.args[0] == "patch" and r.table)
    assert patched == SHIPPED


def test_table_rows_are_the_issue_table():
    table = {r.command_line(): (r.target_s, r.target_mib) for r in ROWS if r.table}
    assert table == ISSUE_TABLE
    assert "--ideal" not in next(r for r in ROWS if r.name == "spice").args
    assert len({r.name for r in ROWS}) == len(ROWS)


def test_rows_selected_by_name_or_command():
    table = [r for r in ROWS if r.table]
    assert latency.select(ROWS, []) == table
    assert latency.select(ROWS, [], everything=True) == ROWS
    assert [r.args[1] for r in latency.select(ROWS, ["patch"])] == SHIPPED
    assert [r.name for r in latency.select(ROWS, ["spice", "design"])] == ["design", "spice"]  # table order
    assert [r.name for r in latency.select(ROWS, ["identify"])] == ["identify", "identify-qube"]  # a command: its rows
    assert [r.name for r in latency.select(ROWS, ["identify-qube"])] == ["identify-qube"]  # an extra row, named
    with pytest.raises(ValueError, match="unknown row 'nonesuch'"):
        latency.select(ROWS, ["nonesuch"])


def _parse(args: list[str]) -> click.Context:
    """The subcommand's context for a patchgen command line, parsed as click would, not run."""
    name, rest = args[0], args[1:]
    command = cli.get_command(click.Context(cli), name)
    assert command is not None, f"patchgen has no command {name!r}"
    return command.make_context(name, rest)


@pytest.mark.parametrize("row", ROWS, ids=lambda r: r.name)
def test_row_is_a_command_line_patchgen_accepts(row, tmp_path, capsys):
    """Each row's arguments parse as its command's, the output directory lands in -o, and the spec,
    bench and scenario it names load."""
    from patchgen.pipeline.inputs import load_inputs, scenario_for

    out, rec = tmp_path / "out", tmp_path / "rec"
    args = [{"OUT": str(out), "REC": str(rec), "REC_QUBE": str(rec)}.get(a, a) for a in row.args]
    if args == ["--help"]:
        with pytest.raises(click.exceptions.Exit) as exit_:
            cli.make_context("patchgen", args)
        assert exit_.value.exit_code == 0 and "Usage" in capsys.readouterr().out
        return
    ctx = _parse(args)
    if row.writes:
        assert ctx.params["out_dir"] == str(out)
    if "spec" in ctx.params:
        inputs = load_inputs(ctx.params["spec"], bench=ctx.params.get("bench_name"), command=args[0])
        if ctx.params.get("scenario_path"):
            scenario_for(ctx.params["scenario_path"], inputs.spec, runs=ctx.params.get("runs", 1))
    for key, made_by in (("REC", latency.RECORDINGS), ("REC_QUBE", latency.ROTARY_RECORDINGS)):
        if key in row.args:
            assert ctx.params["recordings"] == (str(rec),)
            _parse(list(made_by) + [str(rec)])  # the command that makes the recordings


def _python(code: str) -> list[str]:
    """A stand-in for patchgen: python running ``code``, the row's arguments in sys.argv."""
    return [sys.executable, "-c", textwrap.dedent(code)]


def test_a_failed_run_is_not_timed():
    row = latency.Row("x", ("design", "bench-recommended"), 1.0, stdout="text")
    with pytest.raises(latency.RunFailed, match=r"failed \(3\):\nbroken"):
        latency.run_once(row, command=_python("import sys; sys.stderr.write('broken'); sys.exit(3)"))


def test_a_run_that_leaves_out_its_output_is_not_timed():
    writes = latency.Row("x", ("simulate", "-o", "OUT"), 1.0, writes=("summary.json",))
    with pytest.raises(latency.RunFailed, match="without writing summary.json"):
        latency.run_once(writes, command=_python("pass"))
    prints = latency.Row("x", ("design",), 1.0, stdout="text")
    with pytest.raises(latency.RunFailed, match="printed nothing"):
        latency.run_once(prints, command=_python("pass"))
    as_json = latency.Row("x", ("design", "--json"), 1.0, stdout="json")
    with pytest.raises(latency.RunFailed, match="no JSON object"):
        latency.run_once(as_json, command=_python("print('[1, 2]')"))


def test_an_allowed_status_counts_and_children_are_measured():
    """Exit status 1 where the row allows it (spice's disagreement) is a completed run; the peak
    resident set covers a child's memory (wait4's rusage of the whole tree)."""
    row = latency.Row("x", ("spice", "-o", "OUT"), 1.0, writes=("comparison.json",), statuses=(0, 1))
    code = """
        import pathlib, subprocess, sys
        out = pathlib.Path(sys.argv[-1]); out.mkdir()
        (out / "comparison.json").write_text("{}")
        subprocess.run([sys.executable, "-c", "b = bytearray(96 * 2**20)\\nfor i in range(0, len(b), 4096): b[i] = 1"],
                       check=True)
        sys.exit(1)
    """
    sample = latency.run_once(row, command=_python(code))
    assert sample.peak_mib >= 96
    assert sample.cpu_s > 0 and sample.wall_s > 0


def test_design_benchmark_refuses_to_report_nothing(tmp_path):
    with pytest.raises(design_bench.NothingTimed, match="no design specs"):
        design_bench.time_designs(tmp_path, repeats=1)
    shutil.copy(DESIGNS / "bench-recommended.toml", tmp_path)
    with pytest.raises(design_bench.NothingTimed, match="no timed runs"):
        design_bench.time_designs(tmp_path, repeats=0)
    with pytest.raises(design_bench.NothingTimed, match="failed"):
        design_bench.time_designs(tmp_path, repeats=1, command=_python("import sys; sys.exit(2)"))
    with pytest.raises(design_bench.NothingTimed, match="printed nothing"):
        design_bench.time_designs(tmp_path, repeats=1, command=_python("pass"))
    assert design_bench.main(["-n", "0"]) == 2
    assert design_bench.TARGET_S == ISSUE_TABLE["patchgen design bench-recommended"][0]


def test_design_benchmark_times_each_spec(tmp_path):
    shutil.copy(DESIGNS / "bench-recommended.toml", tmp_path)
    shutil.copy(DESIGNS / "thesis-ch5.toml", tmp_path)
    times = design_bench.time_designs(tmp_path, repeats=2, command=_python("print('{\"K\": [1]}')"))
    assert list(times) == ["bench-recommended", "thesis-ch5"] and all(len(v) == 2 for v in times.values())


def test_result_against_targets():
    row = latency.Row("spice", ("spice",), 10.0, target_mib=200.0)
    sample = latency.Sample
    assert latency.Result(row, [sample(9, 5, 150), sample(11, 5, 150), sample(9.5, 5, 150)]).missed() == []
    assert latency.Result(row, [sample(11, 5, 150), sample(9, 5, 150), sample(12, 5, 150)]).missed() == ["wall"]
    assert latency.Result(row, [sample(1, 1, 150), sample(1, 1, 250)]).missed() == ["memory"]  # a peak is a peak


def test_json_result_shape(monkeypatch, capsys):
    """--json: one object on stdout (the table on stderr), a row per row run with its figures."""
    monkeypatch.setattr(latency, "patchgen_command", lambda: _python("print('designed')"))
    status = latency.main(["-n", "2", "--json", "design"])
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    assert "design" in captured.err and "load average" in captured.err
    assert set(result) == {"cores", "repeats", "load_before", "load_after", "rows", "pass"}
    assert result["repeats"] == 2 and len(result["load_before"]) == len(result["load_after"]) == 3
    (row,) = result["rows"]
    assert set(row) == {"name", "command", "in_table", "target_wall_s", "target_peak_mib", "wall_s", "cpu_s",
                        "peak_mib", "load_after", "missed", "pass", "refused"}
    assert (row["name"], row["command"], row["target_wall_s"]) == ("design", "patchgen design bench-recommended", 0.5)
    assert row["refused"] is False
    for figure in ("wall_s", "cpu_s", "peak_mib"):
        assert set(row[figure]) == {"min", "median", "max", "runs"} and len(row[figure]["runs"]) == 2
    assert status == (0 if result["pass"] else 1) and result["pass"] == row["pass"]


@pytest.mark.parametrize("script", sorted(p.name for p in BENCHMARKS.glob("*.py")))
def test_benchmark_imports_exist(script):
    """Every name a benchmark imports from patchgen exists (a renamed function breaks the script
    only when run, which the suite does not do)."""
    tree = ast.parse((BENCHMARKS / script).read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "patchgen":
            module = importlib.import_module(node.module)
            for alias in node.names:
                submodule = hasattr(module, "__path__") and importlib.util.find_spec(f"{node.module}.{alias.name}")
                assert hasattr(module, alias.name) or submodule, f"{script}: {node.module} has no {alias.name}"


def test_a_patch_row_times_a_refusal_and_says_so(tmp_path):
    """A design its machine cannot hold ends in one line and exit 2: a completed run, marked refused;
    any other failure, or a refusal where none is allowed, stops the benchmark."""
    row = next(r for r in latency.rows() if r.name == "patch-thesis-case1-noint")
    sample = latency.run_once(row)
    assert sample.refused and sample.wall_s > 0
    res = latency.Result(row, [sample])
    assert "refused" in latency.table_line(res) and res.as_dict()["refused"]
    strict = latency.Row("strict", row.args, 1.5, writes=row.writes)
    with pytest.raises(latency.RunFailed):
        latency.run_once(strict)
