"""How long the README's test command takes, as a new user meets it: a fresh clone of this
checkout's HEAD, numba's cache empty (the first run compiles every kernel), then the same clone
again with the cache filled. Each run is the whole process, `python3 -m pytest` as the README
says, with the wall time, the CPU time of the process and its children (user + sys), and the
slowest modules (their tests' setup, call and teardown summed, from --durations=0).

Run: python benchmarks/bench_suite.py [--warm-only] [--keep DIR]
The clone takes the interpreter that runs this script (patchgen and the test extras installed
in it, editable or not: the clone's own sources are put first on PYTHONPATH), and Python's
default of writing bytecode, as on a fresh machine (PYTHONDONTWRITEBYTECODE is dropped). The core count
and the load average before and after are printed: a busy machine is slower.
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DURATION = re.compile(r"^([\d.]+)s (?:setup|call|teardown)\s+(\S+?)::", re.M)


def load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def run_suite(clone: Path, cache: Path) -> tuple[float, float, str]:
    """Wall and CPU seconds of the README's test command in ``clone``, and its output."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(clone))
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # a fresh machine writes bytecode: the clone's first run compiles it
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "--durations=0"], cwd=clone,
                       env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if r.returncode != 0:
        sys.exit(f"the suite failed ({r.returncode}):\n{r.stdout[-3000:]}\n{r.stderr[-2000:]}")
    return wall, cpu, r.stdout


def slowest(output: str, n: int = 8) -> list[tuple[str, float]]:
    """The n modules whose tests took longest, summed over setup, call and teardown."""
    per = collections.Counter()
    for seconds, module in DURATION.findall(output):
        per[module] += float(seconds)
    return per.most_common(n)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--warm-only", action="store_true", help="skip the run with an empty numba cache")
    ap.add_argument("--keep", type=Path, help="clone into this (new) directory and keep it")
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="patchgen-suite-"))
    clone = args.keep or work / "clone"
    try:
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        head = subprocess.run(["git", "-C", str(clone), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        print(f"{os.cpu_count()} cores, load {load()}; clone of {head}")
        cache = work / "numba-cache"
        runs = ["warm"] if args.warm_only else ["cold", "warm"]
        if args.warm_only:
            run_suite(clone, cache)  # fills the cache, not timed
        for label in runs:
            wall, cpu, out = run_suite(clone, cache)
            summary = out.strip().splitlines()[-1]
            print(f"{label:5s} wall {wall:6.1f} s  CPU {cpu:6.1f} s  ({summary.strip('= ')})")
            for module, seconds in slowest(out):
                print(f"      {seconds:6.1f} s  {module}")
        print(f"load after: {load()}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
