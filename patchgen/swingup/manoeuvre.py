"""The whole manoeuvre: pump up from hanging, hand off to the *patched* controller, hold on the bench.

The pump-up runs on the nonlinear plant (patchgen.swingup.strategies); when the state enters the hand-off
zone the patched circuit (simulated from its netlist with the bench actuator, noise and drift)
takes over from that state, its integrators released from zero (IC -> OP at hand-off).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from patchgen.bench.simulate import SimResult, simulate
from patchgen.inputs.scenario import InitialState, Scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.swingup.handoff import (
    PROBED_ZONE_SAMPLES,
    Zone,
    default_spread,
    estimate_zone,
    lyapunov_matrix,
    wrap_angle,
)
from patchgen.swingup.pumping import SwingUpResult
from patchgen.swingup.run import optimised_schedule, swing_up
from patchgen.swingup.schedule import SensitivityRow, schedule_sensitivity

RECOVERY_S = 5.0  # a start counts as recovered if the patch holds it this long and brings theta home
HOME_DEG = 3.0  # "home": within 3 degrees of upright at the end, as pumping.UPRIGHT_RAD (0.05 rad)
BENCH_HOLD_S = 30.0  # the patched hold after hand-off: long enough for drift and noise to show


@dataclass
class Manoeuvre:
    """A whole manoeuvre: the pump-up, the patched hold after hand-off, the zone and schedule sensitivity."""

    pump: SwingUpResult
    hold: SimResult | None
    hold_s: float
    zone: Zone | None = None
    sensitivity: list[SensitivityRow] | None = None  # the open-loop schedule on plants off by PARAMETER_ERROR

    @property
    def held(self) -> bool:
        """Whether the patched controller held the pendulum after the hand-off."""
        return self.hold is not None and self.hold.runs[0].held


def _start(x: np.ndarray, duration: float, seed: int, name: str) -> Scenario:
    return Scenario(name=name, description=f"{duration:g} s from a hand-off state", duration_s=duration, seed=seed,
                    initial=InitialState(s=float(x[0]), theta=float(wrap_angle(x[1])), s_dot=float(x[2]),
                                         theta_dot=float(x[3])))


def patched_zone(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile, K4: np.ndarray,
                 force_limit: float, n_samples: int = PROBED_ZONE_SAMPLES, seed: int = 0) -> Zone:
    """The zone of control of the patched controller on the bench: a level set of the linear
    design's closed-loop cost (P), its level found by simulating the patched circuit (bench
    actuator, noise and drift) from sampled starts and stopping at the first it does not recover.

    Parameters
    ----------
    net : Netlist
        The patch.
    plant : PlantParams
        The nonlinear plant.
    bench, machine : BenchProfile, MachineProfile
        What the patch meets: actuator, sensors and noise; the machine's imperfections.
    K4 : numpy.ndarray
        The design's gain on s, theta, s_dot, theta_dot (for the zone's quadratic form).
    force_limit : float
        Largest force (N).
    n_samples, seed : int
        How many starts are probed (each RECOVERY_S on the bench), and the seed.

    Returns
    -------
    Zone
        The zone the pump-up must bring the state into.
    """
    P = lyapunov_matrix(plant, K4, force_limit)

    def recovers(x: np.ndarray) -> bool:
        r = simulate(net, plant, bench, machine, _start(x, RECOVERY_S, seed, "zone-probe"), keep_history=False)
        run = r.runs[0]
        return run.held and abs(np.degrees(wrap_angle(run.final_state[1]))) < HOME_DEG

    return estimate_zone(recovers, P, default_spread(plant), n_samples=n_samples, seed=seed,
                         source="patched controller on the bench")


def manoeuvre(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile, K4: np.ndarray,
              strategy: str, force_limit: float, hold_s: float = BENCH_HOLD_S, seed: int = 0,
              ideal: bool = False) -> Manoeuvre:
    """Pump up with ``strategy`` until the state enters the patched controller's zone, then hold
    with the patched controller for ``hold_s`` seconds on the bench.

    Parameters
    ----------
    net, plant, bench, machine, K4, force_limit
        As for patched_zone.
    strategy : {"supervisory", "schedule", "energy"}
        The pump-up law.
    hold_s : float
        The hold after hand-off (s), its integrators released from zero.
    seed : int
        Seed of the zone's starts and of the bench noise.
    ideal : bool
        Simulate the hold with the ideal actuator (a pure gain K_U) instead of the bench's.

    Returns
    -------
    Manoeuvre
        The pump-up, the hold (None when the zone was never reached), the zone and, for
        'schedule', its sensitivity to parameter error.
    """
    zone = patched_zone(net, plant, bench, machine, K4, force_limit, seed=seed)
    sensitivity = None
    if strategy == "schedule":
        sched = optimised_schedule(plant, force_limit, zone)
        pump = swing_up(plant, force_limit, strategy, K4, zone, schedule=sched, hold_s=0.0)
        sensitivity = schedule_sensitivity(plant, sched.schedule, zone, force_limit)
    else:
        pump = swing_up(plant, force_limit, strategy, K4, zone, hold_s=0.0)
    if not pump.reached:
        return Manoeuvre(pump, None, hold_s, zone, sensitivity)
    sc = _start(pump.handoff_state, hold_s, seed, "hold-after-pump-up")
    return Manoeuvre(pump, simulate(net, plant, bench, machine, sc, ideal=ideal), hold_s, zone, sensitivity)
