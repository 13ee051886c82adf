"""One pump-up run on the nonlinear plant: pump until the hand-off zone, hold with the linear
controller, and the run's histories and switching table.

The run's length and step are choices named here, shared by every strategy and the schedule
replay: PUMP_T_MAX_S, HOLD_S and STEP_S.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from patchgen.plant.equations import PlantParams
from patchgen.plant.step import rk4_step
from patchgen.swingup.handoff import Zone, wrapped
from patchgen.swingup.strategies import PumpController, Switch, hanging_state, pendulum_energy, upright_energy

# The run's length and step, one set for every strategy, the schedule replay and the comparison:
PUMP_T_MAX_S = 12.0  # longest pump-up before a run counts as not reaching the zone: over twice the
#                      thesis's 5.2 s pump-up with 15 N (Table 3.1), room for a weaker force limit
HOLD_S = 5.0  # hold after hand-off: ten times the 0.5 s window the thesis found for it (3.5), long
#               enough to tell a catch from a miss
STEP_S = 1e-3  # RK4 step: a thousandth of the pendulum's period (about 1.3 s, Table B.1), so the
#                bang-bang switching times fall within 1 ms, finer than Table 3.1's 0.01 s
UPRIGHT_RAD = 0.05  # "held" at the end: within about 3 degrees of upright


def saturated_state_feedback(K: np.ndarray, force_limit: float) -> Callable[[float, np.ndarray], float]:
    """u = sat(-K x) on the plant states, angle wrapped about upright."""
    k = np.asarray(K, dtype=float).ravel()[:4]

    def law(t: float, x: np.ndarray) -> float:
        return float(np.clip(-(k @ wrapped(x)), -force_limit, force_limit))

    return law


@dataclass
class SwingUpResult:
    """A simulated manoeuvre: histories, the switching table, and when the hand-off happened."""

    strategy: str
    plant: PlantParams
    force_limit: float
    zone: Zone
    t: np.ndarray
    x: np.ndarray            # (N, 4)
    u: np.ndarray            # (N,)
    holding: np.ndarray      # (N,) bool: the linear controller is in charge
    switches: list[Switch]
    handoff_time: float | None
    dt: float
    notes: dict = field(default_factory=dict)

    @property
    def reached(self) -> bool:
        """Whether the state entered the hand-off zone."""
        return self.handoff_time is not None

    @property
    def pump(self) -> np.ndarray:
        """Per sample: the pump-up law is in charge (before the hand-off)."""
        return ~self.holding

    @property
    def max_abs_s_pump(self) -> float:
        """Largest cart excursion before the hand-off (m)."""
        return float(np.max(np.abs(self.x[self.pump, 0])))

    @property
    def max_abs_s(self) -> float:
        """Largest cart excursion over the whole run (m)."""
        return float(np.max(np.abs(self.x[:, 0])))

    @property
    def on_track(self) -> bool:
        """Whether the cart stayed inside the limit switches (+/- d/2) throughout."""
        return self.max_abs_s < self.plant.d / 2.0

    @property
    def handoff_state(self) -> np.ndarray | None:
        """The state when the linear controller took over (None if the zone was never reached)."""
        if self.handoff_time is None:
            return None
        return self.x[int(np.argmax(self.holding))]

    @property
    def energy_ratio_at_handoff(self) -> float | None:
        """E / E0 when the linear controller takes over."""
        xh = self.handoff_state
        return None if xh is None else float(pendulum_energy(self.plant, xh) / upright_energy(self.plant))

    @property
    def held(self) -> bool:
        """Balanced at the end: upright within UPRIGHT_RAD and on the track throughout."""
        end = wrapped(self.x[-1])
        return self.reached and self.on_track and abs(end[1]) < UPRIGHT_RAD and abs(end[0]) < self.plant.d / 2.0

    def table_rows(self) -> list[dict]:
        """The switching table as rows (series, phase, force, time), ending with the hand-off."""
        rows = [
            {"series": s.series, "phase": s.phase, "phase_name": s.phase_name, "force_N": s.force_N,
             "time_s": s.time_s, "reason": s.reason}
            for s in self.switches
            if self.handoff_time is None or s.time_s <= self.handoff_time
        ]
        if self.handoff_time is not None:
            rows.append({"series": None, "phase": None, "phase_name": "hand-off", "force_N": None,
                         "time_s": round(self.handoff_time, 6), "reason": "state entered the zone"})
        return rows


def simulate(
    plant: PlantParams,
    controller: PumpController,
    zone: Zone,
    *,
    strategy: str,
    force_limit: float,
    hold: Callable[[float, np.ndarray], float] | None = None,
    x0: np.ndarray | None = None,
    t_max: float = PUMP_T_MAX_S,
    hold_s: float = HOLD_S,
    dt: float = STEP_S,
    stop_off_track: bool = True,
) -> SwingUpResult:
    """Pump with ``controller`` until the state enters ``zone`` (or t_max), then ``hold`` for hold_s.

    Parameters
    ----------
    plant : PlantParams
        The nonlinear plant simulated (RK4).
    controller : PumpController
        The pump-up law; it records its switching table.
    zone : Zone
        The hand-off zone.
    strategy : str
        The strategy's name, kept with the result.
    force_limit : float
        Largest force (N).
    hold : callable, optional
        The law after hand-off, u(t, x); without one the run ends at the hand-off.
    x0 : array_like, optional
        The start (default: hanging at rest, cart centred).
    t_max, hold_s, dt : float
        Longest pump-up, hold after hand-off and step (s): PUMP_T_MAX_S, HOLD_S, STEP_S.
    stop_off_track : bool
        End the run when the cart reaches a limit switch (the bench cuts power).

    Returns
    -------
    SwingUpResult
        Histories, switching table and hand-off time.
    """
    x = hanging_state() if x0 is None else np.array(x0, dtype=float)
    ts, xs, us, hs = [0.0], [x.copy()], [], []
    handoff: float | None = None
    t_end = t_max
    k = 0
    while True:
        t = k * dt
        if handoff is None and zone.contains(x):
            handoff = t
            t_end = t + hold_s
            if hold is None:
                us.append(0.0)
                hs.append(True)
                break
        if t >= t_end - 1e-12:
            us.append(us[-1] if us else 0.0)
            hs.append(handoff is not None)
            break
        holding = handoff is not None
        u = hold(t, x) if holding else controller.force(t, x)
        us.append(u)
        hs.append(holding)
        x = rk4_step(plant, x, u, dt)
        k += 1
        ts.append(k * dt)
        xs.append(x.copy())
        if stop_off_track and abs(x[0]) >= plant.d / 2.0:
            us.append(0.0)
            hs.append(holding)
            break
    return SwingUpResult(
        strategy=strategy, plant=plant, force_limit=force_limit, zone=zone,
        t=np.array(ts), x=np.array(xs), u=np.array(us), holding=np.array(hs, dtype=bool),
        switches=list(controller.switches), handoff_time=handoff, dt=dt,
    )
