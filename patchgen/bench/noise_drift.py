"""The noise, random forces and drift of one run, resolved once from the scenario and the profiles.

patchgen's simulator and the SPICE deck both read a run's noise levels, the bench's random forces
on the plant and the integrator drift from here, so a scenario asks the same of both: the
profiles' levels, none, or its own explicit levels and drift rate. ``ideal`` turns all of them
off, as ``patchgen simulate --ideal`` does.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from patchgen.inputs.scenario import Scenario
from patchgen.plant.plant_model import ROTARY
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile


@dataclass(frozen=True)
class NoiseAndDrift:
    """Noise in V rms on each sensor (by id) and on every amplifier's output, with their
    bandwidths; random forces on the cart and at the pendulum's tip in N rms, with theirs; and
    the drift rate of every integrating amplifier (integrators and lags) in V/s."""

    sensor_V_rms: dict[str, float] = field(default_factory=dict)
    sensor_bandwidth_Hz: float = 0.0
    amplifier_V_rms: float = 0.0
    amplifier_bandwidth_Hz: float = 0.0
    drift_V_per_s: float = 0.0
    cart_force_N_rms: float = 0.0  # the random generalised force on the position: on a cart, N; on a
    # rotary pendulum's arm, a torque in N m
    tip_force_N_rms: float = 0.0
    force_bandwidth_Hz: float = 0.0

    def drift_at(self, k0_per_s: float | None, machine: MachineProfile) -> float:
        """The drift of one integrating amplifier, V/s: the run's rate, which is at the machine's
        time scale (its slowest integrator mode), times how much faster the amplifier's mode
        integrates (e_os/(R C) + i_b/C grows as 1/C); a lag (``k0_per_s`` None) at the run's rate."""
        if k0_per_s is None:
            return self.drift_V_per_s
        return self.drift_V_per_s * (k0_per_s * machine.time_scale_s)

    @property
    def noisy(self) -> bool:
        """True when any sensor or amplifier has noise, or the plant a random force."""
        return (self.amplifier_V_rms > 0 or any(v > 0 for v in self.sensor_V_rms.values())
                or self.cart_force_N_rms > 0 or self.tip_force_N_rms > 0)


def noise_and_drift(sensor_ids: Sequence[str], bench: BenchProfile, machine: MachineProfile,
                    scenario: Scenario, ideal: bool = False) -> NoiseAndDrift:
    """The noise levels and drift rate a scenario asks for on a bench and machine.

    Parameters
    ----------
    sensor_ids : sequence of str
        The netlist's sensors.
    bench, machine : BenchProfile, MachineProfile
        The sensors' noise and the random forces (bench) and the amplifiers' noise and drift
        (machine), for mode "profile"; the bandwidths always come from them.
    scenario : Scenario
        Its ``noise`` (profile, off or explicit levels, forces included) and ``drift``
        (profile, off or V/s).
    ideal : bool
        No noise, no random force and no drift, whatever the scenario says.

    Returns
    -------
    NoiseAndDrift
        Every sensor named, with 0.0 where it has no noise.
    """
    sens, imp, dist = bench.sensors, machine.imperfections, bench.disturbance
    if ideal or scenario.noise.mode == "off":
        sensor_rms, amp_rms, forces = {s: 0.0 for s in sensor_ids}, 0.0, (0.0, 0.0)
    elif scenario.noise.mode == "explicit":
        sensor_rms = {s: scenario.noise.level(s) for s in sensor_ids}
        amp_rms = scenario.noise.level("amplifier")
        on_position = "arm_torque_Nm" if bench.plant == ROTARY.name else "cart_force_N"
        forces = (scenario.noise.level(on_position), scenario.noise.level("tip_force_N"))
    else:
        sensor_rms = {s: float(sens.noise_V_rms.get(s, 0.0)) for s in sensor_ids}
        amp_rms = imp.amplifier_noise_V_rms
        forces = (dist.position_rms, dist.tip_force_N_rms)
    if ideal or scenario.drift == "off":
        drift = 0.0
    elif scenario.drift == "profile":
        drift = machine.integrator_drift_V_per_s()
    else:
        drift = float(scenario.drift)
    return NoiseAndDrift(sensor_rms, sens.noise_bandwidth_Hz, amp_rms, imp.noise_bandwidth_Hz, drift,
                         float(forces[0]), float(forces[1]), dist.bandwidth_Hz)
