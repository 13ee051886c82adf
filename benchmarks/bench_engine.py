"""The engine's cost per run-step against its floor, in the same process and the same run.

Both run one block of runs (the engine's LANES) of hold-120s on the shipped bench-recommended
patch, on one thread, from the same draws: patchgen's engine (patchgen.bench.kernel.run_block) and the lean
loop of benchmarks/engine_floor.py, which is the same closed loop written out by hand. The
lean loop must end every run where the engine does (it is checked before anything is timed),
so the ratio compares the same work. Prints ns of CPU per run-step for each (best of --repeats
after a warm-up; the lean loop's compilation is not timed), their ratio against the 1.5x target,
and the load average before and after.

Run: python benchmarks/bench_engine.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT))

from engine_floor import lean_block  # noqa: E402

from patchgen.bench import kernel  # noqa: E402
from patchgen.bench.circuit import compile_circuit  # noqa: E402
from patchgen.bench.configure import engine_config  # noqa: E402
from patchgen.bench.engine import LANES, draw_batch, run_batch  # noqa: E402
from patchgen.bench.lanes import A_DEAD_ZONE, A_FORCE_LIMIT, A_K_U, A_TAU  # noqa: E402
from patchgen.inputs.scenario import load_scenario  # noqa: E402
from patchgen.patch.build import build_patch  # noqa: E402
from patchgen.pipeline.design import run_design  # noqa: E402
from patchgen.pipeline.inputs import load_inputs  # noqa: E402

TARGET = 1.5


def _load() -> str:
    return "load average " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def config():
    """The engine's records for bench-recommended in hold-120s, and LANES runs' draws."""
    inputs = load_inputs("bench-recommended")
    design = run_design(inputs).design
    circuit = compile_circuit(build_patch(design, inputs.machine), inputs.machine, inputs.bench)
    cfg, _ = engine_config(circuit, design.plant, inputs.bench, inputs.machine, load_scenario("hold-120s"))
    draws = draw_batch(cfg, [np.random.default_rng([1, i]) for i in range(LANES)])
    return cfg, draws


def lean(cfg, draws):
    """The lean loop on the same draws: (final state (lanes, 4), max |theta|, run-steps)."""
    s, a = cfg.settings, cfg.actuator
    act = np.array([a[A_K_U], a[A_DEAD_ZONE], a[A_FORCE_LIMIT], 1.0 / a[A_TAU]])
    w = cfg.wiring
    gains = np.concatenate([w.in_gain, w.param1[:2], w.param2[1:2]])
    x, mth, _, done = lean_block(draws.keys, draws.signs, draws.plants, draws.sensor_gains, draws.noise_std,
                                 cfg.noise.a, s.x0, act, gains, w.drift[0], s.dt, s.steps, s.saturation)
    return x.T, mth, done


def best_cpu(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        c0 = time.thread_time()
        fn()
        times.append(time.thread_time() - c0)
    return min(times)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="timed runs of each loop (default 5)")
    opts = ap.parse_args()
    print(f"before: {_load()}")
    cfg, draws = config()
    out = run_batch(cfg, draws, 0)  # warm (the engine from its cache), and the reference
    x, mth, done = lean(cfg, draws)
    steps = np.where(np.isnan(out.trip_time), cfg.settings.steps,
                     np.round(np.nan_to_num(out.trip_time) / cfg.settings.dt)).sum()
    if done != steps or not (np.array_equal(x, out.final_state) and np.array_equal(mth, out.max_abs_theta)):
        diff = np.max(np.abs(x - out.final_state))
        print(f"the lean loop is not the engine's closed loop: run-steps {done} against {steps:.0f}, "
              f"final states apart by up to {diff:.3g}")
        return 1
    args = (0, LANES, draws, *cfg.records, out_records(cfg, draws))
    t_engine = best_cpu(lambda: kernel.run_block(*args), opts.repeats)
    t_lean = best_cpu(lambda: lean(cfg, draws), opts.repeats)
    ns_engine, ns_lean = t_engine / done * 1e9, t_lean / done * 1e9
    ratio = ns_engine / ns_lean
    print(f"{LANES} runs of hold-120s on bench-recommended, one thread, {done / 1e6:.2f} M run-steps, "
          f"the same final states to the bit")
    print(f"engine     {ns_engine:6.1f} ns CPU per run-step")
    print(f"lean loop  {ns_lean:6.1f} ns CPU per run-step")
    print(f"ratio      {ratio:6.2f}x (target {TARGET}x: {'met' if ratio <= TARGET else 'NOT met'})")
    print(f"after: {_load()}")
    return 0 if ratio <= TARGET else 1


def out_records(cfg, draws):
    """Fresh output records for a timed engine run (as run_batch makes them, without histories)."""
    runs, n_amp = draws.signs.shape
    results = np.zeros((runs, len(kernel.RESULTS)))
    results[:, [kernel.R_TRIP, kernel.R_FALL]] = np.nan
    return kernel.Outputs(results=results, overload_first=np.full((runs, n_amp), np.nan),
                          overload_time=np.zeros((runs, n_amp)), amp_peak=np.zeros((runs, n_amp)),
                          history=np.zeros((0, 1, kernel.H_AMPS + n_amp)),
                          history_length=np.zeros(0, dtype=np.int64))


if __name__ == "__main__":
    sys.exit(main())
