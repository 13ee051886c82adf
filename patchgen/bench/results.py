"""What a simulation found: each run's summary, the Monte Carlo's distribution, the settings
simulated, and the first run's history (``SimResult``); built from the engine's batches."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from patchgen.bench.engine import BatchOutput
from patchgen.inputs.scenario import Scenario
from patchgen.plant.plant_model import PLANT_MODELS

PERCENTILES = (5, 50, 95)

IDEAL_MEANING = (
    "no sensor or amplifier noise, no encoder counts, no random force on the plant, no integrator drift, "
    "no saturation (overloads still recorded), "
    "actuator a pure gain K_U (a motor's back-EMF and rotor kept: they are the plant's); kept: nonlinear plant, "
    "pot settings as dialled, weights and inversions, differentiator roll-off as wired, sensors' velocity "
    "filters, limit switches, disturbances")


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
    actuator_limit_time_s: float  # the command sat at the actuator's limit (a motor's: the amplifier's) this long
    final_state: tuple[float, float, float, float]
    drawn: tuple[tuple[str, float], ...] = ()  # the run's plant (--spread) and bench (--bench-spread) draws
    amp_peaks_V: tuple[tuple[str, float], ...] = ()  # each amplifier's largest |output| (V, before the rails)
    # while the pendulum is up (to its fall, in a run that falls)

    def amp_peak(self, amplifier: str) -> float:
        """One amplifier's largest |output| over the run (V, before the rails; 0 when not recorded)."""
        return next((v for a, v in self.amp_peaks_V if a == amplifier), 0.0)


@dataclass(frozen=True)
class Distribution:
    """The Monte Carlo over noise seeds: fractions and percentiles (5, 50, 95) of each figure;
    event-time percentiles are over the runs where the event happened (None when none did)."""

    runs: int
    fraction_held: float
    fraction_tripped: float
    fraction_fallen: float
    fraction_overloaded: float
    fraction_at_actuator_limit: float  # runs whose command sat at the actuator's limit (a fact, not a fault)
    overload_fraction: dict[str, float]  # per amplifier
    percentiles: dict[str, dict[str, float | None]]
    # per amplifier: percentiles of its largest |output| over a run (V, before the rails), and the most
    amplifier_peak_V: dict[str, dict[str, float | None]] = field(default_factory=dict)


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
    cart_force_N_rms: float  # the bench's random force on the cart (on a rotary arm: its torque, N m)
    tip_force_N_rms: float  # and at the pendulum's tip
    force_bandwidth_Hz: float
    saturation_V: float
    saturation_clipped: bool
    actuator: str
    limit_switches: bool
    half_track_m: float | None  # where the run ends at the position's limit (a rotary arm's cable: rad; None: no
    # limit, a slip ring)
    watchdog_m: float | None  # the lab's control cuts the motor at this |s| (none: the switches alone)
    plant_spread: dict[str, float]
    bench_spread: dict[str, list[float]] = field(default_factory=dict)  # key -> [low, high] each run drew from
    bench_distribution: str | None = None  # how: uniform or normal (None: no bench spread)
    plant: str = "cart-pendulum"  # the plant model simulated (patchgen.plant.plant_model): its words name the figures
    measured_plant: dict[str, float] = field(default_factory=dict)  # the bench's own plant figures, in the spec's place


@dataclass
class SimResult:
    """A simulation: what was simulated (design, scenario, profiles, ``ideal``, seed, settings),
    each run's summary, their distribution and the first run's history (channel name -> samples:
    patchgen.bench.kernel.HISTORY_CHANNELS, then the amplifiers)."""

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
    # what each amplifier's output is meant to carry, by id: (polarity, quantity), from the netlist
    carries: dict[str, tuple[int, str]] = field(default_factory=dict)

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
            "settings": _settings(self.settings),
            "amplifiers": list(self.amplifiers),
            "first_run": _position_named(_jsonable(asdict(self.runs[0])), self.settings.plant),
            "distribution": _position_named(_jsonable(asdict(self.distribution)), self.settings.plant),
        }


