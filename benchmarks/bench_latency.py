"""Latency a user feels: each command of the speed issue's table as a whole process (interpreter
start-up, imports, work, output files), timed N times after one warm-up run (numba's cache, the
page cache, compiled bytecode).

Run: python benchmarks/bench_latency.py [-n 5] [--json] [--all] [--list] [row ...]
A row is named as --list shows (design, patch-bench-lqg, simulate-1000, spice, ...); a command's
name (patch, simulate, recommend) takes all of its rows. Without names, the table's rows run.

For each row: the min / median / max wall time and CPU time of the whole process tree (the command
and every child it waited for, user + system, from wait4), the largest resident set in that tree
(wait4's ru_maxrss: the biggest single process, not a sum), the row's targets beside them and
pass or FAIL. A row passes when its median wall time is under its target and, where it has a
memory target, its largest resident set over the runs is under that. The core count and the load
average before, after each row and at the end are printed: a busy machine is slower, so compare
medians taken at similar load. A run that exits with an unexpected status, or does not write what
its command writes, stops the benchmark with its stderr: a failed run is never timed as a fast one.
Exit status 1 when a row misses its target.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DESIGNS = ROOT / "designs"
RSS_BYTES = 1 if sys.platform == "darwin" else 1024  # ru_maxrss unit: bytes on macOS, KiB on Linux
MIB = 1024 * 1024
RECORDINGS = ("bench-test", "bench-recommended", "--seed", "1", "-o")  # what REC stands for: made once
ROTARY_RECORDINGS = ("bench-test", "qube-servo-2", "--seed", "1", "-o")  # and REC_QUBE, the QUBE's


@dataclass(frozen=True)
class Row:
    """One command to time: its arguments (OUT stands for a fresh output directory, REC and REC_QUBE
    for bench recordings of the cart's and the QUBE's), its targets, and what a run must leave
    behind to count as done."""

    name: str
    args: tuple[str, ...]
    target_s: float  # median wall time, seconds
    target_mib: float | None = None  # largest resident set, MiB
    writes: tuple[str, ...] = ()  # files the run must write under OUT
    stdout: str = ""  # "text": it must print something; "json": a JSON object
    statuses: tuple[int, ...] = (0,)  # exit statuses of a completed run
    refusal: bool = False  # exit 2 with one line on stderr is a completed run too (the spec refused)
    table: bool = True  # in the speed issue's table (else an extra row, run when named)

    def command_line(self) -> str:
        return " ".join(["patchgen", *("DIR" if a == "OUT" else a for a in self.args)])


def shipped_designs(designs: Path = DESIGNS) -> list[str]:
    """The shipped designs patchgen patches: the spec files in designs/ of a plant model the patch
    takes (every one, now)."""
    from patchgen.inputs.spec import load_spec
    from patchgen.pipeline.inputs import plants_of

    return sorted(p.stem for p in designs.glob("*.toml") if load_spec(p).plant.model in plants_of("patch"))


def rows(designs: Path = DESIGNS) -> list[Row]:
    """The speed issue's table (a 2-core machine, whole-process medians), then the extra rows an
    earlier latency round set targets for. ``patch`` has a row for every shipped design it takes; a design
    its machine cannot hold (thesis-case1-noint on the GP-6) is answered by the command's one-line
    refusal, exit 2, and that is timed as its run (the result says so). The table
    says the spice run takes "seconds" in under 200 MiB: 10 s and 200 MiB are its stated targets.
    Without --ideal the deck draws its own noise, so spice exits 1 (differs from patchgen's run
    beyond the tolerance) as a completed run; 3 (no ngspice) is not."""
    patch_files = ("netlist.json", "margins.json", "pots.csv", "patch-sheet.html", "wiring.svg")
    hold = ("--scenario", "hold-120s")
    table = [Row("design", ("design", "bench-recommended"), 0.5, stdout="text")]
    table += [Row(f"patch-{name}", ("patch", name, "-o", "OUT"), 1.5, writes=patch_files, refusal=True)
              for name in shipped_designs(designs)]
    table += [
        Row("simulate-1", ("simulate", "bench-recommended", *hold, "--runs", "1", "-o", "OUT"), 1.5,
            writes=("summary.json", "history.csv")),
        Row("simulate-1000", ("simulate", "bench-recommended", *hold, "--runs", "1000", "-o", "OUT"), 5.0,
            writes=("summary.json", "runs.csv")),
        Row("recommend-uncertain", ("recommend", "bench-recommended", "--bench", "uw-1991-uncertain", "-o", "OUT"),
            15.0, writes=("recommended.toml", "recommendation.json")),
        Row("spice", ("spice", "bench-recommended", *hold, "-o", "OUT"), 10.0, target_mib=200.0,
            writes=("patch.cir", "patch.data", "comparison.json"), statuses=(0, 1)),
    ]
    extra = [
        Row("help", ("--help",), 0.3, stdout="text", table=False),
        Row("recommend-spec-bench", ("recommend", "bench-recommended", "-o", "OUT"), 10.0,
            writes=("recommended.toml",), table=False),
        Row("bench-test", ("bench-test", "bench-recommended", "-o", "OUT"), 3.0, writes=("quiet.csv",),
            table=False),
        Row("identify", ("identify", "REC", "-o", "OUT"), 6.0, writes=("bench.toml",), table=False),
        Row("bench-test-qube", ("bench-test", "qube-servo-2", "-o", "OUT"), 3.0, writes=("free-swing.csv",),
            table=False),
        Row("identify-qube", ("identify", "REC_QUBE", "-o", "OUT"), 6.0, writes=("bench.toml",), table=False),
        Row("swingup-qube", ("swingup", "qube-servo-2", "-o", "OUT"), 10.0, writes=("manoeuvre.json",), table=False),
    ]
    return table + extra


def select(all_rows: list[Row], names: list[str], everything: bool = False) -> list[Row]:
    """The rows named (a row's name, or a command's, which takes every row of that command, e.g.
    ``patch``), in table order; none named: the table's rows, or every row with ``everything``."""
    if not names:
        return [r for r in all_rows if r.table or everything]
    known = {r.name for r in all_rows} | {r.args[0] for r in all_rows}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown row {', '.join(map(repr, unknown))} (choose from "
                         f"{', '.join(r.name for r in all_rows)}, or a command: patch, simulate, recommend)")
    return [r for r in all_rows if r.name in names or r.args[0] in names]


