"""Latency a user feels: each command as a whole process (interpreter start-up, imports, work,
output files), timed N times after one warm-up run (which also fills numba's cache).

Run: python benchmarks/bench_latency.py [-n 5] [command ...]   (commands: see TARGETS)
Prints min / median / max wall time per command with its target and whether the median meets
it, and the machine's core count and load average before and after (a busy machine is slower:
compare medians taken at similar load). Exit status 1 when a median misses its target.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# name -> (arguments, target seconds); OUT is replaced by a fresh directory for each run
TARGETS = {
    "help": (["--help"], 0.3),
    "design": (["design", "bench-recommended"], 0.5),
    "patch": (["patch", "bench-recommended", "-o", "OUT"], 1.5),
    "simulate": (["simulate", "bench-recommended", "--scenario", "hold-120s", "--runs", "1", "-o", "OUT"], 1.5),
    "recommend": (["recommend", "bench-recommended", "-o", "OUT"], 10.0),
    "bench-test": (["bench-test", "bench-recommended", "-o", "OUT"], 3.0),
    "identify": (["identify", "REC", "-o", "OUT"], 6.0),
}
RECORDINGS = ["bench-test", "bench-recommended", "--seed", "1", "-o"]  # what REC stands for: made once


def patchgen_command() -> list[str]:
    """The installed console script beside this interpreter, else ``python -m patchgen``."""
    script = Path(sys.executable).with_name("patchgen")
    return [str(script)] if script.exists() else [sys.executable, "-m", "patchgen"]


def time_once(args: list[str], rec: Path) -> float:
    """Wall time of one whole run, in a scratch directory; a failed run stops the benchmark."""
    scratch = Path(tempfile.mkdtemp(prefix="patchgen-latency-"))
    try:
        places = {"OUT": str(scratch / "out"), "REC": str(rec)}
        argv = patchgen_command() + [places.get(a, a) for a in args]
        t0 = time.perf_counter()
        r = subprocess.run(argv, capture_output=True, text=True, cwd=scratch)
        elapsed = time.perf_counter() - t0
        if r.returncode != 0:
            sys.exit(f"{' '.join(args)} failed ({r.returncode}):\n{r.stderr}")
        return elapsed
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", "--repeats", type=int, default=5, help="timed runs per command (default 5)")
    ap.add_argument("commands", nargs="*", metavar="command",
                    help=f"commands to time (default all: {', '.join(TARGETS)})")
    opts = ap.parse_args()
    names = opts.commands or list(TARGETS)
    for n in names:
        if n not in TARGETS:
            ap.error(f"unknown command {n!r} (choose from {', '.join(TARGETS)})")
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"patchgen latency: {cores} cores, load average {load()} (1, 5, 15 min) at the start; "
          f"{opts.repeats} runs per command after one warm-up")
    print(f"{'command':10s} {'min s':>7s} {'median s':>9s} {'max s':>7s} {'target s':>9s}  result")
    missed = 0
    rec = Path(tempfile.mkdtemp(prefix="patchgen-recordings-")) / "rec"
    if "REC" in [a for n in names for a in TARGETS[n][0]]:
        subprocess.run(patchgen_command() + RECORDINGS + [str(rec)], check=True, capture_output=True)
    for name in names:
        args, target = TARGETS[name]
        time_once(args, rec)  # warm-up: page cache, numba's cache, compiled bytecode
        times = [time_once(args, rec) for _ in range(opts.repeats)]
        med = statistics.median(times)
        ok = med < target
        missed += not ok
        print(f"{name:10s} {min(times):7.2f} {med:9.2f} {max(times):7.2f} {target:9.1f}  {'pass' if ok else 'FAIL'}",
              flush=True)
    print(f"load average {load()} at the end")
    shutil.rmtree(rec.parent, ignore_errors=True)
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
