"""Whole-process time of `patchgen design` on every shipped spec (target: under 2 s each).

Run: python benchmarks/bench_design.py [repeats]
Prints the median and the worst of each spec's wall times, measured as separate processes,
so interpreter start-up and imports count, as a user sees them.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    print(f"{'spec':28s} {'median s':>9s} {'max s':>7s}")
    worst = 0.0
    specs = sorted((ROOT / "designs").glob("*.toml"))
    if not specs:
        sys.exit(f"no design specs in {ROOT / 'designs'}: nothing to time")
    for spec in specs:
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "patchgen", "design", str(spec), "--json"], check=True,
                           capture_output=True, cwd=ROOT)
            times.append(time.perf_counter() - t0)
        worst = max(worst, statistics.median(times))
        print(f"{spec.stem:28s} {statistics.median(times):9.3f} {max(times):7.3f}")
    print(f"slowest median {worst:.3f} s: {'under' if worst < 2 else 'OVER'} the 2 s target")


if __name__ == "__main__":
    main()
