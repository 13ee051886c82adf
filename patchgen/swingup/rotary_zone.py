"""The rotary pendulum's hand-off zone: where the *patched* circuit, on the bench, catches the pendulum.

As the cart's manoeuvre does (patchgen.swingup.manoeuvre.patched_zone), the zone is a level set
x^T P x < r of the linear design's closed-loop cost (patchgen.swingup.handoff.closed_loop_cost),
cut to a sampled box; r is found by simulating the patched circuit from sampled starts in order of
increasing x^T P x and stopping at the first it does not recover (handoff.estimate_zone). A rotary
start counts as recovered only if every one of ZONE_RUNS noise seeds holds it: the hold after the
pump-up is judged over many seeds, and a start that one seed in twenty loses is no place to hand off.
"""

from __future__ import annotations

import math

import numpy as np

from patchgen.bench.simulate import simulate
from patchgen.inputs.scenario import InitialState, Scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.rotary_equations import RotaryParams, inertias, linear_matrices
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.swingup.handoff import PROBED_ZONE_SAMPLES, Zone, closed_loop_cost, estimate_zone
from patchgen.swingup.rotary_energy import CATCH_ANGLE_RAD, wrap

RECOVERY_S = 5.0  # a start is recovered if the patch holds it this long and brings theta home
HOME_DEG = 3.0  # "home": within 3 deg of upright at the end, as the cart's zone asks
ZONE_RUNS = 20  # noise seeds per start, all of which must hold it (20 ms of bench time a start)
ZONE_SEED = 0  # the starts' and their noise's seed: the zone is the patch's, the same for every hold
# the sampled box's arm half-width: half the way to the cable's wind-up (pi on a QUBE), so a start
# inside it leaves the patch room to bring the arm home
ARM_SHARE = 0.5
# the box's rates (both): twice the rate a pendulum falling from upright has at the catch angle
# (theta' = 2 sin(theta/2) omega_0, with E = E_0): the pump's arrivals, aimed just above E_0, lie within it
RATE_SCALE = 2.0


def rotary_spread(plant: RotaryParams) -> np.ndarray:
    """Half-widths of the sampled box over alpha, theta, alpha_dot, theta_dot (ARM_SHARE, RATE_SCALE)."""
    c = inertias(plant)
    omega_0 = math.sqrt(c.G / c.J_2)
    rate = RATE_SCALE * 2.0 * math.sin(CATCH_ANGLE_RAD / 2.0) * omega_0
    arm = ARM_SHARE * plant.alpha_limit if math.isfinite(plant.alpha_limit) else math.pi
    return np.array([arm, CATCH_ANGLE_RAD, rate, rate])


def rotary_cost(plant: RotaryParams, K: np.ndarray, v_limit: float) -> np.ndarray:
    """P of the zone: the closed loop's cost-to-go with the states weighted by 1/spread^2 and the
    voltage by 1/v_limit^2 (a state that saturates the amplifier counts as far from upright)."""
    A, B = linear_matrices(plant)
    return closed_loop_cost(A, B, K, v_limit, rotary_spread(plant) ** -2.0)


def start_scenario(x: np.ndarray, duration: float, seed: int, name: str = "hold-after-pump-up") -> Scenario:
    """The bench's noise for ``duration`` s from state x (theta wrapped about upright)."""
    return Scenario(name=name, description=f"{duration:g} s from a hand-off state",
                    duration_s=duration, seed=seed,
                    initial=InitialState(alpha=float(x[0]), theta=float(wrap(x[1])), alpha_dot=float(x[2]),
                                         theta_dot=float(x[3])))


def patched_rotary_zone(net: Netlist, plant: RotaryParams, bench: BenchProfile, machine: MachineProfile,
                        K: np.ndarray, n_samples: int = PROBED_ZONE_SAMPLES, seed: int = ZONE_SEED) -> Zone:
    """The patched circuit's zone of control on the bench.

    Parameters
    ----------
    net : Netlist
        The patch.
    plant : RotaryParams
        The nonlinear plant.
    bench, machine : BenchProfile, MachineProfile
        What the patch meets (its voltage limit is the bench amplifier's).
    K : numpy.ndarray
        The design's gain on alpha, theta, alpha_dot, theta_dot (for the zone's quadratic form).
    n_samples, seed : int
        How many starts at most (each ZONE_RUNS seeds for RECOVERY_S on the bench), and their seed.

    Returns
    -------
    Zone
        The zone the pump must bring the state into.
    """

    def recovers(x: np.ndarray) -> bool:
        r = simulate(net, plant, bench, machine, start_scenario(x, RECOVERY_S, seed, "zone-probe"), runs=ZONE_RUNS,
                     keep_history=False)
        return all(run.held and abs(math.degrees(float(wrap(run.final_state[1])))) < HOME_DEG for run in r.runs)

    P = rotary_cost(plant, K, bench.actuator.V_limit)
    return estimate_zone(recovers, P, rotary_spread(plant), n_samples=n_samples, seed=seed,
                         source="patched controller on the bench")
