"""The rotary pendulum's whole manoeuvre: pump it up from hanging by energy control on the
nonlinear plant (patchgen.swingup.rotary_energy), hand the state to the *patched* controller when
it enters that controller's zone of control (patchgen.swingup.rotary_zone), and hold with the
patched circuit on the bench (its actuator limit, encoder counts, noise, random forces and drift),
its integrators released from zero at the hand-off as the cart's manoeuvre does
(patchgen.swingup.manoeuvre). The pump keeps going while the state is outside the zone."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from patchgen.bench.simulate import SimResult, simulate
from patchgen.patch.netlist import Netlist
from patchgen.plant.rotary_equations import RotaryParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.profiles.measured_plant import as_on_bench
from patchgen.swingup.handoff import Zone
from patchgen.swingup.rotary_energy import SWITCHING, SwingUpRun, simulate_swingup, wrap
from patchgen.swingup.rotary_zone import patched_rotary_zone, start_scenario

PUMP_S = 30.0  # s: the longest the pump may take to reach the catch zone from hanging


@dataclass(frozen=True)
class RotaryManoeuvre:
    """The pump-up (to the hand-off, or its whole PUMP_S when it never got there), the patch's zone
    of control it handed off in, and the patched hold after it (None without a hand-off)."""

    pump: SwingUpRun
    hold: SimResult | None
    hold_s: float
    v_limit: float
    zone: Zone

    @property
    def reached(self) -> bool:
        """Whether the pump brought the pendulum into the catch zone."""
        return self.pump.handoff_time is not None

    @property
    def held(self) -> bool:
        """Whether the patched controller held the pendulum for the whole hold after the hand-off."""
        return self.hold is not None and self.hold.runs[0].held

    @property
    def closest_deg(self) -> float:
        """How near upright the pump brought the pendulum (deg; 0 is upright)."""
        return float(np.degrees(np.min(np.abs(wrap(self.pump.x[:, 1])))))

    def summary(self) -> dict:
        """The manoeuvre's figures as plain data (manoeuvre.json)."""
        out = {"strategy": "energy", "voltage_limit_V": self.v_limit, "reached_zone": self.reached,
               "handoff_time_s": self.pump.handoff_time, "closest_to_upright_deg": self.closest_deg,
               "max_abs_alpha_pump_rad": self.pump.max_abs_alpha, "hold_s": self.hold_s, "held": self.held,
               "switching_table": [{"condition": r.condition, "law": r.law} for r in SWITCHING],
               "zone": {"source": self.zone.source, "level_r": self.zone.r, "starts_tried": self.zone.samples,
                        "failed_start": bool(self.zone.failures),
                        "box_half_widths": list(self.zone.half_widths or ()),
                        "P": np.asarray(self.zone.P).tolist()}}
        if self.reached:
            x = self.pump.x[-1]
            out["handoff_state"] = {"alpha_rad": float(x[0]), "theta_deg": float(np.degrees(wrap(x[1]))),
                                    "alpha_dot_rad_s": float(x[2]), "theta_dot_rad_s": float(x[3])}
        if self.hold is not None:
            first = self.hold.summary()["first_run"]
            out["hold"] = {k: v for k, v in first.items() if k != "final_state"}
        return out


def rotary_manoeuvre(net: Netlist, plant: RotaryParams, bench: BenchProfile, machine: MachineProfile,
                     gain: np.ndarray, hold_s: float, seed: int = 0) -> RotaryManoeuvre:
    """Estimate the patch's zone of control, pump up from hanging (at the bench amplifier's voltage
    limit) until the state is inside it, then hold with the patch.

    Parameters
    ----------
    net : Netlist
        The patch.
    plant : RotaryParams
        The plant (the spec's: the pump and the hold run on it with the bench's measured figures,
        patchgen.profiles.measured_plant).
    bench, machine : BenchProfile, MachineProfile
        What the patch meets; the pump drives the motor up to the bench's V_limit.
    gain : numpy.ndarray
        The design's state feedback K (V_m = -K x), the patch's: the zone's quadratic form.
    hold_s : float
        The patched hold after the hand-off (s).
    seed : int
        The hold's noise seed (the zone's starts have their own, ZONE_SEED: the same hand-off for
        every hold).

    Returns
    -------
    RotaryManoeuvre
    """
    v_limit = bench.actuator.V_limit
    plant = as_on_bench(plant, bench)
    K = np.asarray(gain, dtype=float).ravel()
    zone = patched_rotary_zone(net, plant, bench, machine, K)
    pump = simulate_swingup(plant, v_limit, t_end=PUMP_S, K=K, stop_at_handoff=True, zone=zone)
    if pump.handoff_time is None:
        return RotaryManoeuvre(pump, None, hold_s, v_limit, zone)
    x = pump.x[-1]
    if math.isfinite(plant.alpha_limit) and abs(x[0]) >= plant.alpha_limit:
        return RotaryManoeuvre(pump, None, hold_s, v_limit, zone)
    hold = simulate(net, plant, bench, machine, start_scenario(x, hold_s, seed))
    return RotaryManoeuvre(pump, hold, hold_s, v_limit, zone)
