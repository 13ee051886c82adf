"""Whole-process time of `patchgen design SPEC --json` on every shipped spec, against 0.5 s each:
the speed issue's table sets 0.5 s (median wall, 2-core machine) for `patchgen design
bench-recommended`; a user may design any shipped spec, so each is held to it here.

Run: python benchmarks/bench_design.py [-n REPEATS]
Each spec is run once to warm up, then timed REPEATS times as a separate process (interpreter
start-up and imports count, as a user meets them). Prints each spec's min / median / max wall time
and median CPU time (the process and its children), the slowest median against the target, and
the load average before and after. Refuses to report (exit status 2) when it timed nothing: no
spec in designs/, no repeats, or a run that failed or printed no design. Exit status 1 when the
slowest median misses the target.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_latency import DESIGNS, Row, RunFailed, Sample, cores, fmt_load, plural, run_once

TARGET_S = 0.5  # the speed issue's table: `patchgen design bench-recommended`, median wall


class NothingTimed(RuntimeError):
    """The benchmark has no figure to give: nothing ran, or a run did not do the work."""


def time_designs(folder: Path = DESIGNS, repeats: int = 5,
                 command: list[str] | None = None) -> dict[str, list[Sample]]:
    """Each spec file in ``folder`` designed (``command`` + ``design SPEC --json``, default
    patchgen's) once to warm up and ``repeats`` times timed. Raises NothingTimed when there is no
    spec or no repeat, or a run fails or prints no JSON design."""
    specs = sorted(Path(folder).glob("*.toml"))
    if not specs:
        raise NothingTimed(f"no design specs in {folder}: nothing to time")
    if repeats < 1:
        raise NothingTimed("no timed runs asked for (repeats < 1)")
    out = {}
    for spec in specs:
        row = Row(f"design-{spec.stem}", ("design", str(spec), "--json"), TARGET_S, stdout="json")
        try:
            run_once(row, command=command)
            out[spec.stem] = [run_once(row, command=command) for _ in range(repeats)]
        except RunFailed as exc:
            raise NothingTimed(str(exc)) from None
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-n", "--repeats", type=int, default=5, help="timed runs per spec after one warm-up (default 5)")
    opts = ap.parse_args(argv)
    before = os.getloadavg()
    try:
        times = time_designs(DESIGNS, opts.repeats)
    except NothingTimed as exc:
        print(f"no result: {exc}", file=sys.stderr)
        return 2
    print(f"patchgen design, whole processes: {cores()} cores, load average {fmt_load(before)} at the start; "
          f"{plural(opts.repeats, 'timed run')} per spec after one warm-up")
    print(f"{'spec':24s} {'min s':>6s} {'median':>6s} {'max s':>6s}  {'CPU s':>6s}")
    for name, samples in times.items():
        walls = [s.wall_s for s in samples]
        print(f"{name:24s} {min(walls):6.3f} {statistics.median(walls):6.3f} {max(walls):6.3f}  "
              f"{statistics.median(s.cpu_s for s in samples):6.3f}")
    name, worst = max(((n, statistics.median(s.wall_s for s in v)) for n, v in times.items()), key=lambda t: t[1])
    ok = worst < TARGET_S
    print(f"slowest median {worst:.3f} s ({name}): {'under' if ok else 'OVER'} the {TARGET_S} s target")
    print(f"load average {fmt_load(os.getloadavg())} at the end")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