class RunFailed(RuntimeError):
    """A run that did not complete: its time says nothing about the command."""


@dataclass(frozen=True)
class Sample:
    """One whole run: wall seconds, CPU seconds of its process tree, largest resident set (MiB)."""

    wall_s: float
    cpu_s: float
    peak_mib: float
    refused: bool = False  # the run ended in the command's one-line refusal (exit 2)


def patchgen_command() -> list[str]:
    """The installed console script beside this interpreter, else ``python -m patchgen``."""
    script = Path(sys.executable).with_name("patchgen")
    return [str(script)] if script.exists() else [sys.executable, "-m", "patchgen"]


def run_once(row: Row, places: dict[str, str] | None = None, command: list[str] | None = None) -> Sample:
    """One run of the row's command (after ``command``, default patchgen's) in a scratch directory.

    Wall time from start to exit; CPU time and the largest resident set from wait4's rusage, which
    covers the process and every child it waited for (ngspice under spice, numba's threads). Raises
    RunFailed, with the run's stderr, when the exit status is not one the row allows or the run did
    not write or print what the row says it does.
    """
    scratch = Path(tempfile.mkdtemp(prefix="patchgen-latency-"))
    try:
        out = scratch / "out"
        subst = {"OUT": str(out), **(places or {})}
        argv = (command or patchgen_command()) + [subst.get(a, a) for a in row.args]
        with open(scratch / "stdout.txt", "w+b") as so, open(scratch / "stderr.txt", "w+b") as se:
            t0 = time.perf_counter()
            proc = subprocess.Popen(argv, stdout=so, stderr=se, cwd=scratch)
            _, status, usage = os.wait4(proc.pid, 0)
            wall = time.perf_counter() - t0
            proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here: Popen must not wait again
            so.seek(0)
            se.seek(0)
            printed, errors = so.read().decode(errors="replace"), se.read().decode(errors="replace")
        what = f"{row.command_line()} ({row.name})"
        lines = [x for x in errors.splitlines() if x.strip()]
        if row.refusal and proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("patchgen: "):
            return Sample(wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss * RSS_BYTES / MIB, refused=True)
        if proc.returncode not in row.statuses:
            raise RunFailed(f"{what} failed ({proc.returncode}):\n{errors}")
        missing = [f for f in row.writes if not (out / f).is_file()]
        if missing:
            raise RunFailed(f"{what} exited {proc.returncode} without writing {', '.join(missing)}:\n{errors}")
        if row.stdout and not printed.strip():
            raise RunFailed(f"{what} printed nothing:\n{errors}")
        if row.stdout == "json":
            try:
                if not isinstance(json.loads(printed), dict):
                    raise ValueError("not an object")
            except ValueError as exc:
                raise RunFailed(f"{what} printed no JSON object ({exc}):\n{errors}") from None
        return Sample(wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss * RSS_BYTES / MIB)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


@dataclass
class Result:
    """A row's timed runs and what they say against its targets."""

    row: Row
    samples: list[Sample]
    load_after: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def figures(self, attr: str) -> dict[str, float | list[float]]:
        values = [getattr(s, attr) for s in self.samples]
        return {"min": min(values), "median": statistics.median(values), "max": max(values), "runs": values}

    def missed(self) -> list[str]:
        """What the row misses: "wall" (median over its target), "memory" (a run's peak over it)."""
        out = []
        if statistics.median(s.wall_s for s in self.samples) >= self.row.target_s:
            out.append("wall")
        if self.row.target_mib is not None and max(s.peak_mib for s in self.samples) >= self.row.target_mib:
            out.append("memory")
        return out

    def as_dict(self) -> dict:
        r = self.row
        return {"name": r.name, "command": r.command_line(), "in_table": r.table,
                "target_wall_s": r.target_s, "target_peak_mib": r.target_mib,
                "wall_s": self.figures("wall_s"), "cpu_s": self.figures("cpu_s"),
                "peak_mib": self.figures("peak_mib"), "load_after": list(self.load_after),
                "missed": self.missed(), "pass": not self.missed(),
                "refused": any(x.refused for x in self.samples)}


