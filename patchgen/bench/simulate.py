"""Simulate a patched circuit on the bench: the netlist as wired, the nonlinear plant, the real
actuator, sensors and track, and the machine's imperfections; one run or a Monte Carlo.

``ideal=True`` turns every imperfection off and keeps what is wired and what is physical:

- off: sensor noise, amplifier output noise, integrator drift, amplifier saturation (outputs are
  unbounded, but an output that would leave +/- saturation_V is still recorded as an overload),
  the actuator's lag, zero, dead zone and force limit (the actuator is the pure gain K_U of the
  bench);
- kept: the nonlinear plant (eq. 2.16-2.19), every pot setting as dialled (quantised), the x1/x10
  weights and inversions, the differentiator's roll-off as wired (a pure differentiator cannot
  be patched, nor simulated), integrator initial conditions, the track's limit switches (the track
  is not an imperfection) and the scenario's disturbances.

So for small angles an ideal run is the linear closed loop of the netlist's realised coefficients
with the differentiator's roll-off (tests/test_simulate.py checks this).
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numba
import numpy as np

from patchgen.bench import budget
from patchgen.bench.circuit import Circuit, compile_circuit
from patchgen.bench.engine import (
    ACT_GAIN,
    ACT_LAG,
    ACT_LAG_ZERO,
    DIST_CART_FORCE,
    DIST_STEP,
    DIST_TIP_FORCE,
    HISTORY_CHANNELS,
    LANES,
    EngineConfig,
    default_step,
    draw_batch,
    noise_process,
    run_batch,
)
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.render import plot_helper

PERCENTILES = (5, 50, 95)

IDEAL_MEANING = (
    "no sensor or amplifier noise, no integrator drift, no saturation (overloads still recorded), "
    "actuator a pure gain K_U; kept: nonlinear plant, pot settings as dialled, weights and "
    "inversions, differentiator roll-off as wired, limit switches, disturbances")


@dataclass(frozen=True)
class Overload:
    """An amplifier output beyond the rails: when first, and for how long in all."""

    amplifier: str
    first_time_s: float
    total_time_s: float


@dataclass(frozen=True)
class RunSummary:
    """What run ``run`` (random draws from numpy's default generator seeded [seed, run]) did.
    Times are None when the event did not happen. A run ends at the
    scenario's end or at the limit-switch trip (the motor is off, the experiment over): the
    figures cover the run up to there."""

    run: int
    held: bool  # neither fallen nor the limit switches tripped
    limit_switch_tripped: bool
    trip_time_s: float | None
    fallen: bool
    fall_time_s: float | None
    max_abs_theta_deg: float
    max_abs_s_m: float
    rms_theta_deg: float
    max_abs_u_c_V: float
    max_abs_force_N: float
    overloads: tuple[Overload, ...]
    final_state: tuple[float, float, float, float]


@dataclass(frozen=True)
class Distribution:
    """The Monte Carlo over noise seeds: fractions and percentiles (5, 50, 95) of each figure;
    event-time percentiles are over the runs where the event happened (None when none did)."""

    runs: int
    fraction_held: float
    fraction_tripped: float
    fraction_fallen: float
    fraction_overloaded: float
    overload_fraction: dict[str, float]  # per amplifier
    percentiles: dict[str, dict[str, float | None]]


@dataclass(frozen=True)
class SimSettings:
    """What was simulated, resolved from the profiles, the scenario and ``ideal``."""

    dt_s: float
    steps: int
    record_dt_s: float
    sensor_noise_V_rms: dict[str, float]
    sensor_noise_bandwidth_Hz: float
    amplifier_noise_V_rms: float
    amplifier_noise_bandwidth_Hz: float
    integrator_drift_V_per_s: float
    saturation_V: float
    saturation_clipped: bool
    actuator: str
    limit_switches: bool
    half_track_m: float
    plant_spread: dict[str, float]


@dataclass
class SimResult:
    design: str
    scenario: Scenario
    machine: str
    bench: str
    ideal: bool
    seed: int
    settings: SimSettings
    amplifiers: tuple[str, ...]  # in evaluation order, as in the history
    history: dict[str, np.ndarray] | None  # of the first run (its seed is ``seed``'s run 0)
    runs: list[RunSummary]
    distribution: Distribution

    def summary(self) -> dict:
        """Everything but the histories, as plain JSON-able data."""
        return {
            "design": self.design,
            "scenario": self.scenario.model_dump(mode="json", exclude_none=True),
            "machine": self.machine,
            "bench": self.bench,
            "ideal": self.ideal,
            "ideal_meaning": IDEAL_MEANING if self.ideal else None,
            "seed": self.seed,
            "settings": asdict(self.settings),
            "amplifiers": list(self.amplifiers),
            "first_run": _jsonable(asdict(self.runs[0])),
            "distribution": _jsonable(asdict(self.distribution)),
        }


def simulate(netlist: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
             scenario: Scenario, *, seed: int | None = None, runs: int = 1, ideal: bool = False,
             keep_history: bool = True,
             progress: Callable[[int], None] | None = None,
             spread: dict[str, float] | None = None) -> SimResult:
    """Simulate ``runs`` runs of the scenario (seed from the argument, else the scenario's).
    ``spread`` (e.g. {"M": 0.1, "l": 0.1}) draws each run's plant parameters uniformly within
    those fractions of the nominal: the Monte Carlo then covers model error as well as noise.

    Run i draws from ``numpy.random.default_rng([seed, i])`` (drift signs, the key of its
    counter-based noise, its plant), so run 0 of a Monte Carlo is the single run of the same seed.
    ``keep_history`` keeps the first run's time histories. ``progress`` is called with the
    number of runs done after each batch.
    """
    if runs < 1:
        raise InputError("--runs", "", f"must be at least 1 (got {runs})")
    circuit = compile_circuit(netlist, machine)
    base_seed = scenario.seed if seed is None else seed
    if not 0 <= base_seed < 2**63:
        raise InputError("--seed", "", f"must be between 0 and 2**63 - 1 (got {base_seed})")
    cfg, settings = engine_config(circuit, plant, bench, machine, scenario, ideal=ideal, spread=spread)
    budget.check(scenario, runs, step=cfg.dt, stride=cfg.stride, history=keep_history,
                 usual_step=default_step([], ideal))

    # batches of runs, for the progress calls: whole blocks, enough of them for the threads
    per_call = LANES * numba.get_num_threads()
    chunk = per_call * max(1, math.ceil(runs / 20 / per_call))
    parts = []
    for start in range(0, runs, chunk):
        stop = min(start + chunk, runs)
        draws = draw_batch(cfg, [np.random.default_rng([base_seed, i]) for i in range(start, stop)])
        parts.append(run_batch(cfg, draws, 1 if keep_history and start == 0 else 0))
        if progress is not None:
            progress(stop)

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    trip, fall = cat("trip_time"), cat("fall_time")
    ovl_first, ovl_time = cat("overload_first"), cat("overload_time")
    max_th, max_s, rms_th = cat("max_abs_theta"), cat("max_abs_s"), cat("rms_theta")
    max_uc, max_f, final = cat("max_abs_u_c"), cat("max_abs_force"), cat("final_state")
    summaries = [
        RunSummary(
            run=i,
            held=bool(np.isnan(trip[i]) and np.isnan(fall[i])),
            limit_switch_tripped=bool(not np.isnan(trip[i])), trip_time_s=_opt(trip[i]),
            fallen=bool(not np.isnan(fall[i])), fall_time_s=_opt(fall[i]),
            max_abs_theta_deg=math.degrees(max_th[i]), max_abs_s_m=float(max_s[i]),
            rms_theta_deg=math.degrees(rms_th[i]), max_abs_u_c_V=float(max_uc[i]),
            max_abs_force_N=float(max_f[i]),
            overloads=tuple(
                Overload(circuit.amp_ids[j], _opt(ovl_first[i, j]), round(float(ovl_time[i, j]), 9))
                for j in np.argsort(ovl_first[i], kind="stable") if not np.isnan(ovl_first[i, j])),
            final_state=tuple(float(v) for v in final[i]),
        )
        for i in range(runs)
    ]
    history = None
    if keep_history:
        h = parts[0].history[0, :parts[0].history_length[0]]
        names = HISTORY_CHANNELS + circuit.amp_ids
        history = {name: h[:, k].copy() for k, name in enumerate(names)}
    return SimResult(
        design=netlist.design, scenario=scenario, machine=machine.id, bench=bench.id, ideal=ideal,
        seed=base_seed, settings=settings, amplifiers=circuit.amp_ids, history=history,
        runs=summaries, distribution=_distribution(summaries, circuit.amp_ids),
    )


SPREAD_ORDER = ("M", "m", "l", "g", "b_VF", "c", "d")  # the engine's plant vector (d: half track)


def engine_config(circuit: Circuit, plant: PlantParams, bench: BenchProfile,
                  machine: MachineProfile, scenario: Scenario, *,
                  ideal: bool = False, spread: dict[str, float] | None = None) -> tuple[EngineConfig, SimSettings]:
    """Resolve profiles, scenario and ``ideal`` into the engine's arrays (and a readable record).
    ``spread`` gives, per plant parameter, the fraction within which each run draws it."""
    spread = dict(spread or {})
    fastest = [1.0 / v for v in circuit.time_rates() if v > 0]
    if not ideal and bench.actuator.model != "gain":
        fastest.append(bench.actuator.tau)
    step = scenario.dt_s or default_step(fastest, ideal)
    n_steps = max(1, math.ceil(scenario.duration_s / step - 1e-9))
    step = scenario.duration_s / n_steps
    stride = max(1, round(scenario.record_dt_s / step))
    imp = machine.imperfections

    sens = bench.sensors
    if ideal or scenario.noise.mode == "off":
        sensor_rms = {s: 0.0 for s in circuit.sensor_ids}
        amp_rms = 0.0
    elif scenario.noise.mode == "explicit":
        sensor_rms = {s: scenario.noise.level(s) for s in circuit.sensor_ids}
        amp_rms = scenario.noise.level("amplifier")
    else:
        sensor_rms = {s: float(sens.noise_V_rms.get(s, 0.0)) for s in circuit.sensor_ids}
        amp_rms = imp.amplifier_noise_V_rms
    s_proc = [noise_process(sensor_rms[s], sens.noise_bandwidth_Hz, step)
              for s in circuit.sensor_ids]
    a_proc = noise_process(amp_rms, imp.noise_bandwidth_Hz, step)

    if ideal or scenario.drift == "off":
        drift = 0.0
    elif scenario.drift == "profile":
        drift = machine.integrator_drift_V_per_s()
    else:
        drift = float(scenario.drift)

    act = bench.actuator
    if ideal:
        model, tau, dead, flim = ACT_GAIN, 0.0, 0.0, math.inf
        act_text = f"ideal: pure gain K_U = {act.K_U} N/V (no lag, dead zone or force limit)"
    else:
        model = {"gain": ACT_GAIN, "lag": ACT_LAG, "lag_zero": ACT_LAG_ZERO}[act.model]
        tau, dead, flim = act.tau, act.dead_zone_V, act.force_limit_N
        if model != ACT_GAIN and tau <= 0:
            if model == ACT_LAG_ZERO:
                raise InputError(f"bench {bench.id}", "actuator.tau",
                                 "model lag_zero needs tau > 0")
            model = ACT_GAIN
        act_text = (f"{act.model}: K_U = {act.K_U} N/V, tau = {tau} s, "
                    f"dead zone +/-{dead} V, force limit +/-{flim} N")

    kinds, t0s, t1s, vals = [], [], [], []
    for d in scenario.disturbances:
        if d.kind == "step":
            kinds.append(DIST_STEP)
            t0s.append(d.time_s)
            t1s.append(math.inf)
            vals.append(d.size_m)
        else:
            kinds.append(DIST_TIP_FORCE if d.at == "pendulum_tip" else DIST_CART_FORCE)
            t0s.append(d.time_s)
            t1s.append(d.time_s + d.duration_s)
            vals.append(d.force_N)

    n_amp = circuit.n_amps
    cfg = EngineConfig(
        dt=step, n_steps=n_steps, stride=stride,
        x0=np.array(scenario.initial.vector(), dtype=np.float64),
        plant=np.array([plant.M, plant.m, plant.l, plant.g, plant.b_VF, plant.c, plant.d / 2]),
        plant_spread=np.array([spread.get(k, 0.0) for k in SPREAD_ORDER]),
        limit_switches=bool(bench.track.limit_switches),
        sensor_state=circuit.sensor_state, sensor_gain=circuit.sensor_gain,
        sensor_noise_a=np.array([p[0] for p in s_proc]),
        sensor_noise_std=np.array([p[1] for p in s_proc]),
        amp_kind=circuit.amp_kind, in_ptr=circuit.in_ptr, in_src=circuit.in_src,
        in_gain=circuit.in_gain, param1=circuit.param1, param2=circuit.param2, ic_V=circuit.ic_V,
        drift=np.where(circuit.drifting(), drift, 0.0),
        amp_noise_a=np.full(n_amp, a_proc[0]), amp_noise_std=np.full(n_amp, a_proc[1]),
        saturation_V=imp.saturation_V, clip=not ideal, output_index=circuit.output_index,
        actuator=model, K_U=act.K_U, tau=tau, dead_zone_V=dead, force_limit_N=flim,
        dist_kind=np.array(kinds, dtype=np.int64), dist_t0=np.array(t0s, dtype=np.float64),
        dist_t1=np.array(t1s, dtype=np.float64), dist_value=np.array(vals, dtype=np.float64),
        fall_angle=math.radians(scenario.fall_angle_deg),
    )
    settings = SimSettings(
        dt_s=step, steps=n_steps, record_dt_s=stride * step,
        sensor_noise_V_rms=sensor_rms, sensor_noise_bandwidth_Hz=sens.noise_bandwidth_Hz,
        amplifier_noise_V_rms=amp_rms, amplifier_noise_bandwidth_Hz=imp.noise_bandwidth_Hz,
        integrator_drift_V_per_s=drift,
        saturation_V=imp.saturation_V, saturation_clipped=not ideal,
        actuator=act_text, limit_switches=bool(bench.track.limit_switches),
        half_track_m=plant.d / 2,
        plant_spread={k: v for k, v in spread.items() if v},
    )
    return cfg, settings


def _opt(v: float) -> float | None:
    """An event time (n * dt) rounded to the nanosecond, or None when it did not happen."""
    return None if np.isnan(v) else round(float(v), 9)


def _jsonable(obj):
    """Tuples to lists and non-finite floats to None, recursively."""
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _distribution(runs: list[RunSummary], amps: tuple[str, ...]) -> Distribution:
    n = len(runs)

    def pct(values: list[float]) -> dict[str, float | None]:
        if not values:
            return {f"p{q}": None for q in PERCENTILES}
        return {f"p{q}": float(v) for q, v in zip(PERCENTILES, np.percentile(values, PERCENTILES))}

    return Distribution(
        runs=n,
        fraction_held=sum(r.held for r in runs) / n,
        fraction_tripped=sum(r.limit_switch_tripped for r in runs) / n,
        fraction_fallen=sum(r.fallen for r in runs) / n,
        fraction_overloaded=sum(bool(r.overloads) for r in runs) / n,
        overload_fraction={a: sum(any(o.amplifier == a for o in r.overloads) for r in runs) / n
                           for a in amps},
        percentiles={
            "max_abs_theta_deg": pct([r.max_abs_theta_deg for r in runs]),
            "max_abs_s_m": pct([r.max_abs_s_m for r in runs]),
            "rms_theta_deg": pct([r.rms_theta_deg for r in runs]),
            "max_abs_u_c_V": pct([r.max_abs_u_c_V for r in runs]),
            "trip_time_s": pct([r.trip_time_s for r in runs if r.trip_time_s is not None]),
            "fall_time_s": pct([r.fall_time_s for r in runs if r.fall_time_s is not None]),
        },
    )


# ---- output files -------------------------------------------------------------------------

_UNITS = {"t": "s", "s": "m", "theta": "rad", "s_dot": "m_per_s", "theta_dot": "rad_per_s",
          "s_ref": "m", "u_c": "V", "force": "N"}


def write_outputs(result: SimResult, out_dir: str | Path, svg: bool = False) -> list[Path]:
    """Write history.csv (first run), runs.csv (one line per run), summary.json (sorted keys)
    and the history.png plot (and history.svg with ``svg``); same result -> same bytes.
    Returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    plot = plot_helper.submit(_plot, result, out, svg) if result.history is not None else None
    if result.history is not None:
        path = out / "history.csv"
        names = list(result.history)
        header = [f"{n}_{_UNITS.get(n, 'V')}" for n in names]
        cols = np.column_stack([result.history[n] for n in names])
        buf = io.StringIO()
        buf.write(",".join(header) + "\n")
        if np.isnan(cols).any():
            for row in cols:
                buf.write(",".join(_num(v) for v in row) + "\n")
        else:  # one %-format per row: the same text as _num, four times faster
            line = ",".join(["%.9g"] * len(names)) + "\n"
            buf.writelines(line % tuple(row) for row in cols.tolist())
        path.write_text(buf.getvalue())
        written.append(path)
    path = out / "runs.csv"
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["run", "held", "limit_switch_tripped", "trip_time_s", "fallen",
                "fall_time_s", "max_abs_theta_deg", "max_abs_s_m", "rms_theta_deg",
                "max_abs_u_c_V", "max_abs_force_N", "overloads"])
    for r in result.runs:
        w.writerow([r.run, int(r.held), int(r.limit_switch_tripped), _num(r.trip_time_s),
                    int(r.fallen), _num(r.fall_time_s), _num(r.max_abs_theta_deg),
                    _num(r.max_abs_s_m), _num(r.rms_theta_deg), _num(r.max_abs_u_c_V),
                    _num(r.max_abs_force_N),
                    " ".join(f"{o.amplifier}@{_num(o.first_time_s)}" for o in r.overloads)])
    path.write_text(buf.getvalue())
    written.append(path)
    path = out / "summary.json"
    path.write_text(json.dumps(result.summary(), indent=2, sort_keys=True, allow_nan=False) + "\n")
    written.append(path)
    if plot is not None:
        written += plot.result()
    return written


def _num(v: float | None) -> str:
    return "" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.9g}"


