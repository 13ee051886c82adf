"""Speed and accuracy of patchgen's bench simulator. A script, not a timed test.

1. One 60 s run of the section 5.3 patch (tests/fixtures/thesis-ch5.netlist.json) in ideal mode,
   released from 10 deg, through patchgen.bench.simulate and through python-control's
   input_output_response on the same closed loop: the nonlinear plant (patchgen.plant.equations) and the
   same circuit, evaluated in Python from the same compiled netlist arrays. A python-control run
   at rtol 1e-12 (DOP853) is the reference; python-control is timed at each tolerance, and the
   speed ratio is taken at the loosest tolerance whose theta error is no larger than patchgen's
   ("equal accuracy"). The numba compile time is reported apart (a fresh cache in a subprocess).
2. 1000 noisy 60 s Monte-Carlo runs: the same patch with the sensor and amplifier noise and the
   integrator drift of the profiles, saturation, dead zone and force limit, but the actuator's
   lag removed so that every run lasts the full 60 s (with the real 0.2 s lag every run ends at
   the limit switches within seconds, which would flatter the figure; that case is timed too).
   Peak memory is resource.getrusage's maximum resident set of this process.
3. Monte-Carlo throughput: 1000 runs of hold-120s on bench-recommended (120 s at 2 ms, noise and
   drift as the profiles say), in process through patchgen.bench.simulate with numba's cache warm
   (median of --repeats): ns of CPU per run-step (all threads' CPU time over the run-steps done)
   and runs per second of wall time; then the whole command `patchgen simulate bench-recommended
   --scenario hold-120s --runs 1000 -o DIR` in a fresh process (median of --process-repeats),
   which adds the imports, the design, the plots and the files.

The machine's other work shows in every figure: the load average is printed before and after.

Run: python benchmarks/bench_simulate.py [--only accuracy|monte-carlo|throughput]
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from patchgen.bench.circuit import DIFFERENTIATOR, INTEGRATOR, LAG, SUMMER, compile_circuit
from patchgen.bench.simulate import simulate
from patchgen.inputs.scenario import Scenario, load_scenario
from patchgen.patch.netlist import read_netlist
from patchgen.plant.equations import PlantParams, nonlinear_rhs
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine

NETLIST = ROOT / "tests/fixtures/thesis-ch5.netlist.json"
# thesis table B.1 (the design spec, designs/thesis-ch5.toml, will carry these)
PLANT = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)
DURATION_S = 60.0
MC_RUNS = 1000


def _inputs():
    net = read_netlist(NETLIST)
    bench, gp6 = load_bench("uw-1991"), load_machine("gp6")
    base = load_scenario("offset-10deg").model_dump()
    sc = Scenario.model_validate({**base, "duration_s": DURATION_S})
    return net, bench, gp6, sc


def python_control_system(net, bench, gp6):
    """The ideal closed loop as a python-control nlsys: plant states, then one state per
    amplifier (integrator output, lag output, differentiator roll-off state; summers unused)."""
    import control

    c = compile_circuit(net, gp6, bench)
    ns, na = c.n_sensors, c.n_amps
    K_U = bench.actuator.K_U

    def circuit(xp, za):
        sig = np.empty(ns + na)
        sig[:ns] = c.sensor_gain * xp[c.sensor_state]
        dza = np.zeros(na)
        for j in range(na):
            lo, hi = c.in_ptr[j], c.in_ptr[j + 1]
            acc = float(np.dot(c.in_gain[lo:hi], sig[c.in_src[lo:hi]]))
            kind = c.amp_kind[j]
            if kind == SUMMER:
                sig[ns + j] = -acc
            elif kind == INTEGRATOR:
                sig[ns + j] = za[j]
                dza[j] = -c.param1[j] * acc
            elif kind == LAG:
                sig[ns + j] = za[j]
                dza[j] = c.param1[j] * (-acc - za[j])
            else:
                sig[ns + j] = -c.param1[j] * (acc - za[j])
                dza[j] = c.param2[j] * (acc - za[j])
        return sig, dza

    def updfcn(t, x, u, params):
        sig, dza = circuit(x[:4], x[4:])
        return np.concatenate([nonlinear_rhs(PLANT, x[:4], K_U * sig[c.output_index]), dza])

    def initial(x_plant):
        za = c.ic_V.copy()
        for _ in range(na):  # differentiators settled on their input, as patchgen starts them
            sig, _ = circuit(x_plant, za)
            for j in range(na):
                if c.amp_kind[j] == DIFFERENTIATOR:
                    za[j] -= sig[ns + j] / c.param1[j]
        return np.concatenate([x_plant, za])

    sys_ = control.nlsys(updfcn, None, inputs=0, outputs=4 + na, states=4 + na, name="ch5")
    return sys_, initial


def first_call_seconds(cache_dir: str | None) -> tuple[float, float]:
    """Times of the first single-run and the first Monte-Carlo simulate() calls in a fresh
    process (numba compiling, or loading from its cache)."""
    env = dict(os.environ)
    if cache_dir:
        env["NUMBA_CACHE_DIR"] = cache_dir
    out = subprocess.run([sys.executable, __file__, "--first-call"], env=env, check=True,
                         capture_output=True, text=True).stdout
    one, many = out.strip().splitlines()[-1].split()
    return float(one), float(many)


def _load() -> str:
    return "load average " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def main(only: str | None, repeats: int, process_repeats: int) -> None:
    import numba

    print(f"machine: {os.cpu_count()} CPUs, numba threads {numba.get_num_threads()}, {_load()}")
    if only in (None, "accuracy"):
        accuracy()
    if only in (None, "monte-carlo"):
        monte_carlo()
    if only in (None, "throughput"):
        throughput(repeats, process_repeats)
    print(f"\nafter: {_load()}")


def accuracy() -> None:
    import control

    net, bench, gp6, sc = _inputs()
    with tempfile.TemporaryDirectory() as cold:
        t_cold = first_call_seconds(cold)
    t_cached = first_call_seconds(None)
    print(f"first simulate() calls in a fresh process, single run / Monte Carlo: "
          f"{t_cold[0]:.1f} s / {t_cold[1]:.1f} s with numba compiling, "
          f"{t_cached[0]:.2f} s / {t_cached[1]:.2f} s from its cache (cache=True); "
          "excluded from the figures below")

    # 1. one 60 s ideal run ---------------------------------------------------------------------
    simulate(net, PLANT, bench, gp6, sc, ideal=True)  # warm
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        res = simulate(net, PLANT, bench, gp6, sc, ideal=True)
        times.append(time.perf_counter() - t0)
    t_pg = min(times)
    assert res.runs[0].held, "the ideal ch5 patch should hold the 10 deg release"
    T = res.history["t"]
    sys_, initial = python_control_system(net, bench, gp6)
    x0 = initial(np.array(sc.initial.vector()))

    def pc(rtol, method="RK45"):
        t0 = time.perf_counter()
        r = control.input_output_response(sys_, T, 0, x0, solve_ivp_method=method,
                                          solve_ivp_kwargs={"rtol": rtol, "atol": rtol * 1e-2})
        return time.perf_counter() - t0, r.states[1]

    _, ref = pc(1e-12, "DOP853")
    err_pg = math.sqrt(np.mean((res.history["theta"] - ref) ** 2))
    print(f"\n1. one {DURATION_S:.0f} s run, ideal, 10 deg release ({len(T)} samples)")
    print(f"   patchgen: {t_pg * 1e3:.1f} ms (best of 5; step {res.settings.dt_s * 1e3:g} ms, "
          f"{res.settings.steps} RK4 steps), theta error vs reference {err_pg:.2e} rad RMS")
    equal = None
    for rtol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        t_pc, th = pc(rtol)
        err = math.sqrt(np.mean((th - ref) ** 2))
        print(f"   python-control RK45 rtol {rtol:.0e}: {t_pc:7.2f} s, "
              f"theta error {err:.2e} rad RMS, ratio {t_pc / t_pg:8.0f}x")
        if equal is None and err <= err_pg:
            equal = (rtol, t_pc, err)
    if equal is None:
        print("   python-control did not reach patchgen's accuracy at rtol 1e-10; the ratio above "
              "at 1e-10 is a lower bound")
        ratio = t_pc / t_pg
    else:
        ratio = equal[1] / t_pg
        print(f"   at equal accuracy (rtol {equal[0]:.0e}): {ratio:.0f}x faster")
    diff = np.max(np.abs(res.history["theta"] - ref))
    print(f"   trajectory difference patchgen - reference: max |d theta| {diff:.2e} rad")
    print(f"   target >= 100x: {'met' if ratio >= 100 else 'NOT met'}")


def monte_carlo() -> None:
    net, bench, gp6, _ = _inputs()
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    no_lag = bench.model_copy(update={"actuator": bench.actuator.model_copy(
        update={"model": "gain", "tau": 0.0})})
    hold = Scenario(name="hold-60s", duration_s=DURATION_S, noise="profile", drift="profile")
    simulate(net, PLANT, no_lag, gp6, hold.model_copy(update={"duration_s": 1.0}), runs=4 * 64,
             keep_history=False)  # warm: the parallel entry point, from the cache
    t0, c0 = time.perf_counter(), time.process_time()
    mc = simulate(net, PLANT, no_lag, gp6, hold, runs=MC_RUNS, keep_history=False)
    t_mc, cpu_mc = time.perf_counter() - t0, time.process_time() - c0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    d = mc.distribution
    full = sum(r.held for r in mc.runs)
    print(f"\n2. {MC_RUNS} noisy {DURATION_S:.0f} s Monte-Carlo runs (profile noise and drift, "
          "saturation, dead zone, force limit; no actuator lag)")
    print(f"   {t_mc:.2f} s wall, {cpu_mc:.2f} s CPU over all threads ({full} of {MC_RUNS} ran "
          f"the full {DURATION_S:.0f} s); fraction held {d.fraction_held:.3f}, max |theta| "
          f"p50 {d.percentiles['max_abs_theta_deg']['p50']:.2f} deg, "
          f"p95 {d.percentiles['max_abs_theta_deg']['p95']:.2f} deg")
    print(f"   peak memory (max RSS of this process): {rss:.0f} MB (before the Monte Carlo "
          f"{rss_before:.0f} MB)")
    print(f"   target < 10 s: {'met' if t_mc < 10 else 'NOT met'}; target < 1 GB: "
          f"{'met' if rss < 1024 else 'NOT met'}")
    t0 = time.perf_counter()
    real = simulate(net, PLANT, bench, gp6, hold, runs=MC_RUNS, keep_history=False)
    t_real = time.perf_counter() - t0
    print(f"   the same on the real bench (0.2 s lag): {t_real:.2f} s, fraction held "
          f"{real.distribution.fraction_held:.3f}, trip time p50 "
          f"{real.distribution.percentiles['trip_time_s']['p50']:.2f} s (runs end at the trip)")


def throughput(repeats: int, process_repeats: int) -> None:
    import numba

    from patchgen.patch.build import build_patch
    from patchgen.pipeline.design import run_design
    from patchgen.pipeline.inputs import load_inputs, scenario_for

    # as `patchgen simulate` takes them (patchgen.pipeline.simulate.run_simulate)
    inputs = load_inputs("bench-recommended")
    d, machine, bench = run_design(inputs).design, inputs.machine, inputs.bench
    net, plant = build_patch(d, machine), d.plant
    sc = scenario_for("hold-120s", inputs.spec, runs=MC_RUNS)
    threads = numba.get_num_threads()
    simulate(net, plant, bench, machine, sc, runs=1)  # warm: both entry points, from the cache
    simulate(net, plant, bench, machine, sc.model_copy(update={"duration_s": 1.0}), runs=4 * 64)
    walls, cpus = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        res = simulate(net, plant, bench, machine, sc, runs=MC_RUNS)  # as the command: run 0's history kept
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    dt = res.settings.dt_s
    run_steps = sum(round((r.trip_time_s or sc.duration_s) / dt) for r in res.runs)
    wall, cpu = statistics.median(walls), statistics.median(cpus)
    print(f"\n3. {MC_RUNS} runs of {sc.name} on {net.design} ({res.settings.steps} steps of "
          f"{dt * 1e3:g} ms; {run_steps / 1e6:.1f} M run-steps, fraction held "
          f"{res.distribution.fraction_held:.3f}), {threads} threads, {_load()}")
    print(f"   in process, cache warm, median of {repeats}: {wall:.2f} s wall "
          f"(all: {' '.join(f'{w:.2f}' for w in walls)}), {MC_RUNS / wall:.0f} runs/s; "
          f"{cpu:.2f} s CPU, {cpu / run_steps * 1e9:.0f} ns CPU per run-step")
    print(f"   target < 5 s: {'met' if wall < 5 else 'NOT met'}")
    cmd = [sys.executable, "-m", "patchgen", "simulate", "bench-recommended", "--scenario",
           "hold-120s", "--runs", str(MC_RUNS), "-o"]
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(process_repeats):
            t0 = time.perf_counter()
            subprocess.run(cmd + [os.path.join(tmp, str(k))], check=True, capture_output=True)
            times.append(time.perf_counter() - t0)
    print(f"   whole command (`patchgen simulate bench-recommended --scenario hold-120s --runs "
          f"{MC_RUNS} -o DIR`), median of {process_repeats}: {statistics.median(times):.2f} s "
          f"(all: {' '.join(f'{t:.2f}' for t in times)}); {_load()}")


def _first_call() -> None:
    net, bench, gp6, sc = _inputs()
    t0 = time.perf_counter()
    simulate(net, PLANT, bench, gp6, sc, ideal=True)
    t1 = time.perf_counter()
    simulate(net, PLANT, bench, gp6, sc, runs=2)
    print(t1 - t0, time.perf_counter() - t1)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first-call", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--only", choices=("accuracy", "monte-carlo", "throughput"))
    ap.add_argument("--repeats", type=int, default=5, help="in-process Monte Carlos (throughput)")
    ap.add_argument("--process-repeats", type=int, default=3, help="whole commands (throughput)")
    args = ap.parse_args()
    if args.first_call:
        _first_call()
    else:
        main(args.only, args.repeats, args.process_repeats)