def _settings(settings: SimSettings) -> dict:
    """The settings as plain data; ``measured_plant`` only where the bench states its own figures."""
    out = asdict(settings)
    if not out["measured_plant"]:
        del out["measured_plant"]
    return out


def _position_named(data: dict, plant: str) -> dict:
    """``data`` with the largest |position| under its plant's key (max_abs_alpha_rad on a rotary arm;
    the runs' field is the cart's max_abs_s_m), at the top and among the percentiles."""
    key = PLANT_MODELS[plant].position_key
    rename = lambda d: {key if k == "max_abs_s_m" else k: v for k, v in d.items()}
    out = rename(data)
    if isinstance(out.get("percentiles"), dict):
        out["percentiles"] = rename(out["percentiles"])
    return out


def run_summaries(parts: list[BatchOutput], amp_ids: tuple[str, ...], first_run: int = 0,
                  drawn: list[tuple[tuple[str, float], ...]] | None = None,
                  harmless: tuple[str, ...] = ()) -> list[RunSummary]:
    """Each run's summary, from the engine's batches in run order.

    Parameters
    ----------
    parts : list of BatchOutput
        The batches, the first run first.
    amp_ids : tuple of str
        The amplifiers in evaluation order (the engine's columns).
    first_run : int
        The first run's number.
    drawn : list, optional
        Each run's drawn parameters (patchgen.bench.engine.drawn), in run order.
    harmless : tuple of str
        Amplifiers whose excursion past the rails is not an overload: the command's, when it is a
        summer feeding an actuator whose own limit is within the rails (clipped there, it asks
        what the actuator would give anyway); its time at the limit is reported instead.

    Returns
    -------
    list of RunSummary
        One per run, numbered from ``first_run``.
    """
    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    trip, fall = cat("trip_time"), cat("fall_time")
    ovl_first, ovl_time = cat("overload_first"), cat("overload_time")
    max_th, max_s, rms_th = cat("max_abs_theta"), cat("max_abs_s"), cat("rms_theta")
    max_uc, max_f, final = cat("max_abs_u_c"), cat("max_abs_force"), cat("final_state")
    limit, peak = cat("limit_time"), cat("amp_peak")
    return [
        RunSummary(
            run=first_run + i,
            held=bool(np.isnan(trip[i]) and np.isnan(fall[i])),
            limit_switch_tripped=bool(not np.isnan(trip[i])), trip_time_s=_opt(trip[i]),
            fallen=bool(not np.isnan(fall[i])), fall_time_s=_opt(fall[i]),
            max_abs_theta_deg=math.degrees(max_th[i]), max_abs_s_m=float(max_s[i]),
            rms_theta_deg=math.degrees(rms_th[i]), max_abs_u_c_V=float(max_uc[i]),
            max_abs_force_N=float(max_f[i]),
            overloads=tuple(
                Overload(amp_ids[j], _opt(ovl_first[i, j]), round(float(ovl_time[i, j]), 9))
                for j in np.argsort(ovl_first[i], kind="stable") if not np.isnan(ovl_first[i, j])
                and amp_ids[j] not in harmless),
            actuator_limit_time_s=round(float(limit[i]), 9),
            final_state=tuple(float(v) for v in final[i]),
            drawn=drawn[i] if drawn else (),
            amp_peaks_V=tuple((a, float(peak[i, j])) for j, a in enumerate(amp_ids)),
        )
        for i in range(len(trip))
    ]


def distribution(runs: list[RunSummary], amps: tuple[str, ...]) -> Distribution:
    """The Monte Carlo's fractions and percentiles over ``runs`` (``amps``: every amplifier)."""
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
        fraction_at_actuator_limit=sum(r.actuator_limit_time_s > 0 for r in runs) / n,
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
        amplifier_peak_V={a: {**pct([r.amp_peak(a) for r in runs]), "max": max(r.amp_peak(a) for r in runs)}
                          for a in amps},
    )


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