def _plot(result: SimResult, out: Path, svg: bool = False) -> list[Path]:
    """The first run's histories, a panel each; u_c shares the panel of the amplifier that
    makes it (the same trace), with the rails."""
    import matplotlib

    from patchgen.render import plotting

    h = result.history
    t = h["t"]
    first = result.runs[0]
    sat = result.settings.saturation_V
    out_amp = [a for a in result.amplifiers if np.array_equal(h[a], h["u_c"])][:1]
    panels = [("s (m)", [("s", h["s"]), ("s_ref", h["s_ref"])], None),
              ("theta (deg)", [("theta", np.degrees(h["theta"]))], None),
              (f"u_c = {out_amp[0]} (V)" if out_amp else "u_c (V)", [("u_c", h["u_c"])], sat if out_amp else None),
              ("force (N)", [("force", h["force"])], None)]
    panels += [(f"{a} (V)", [(a, h[a])], sat) for a in result.amplifiers if a not in out_amp]
    with matplotlib.rc_context({"font.size": 8}):
        fig, axes = plotting.stacked(8.0, 1.5 * len(panels) + 0.6, len(panels))
        cols = plotting.columns(fig)
        for ax, (label, lines, rail) in zip(axes, panels):
            for name, y in lines:
                ax.plot(*plotting.envelope(t, y, cols), lw=0.8, label=name)
            if rail is not None:
                ax.axhline(rail, color="tab:red", lw=0.6, ls="--")
                ax.axhline(-rail, color="tab:red", lw=0.6, ls="--")
            if first.trip_time_s is not None:
                ax.axvline(first.trip_time_s, color="black", lw=0.6, ls=":")
            if first.fall_time_s is not None:
                ax.axvline(first.fall_time_s, color="tab:purple", lw=0.6, ls=":")
            ax.set_ylabel(label)
            ax.grid(True, lw=0.3)
            if len(lines) > 1:
                ax.legend(loc="upper right", fontsize=7, ncols=len(lines))
        axes[-1].set_xlabel("t (s)")
        mode = "ideal" if result.ideal else f"bench {result.bench}"
        events = []
        if first.trip_time_s is not None:
            events.append(f"limit switch at {first.trip_time_s:.2f} s")
        if first.fall_time_s is not None:
            events.append(f"fallen at {first.fall_time_s:.2f} s")
        fig.suptitle(f"{result.design} / {result.scenario.name} / {mode} / seed {result.seed}: "
                     + (", ".join(events) if events else "held"))
        return plotting.save(fig, out / "history.png", out / "history.svg" if svg else None)