def measure(row: Row, repeats: int, places: dict[str, str] | None = None) -> Result:
    """One untimed warm-up run, then ``repeats`` timed ones."""
    if repeats < 1:
        raise ValueError("at least one timed run per row")
    run_once(row, places)
    samples = [run_once(row, places) for _ in range(repeats)]
    return Result(row, samples, os.getloadavg())


def cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 0


def plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def fmt_load(load: tuple[float, ...] | list[float]) -> str:
    return " ".join(f"{x:.2f}" for x in load)


HEADER = (f"{'':24s} {'wall s':^27s}  {'CPU s (process tree)':^20s}  {'peak RSS MiB':^14s}\n"
          f"{'row':24s} {'min':>6s} {'median':>6s} {'max':>6s} {'target':>6s}  {'min':>6s} {'median':>6s} "
          f"{'max':>6s}  {'max':>6s} {'target':>7s}  {'load':>5s}  result")


def table_line(res: Result) -> str:
    w, c, m = res.figures("wall_s"), res.figures("cpu_s"), res.figures("peak_mib")
    target_mib = f"{res.row.target_mib:7.0f}" if res.row.target_mib is not None else f"{'-':>7s}"
    missed = res.missed()
    verdict = ("pass" if not missed else f"FAIL ({', '.join(missed)})") + (
        " (refused: does not fit)" if any(x.refused for x in res.samples) else "")
    return (f"{res.row.name:24s} {w['min']:6.2f} {w['median']:6.2f} {w['max']:6.2f} {res.row.target_s:6.1f}  "
            f"{c['min']:6.2f} {c['median']:6.2f} {c['max']:6.2f}  {m['max']:6.0f} {target_mib}  "
            f"{res.load_after[0]:5.2f}  {verdict}")


def report(results: list[Result], repeats: int, load_before, load_after) -> dict:
    """The machine-readable result (--json)."""
    return {"cores": cores(), "repeats": repeats, "load_before": list(load_before), "load_after": list(load_after),
            "rows": [r.as_dict() for r in results], "pass": all(not r.missed() for r in results)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-n", "--repeats", type=int, default=5, help="timed runs per row, after one warm-up (default 5)")
    ap.add_argument("--json", action="store_true", help="print the result as JSON on stdout (the table goes to stderr)")
    ap.add_argument("--all", action="store_true", help="the extra rows too when none is named")
    ap.add_argument("--list", action="store_true", help="print the rows, their commands and targets, and stop")
    ap.add_argument("names", nargs="*", metavar="row", help="rows to time (default: the table's)")
    opts = ap.parse_args(argv)
    if opts.repeats < 1:
        ap.error("--repeats must be at least 1")
    every = rows()
    try:
        chosen = select(every, opts.names, opts.all)
    except ValueError as exc:
        ap.error(str(exc))
    if opts.list:
        for r in every:
            mem = f", peak under {r.target_mib:g} MiB" if r.target_mib is not None else ""
            print(f"{r.name:24s} {r.command_line()}  (under {r.target_s:g} s{mem}{'' if r.table else '; extra'})")
        return 0
    show = sys.stderr if opts.json else sys.stdout
    load_before = os.getloadavg()
    print(f"patchgen latency, whole processes: {cores()} cores, load average {fmt_load(load_before)} "
          f"(1, 5, 15 min) at the start; {plural(opts.repeats, 'timed run')} per row after one warm-up", file=show)
    print(HEADER, file=show, flush=True)
    work = Path(tempfile.mkdtemp(prefix="patchgen-recordings-"))
    places = {"REC": str(work / "rec"), "REC_QUBE": str(work / "rec-qube")}
    results = []
    try:
        for key, made_by in (("REC", RECORDINGS), ("REC_QUBE", ROTARY_RECORDINGS)):
            if any(key in r.args for r in chosen):
                subprocess.run(patchgen_command() + list(made_by) + [places[key]], check=True, capture_output=True)
        for row in chosen:
            try:
                res = measure(row, opts.repeats, places)
            except RunFailed as exc:
                sys.exit(str(exc))
            results.append(res)
            print(table_line(res), file=show, flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    load_after = os.getloadavg()
    print(f"load average {fmt_load(load_after)} at the end", file=show)
    result = report(results, opts.repeats, load_before, load_after)
    if opts.json:
        print(json.dumps(result, indent=2))
    return 0 if result["pass"] else 1


if __name__ == "__main__":
    sys.exit(main())
