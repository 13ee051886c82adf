"""One entry point for the pump-up manoeuvre and the comparison of strategies.

``swing_up(plant, force_limit, strategy, zone, K)`` runs the full manoeuvre from hanging at rest:
pump with the chosen strategy, hand off to sat(-K x) when the state enters the zone, hold.
``compare_strategies`` tabulates time to the zone, cart excursion and robustness to +/-10 %
parameter error for all three strategies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from patchgen.plant.equations import PlantParams
from patchgen.swingup.handoff import Zone, lqr_zone
from patchgen.swingup.pumping import HOLD_S, PUMP_T_MAX_S, STEP_S, SwingUpResult, saturated_state_feedback, simulate
from patchgen.swingup.schedule import (
    PARAMETER_ERROR,
    OptimisedSchedule,
    ScheduleSettings,
    optimise_schedule,
    perturbed_plants,
    replay,
    schedule_from_result,
)
from patchgen.swingup.strategies import STRATEGIES, EnergyControl, EnergySettings, Supervisor, SupervisorSettings


def default_zone(plant: PlantParams, K: np.ndarray, force_limit: float) -> Zone:
    """The zone of the linear design (Lyapunov level set checked on the nonlinear plant)."""
    return lqr_zone(plant, K, force_limit)


def swing_up(
    plant: PlantParams,
    force_limit: float,
    strategy: str,
    K: np.ndarray,
    zone: Zone | None = None,
    *,
    model: PlantParams | None = None,
    schedule: OptimisedSchedule | None = None,
    t_max: float = PUMP_T_MAX_S,
    hold_s: float = HOLD_S,
    dt: float = STEP_S,
) -> SwingUpResult:
    """Full manoeuvre on ``plant``: pump up from hanging, hand off to sat(-K x) in the zone, hold.

    Parameters
    ----------
    plant : PlantParams
        The plant simulated.
    force_limit : float
        Largest force (N).
    strategy : {"supervisory", "schedule", "energy"}
        The pump-up law.
    K : array_like
        State-feedback gain of the linear controller (its first four entries).
    zone : Zone, optional
        The hand-off zone (default: default_zone on the model).
    model : PlantParams, optional
        The plant the strategy's logic and schedule are worked out on (default: ``plant``).
    schedule : OptimisedSchedule, optional
        For 'schedule': the table to replay; without one, the supervisory run on the model seeds
        the optimisation.
    t_max, hold_s, dt : float
        Longest pump-up, hold after hand-off and step (s).

    Returns
    -------
    SwingUpResult
        The run; for 'schedule' its notes carry the predicted and seed final times, and whether
        (and why) the optimiser kept its seed.
    """
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {strategy!r} (known: {', '.join(STRATEGIES)})")
    model = plant if model is None else model
    zone = default_zone(model, K, force_limit) if zone is None else zone
    hold = saturated_state_feedback(K, force_limit)
    common = dict(force_limit=force_limit, hold=hold, t_max=t_max, hold_s=hold_s, dt=dt)
    if strategy == "supervisory":
        return simulate(plant, Supervisor(model, force_limit), zone, strategy=strategy, **common)
    if strategy == "energy":
        return simulate(plant, EnergyControl(model, force_limit), zone, strategy=strategy, **common)
    if schedule is None:
        schedule = optimised_schedule(model, force_limit, zone)
    result = replay(plant, schedule.schedule, zone, force_limit, K, t_max=t_max, hold_s=hold_s, dt=dt)
    result.notes.update(predicted_T_F=schedule.T_F, seed_T_F=schedule.seed_T_F,
                        optimised=schedule.success, iterations=schedule.iterations, kept_seed=schedule.kept_seed,
                        kept_seed_note=schedule.note())
    return result


def optimised_schedule(
    model: PlantParams, force_limit: float, zone: Zone, settings: ScheduleSettings | None = None
) -> OptimisedSchedule:
    """The supervisory table on the model, then the minimum-time switching times from it.

    Parameters
    ----------
    model : PlantParams
        The plant the schedule is worked out on.
    force_limit : float
        Largest force (N).
    zone : Zone
        The hand-off zone the schedule must end in.
    settings : ScheduleSettings, optional
        The optimiser's tuning.

    Returns
    -------
    OptimisedSchedule
        The schedule, its predicted final time and the seed's.
    """
    seed_run = simulate(model, Supervisor(model, force_limit), zone, strategy="supervisory",
                        force_limit=force_limit, hold=None)
    seed, T = schedule_from_result(seed_run)
    return optimise_schedule(model, zone, seed, T, settings)


@dataclass(frozen=True)
class StrategySummary:
    """One row of the comparison: nominal figures and how many perturbed plants still succeed."""

    strategy: str
    time_to_zone_s: float | None
    max_abs_s_m: float
    energy_ratio: float | None
    held: bool
    robust_reached: int
    robust_total: int
    worst_time_s: float | None


def robustness(
    plant: PlantParams, force_limit: float, strategy: str, K: np.ndarray, zone: Zone,
    schedule: OptimisedSchedule | None = None, by: float = PARAMETER_ERROR, t_max: float = PUMP_T_MAX_S,
) -> list[tuple[str, float, SwingUpResult]]:
    """Run a strategy designed on ``plant`` against each plant with one parameter off by +/-by.

    Parameters
    ----------
    plant : PlantParams
        The nominal plant: the model the strategy works with.
    force_limit, strategy, K, zone, schedule
        As for swing_up.
    by : float
        The fractional error of each parameter in turn (PARAMETER_ERROR).
    t_max : float
        Longest pump-up (s).

    Returns
    -------
    list of (str, float, SwingUpResult)
        Parameter name, its factor, and the pump-up on that plant (no hold).
    """
    return [
        (name, f, swing_up(p, force_limit, strategy, K, zone, model=plant, schedule=schedule,
                           t_max=t_max, hold_s=0.0))
        for name, f, p in perturbed_plants(plant, by)
    ]


def compare_strategies(
    plant: PlantParams, force_limit: float, K: np.ndarray, zone: Zone | None = None,
    by: float = PARAMETER_ERROR, t_max: float = PUMP_T_MAX_S,
) -> list[StrategySummary]:
    """Time to zone, max |s|, E/E0 at hand-off, and success on the 10 perturbed plants.

    Parameters
    ----------
    plant : PlantParams
        The nominal plant.
    force_limit : float
        Largest force (N).
    K : array_like
        State-feedback gain of the linear controller.
    zone : Zone, optional
        The hand-off zone (default: default_zone).
    by, t_max : float
        The parameter error of the robustness runs, and the longest pump-up (s).

    Returns
    -------
    list of StrategySummary
        One row per strategy, in STRATEGIES order.
    """
    zone = default_zone(plant, K, force_limit) if zone is None else zone
    sched = optimised_schedule(plant, force_limit, zone)
    rows = []
    for strategy in STRATEGIES:
        nominal = swing_up(plant, force_limit, strategy, K, zone, schedule=sched, t_max=t_max)
        runs = robustness(plant, force_limit, strategy, K, zone, sched, by, t_max)
        ok = [r for _, _, r in runs if r.reached and r.on_track]
        rows.append(StrategySummary(
            strategy=strategy, time_to_zone_s=nominal.handoff_time, max_abs_s_m=nominal.max_abs_s_pump,
            energy_ratio=nominal.energy_ratio_at_handoff, held=nominal.held,
            robust_reached=len(ok), robust_total=len(runs),
            worst_time_s=max((r.handoff_time for r in ok), default=None),
        ))
    return rows


__all__ = [
    "EnergySettings",
    "StrategySummary",
    "SupervisorSettings",
    "compare_strategies",
    "default_zone",
    "optimised_schedule",
    "robustness",
    "swing_up",
]
