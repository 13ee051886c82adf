"""Pump-up from hanging to upright (thesis chapter 3) and hand-off to the linear controller (3.5).

Three strategies on the nonlinear plant (eq. 2.16-2.19), with bang-bang force of a given limit:

- ``supervisory``: the three-phase series of section 3.3/3.4 run as closed-loop logic: at each
  bottom crossing push (phase 1), reverse when the push stops pumping energy (theta_dot = 0, or the
  pendulum crossing the horizontal: the refinement 3.3 suggests), coast when s_dot = 0 (phase 3);
  the next series pushes the other way. Two guards use a short prediction on the internal model:
  end the push early when braking later would overrun the track, or when the pendulum would get
  more than the upright energy.
- ``schedule``: an open-loop table of switching times (see schedule.py), replayed.
- ``energy``: Astrom-Furuta energy control u = sat(k (E - E0) sign(theta_dot cos theta) - k_s s -
  k_v s_dot).

Every run stops pumping when the state enters the hand-off zone (handoff.Zone), then holds with
the linear controller. Pendulum energy is taken in the cart frame: E = m l^2 theta_dot^2 / 2 +
m g l cos(theta), so E0 = m g l upright at rest and -m g l hanging at rest.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

from patchgen.plant.equations import PlantParams
from patchgen.plant.step import rk4_step

Strategy = Literal["supervisory", "schedule", "energy"]
STRATEGIES: tuple[str, ...] = ("supervisory", "schedule", "energy")

PUSH, BRAKE, COAST = 1, 2, 3
PHASE_NAMES = {PUSH: "push", BRAKE: "reverse", COAST: "coast"}

# The energy law's gains (Astrom-Furuta form; the thesis pumps bang-bang only), chosen on the
# uw-1991 plant (Table B.1): k saturates the force for an energy error of a few percent of
# m g l, and the cart terms pull it back to the track's centre without stalling the pumping.
ENERGY_GAIN_N_PER_J = 300.0
CART_POSITION_GAIN_N_PER_M = 5.0
CART_VELOCITY_GAIN_NS_PER_M = 3.0
TRACK_MARGIN = 0.9  # the guard brakes when the stopping point would pass this fraction of d/2


def pendulum_energy(plant: PlantParams, x: np.ndarray) -> np.ndarray | float:
    """Pendulum energy in the cart frame (J): kinetic about the pivot, I = m l L (J + m l^2, L the
    swing length), plus potential (0 = level)."""
    return 0.5 * plant.m * (plant.l * plant.swing_length()) * x[3] ** 2 + plant.m * plant.g * plant.l * np.cos(x[1])


def upright_energy(plant: PlantParams) -> float:
    """E0 = m g l: the energy of the pendulum at rest upright."""
    return plant.m * plant.g * plant.l


def hanging_state() -> np.ndarray:
    """Hanging at rest, cart centred: theta = pi."""
    return np.array([0.0, np.pi, 0.0, 0.0])


@dataclass(frozen=True)
class Switch:
    """One row of the switching table: from ``time_s`` on, ``force_N`` (phase of a series)."""

    series: int
    phase: int
    force_N: float
    time_s: float
    reason: str = ""

    @property
    def phase_name(self) -> str:
        """The phase in words: push, reverse, coast (or hand-off)."""
        return PHASE_NAMES.get(self.phase, "hand-off")


class PumpController(Protocol):
    """A pump-up law: force for the sampled state; it records its own switching table."""

    switches: list[Switch]

    def force(self, t: float, x: np.ndarray) -> float:
        """The force (N) at time ``t`` (s) for the state ``x`` (s, theta, s_dot, theta_dot)."""
        ...


class _Pumping:
    """What every closed-loop pump-up law keeps: its model of the plant, the force limit, its
    settings, the upright energy it pumps towards and the switches it made."""

    def __init__(self, model: PlantParams, force_limit: float, settings):
        self.model = model
        self.F = float(force_limit)
        self.cfg = settings
        self.E0 = upright_energy(model)
        self.switches: list[Switch] = []


# --------------------------------------------------------------------------- supervisory


@dataclass
class SupervisorSettings:
    """Tuning of the supervisory logic. Margins are fractions; periods in seconds."""

    track_margin: float = 0.8          # keep predicted |s| below this fraction of d/2
    energy_target: float = 1.0         # stop pumping when the predicted energy reaches this x E0
    guard_period_s: float = 5e-3       # how often the guards predict ahead
    predict_step_s: float = 5e-3       # step of the internal prediction
    predict_horizon_s: float = 1.5     # longest braking prediction
    reverse_at_horizontal: bool = True  # end the push when the pendulum crosses the horizontal


class Supervisor(_Pumping):
    """Three-phase bang-bang pump-up (section 3.3) as closed-loop logic (section 3.4).

    ``model`` is the plant the guards predict with (the design's model); the plant actually
    simulated may differ from it (sensitivity runs).
    """

    def __init__(self, model: PlantParams, force_limit: float, settings: SupervisorSettings | None = None):
        super().__init__(model, force_limit, settings or SupervisorSettings())
        self.phase = 0
        self.direction = 1.0
        self.series = 0
        self.sign_goal = 1.0       # +1 pumping energy in, -1 taking it out
        self.prev: np.ndarray | None = None
        self.next_guard_t = 0.0

    # -- predictions on the internal model
    def _predict(self, x: np.ndarray, push_s: float) -> tuple[float, float]:
        """Keep pushing for push_s, then reverse until the cart stops: (max |s|, energy at stop)."""
        h = self.cfg.predict_step_s
        y = np.array(x, dtype=float)
        s_max = abs(y[0])
        push_force = self.direction * self.F
        n_push = int(round(push_s / h))
        for _ in range(n_push):
            y = rk4_step(self.model, y, push_force, h)
            s_max = max(s_max, abs(y[0]))
        for _ in range(int(self.cfg.predict_horizon_s / h)):
            if y[2] * self.direction <= 0.0:
                break
            y = rk4_step(self.model, y, -push_force, h)
            s_max = max(s_max, abs(y[0]))
        return s_max, float(pendulum_energy(self.model, y))

    def _start_series(self, t: float, x: np.ndarray, first: bool = False) -> None:
        E = float(pendulum_energy(self.model, x))
        self.sign_goal = 1.0 if E < self.cfg.energy_target * self.E0 else -1.0
        if first or x[3] == 0.0:
            self.direction = 1.0
        else:
            self.direction = float(np.sign(x[3])) * self.sign_goal
        self.series += 1
        self._set(t, PUSH, self.direction * self.F, "bottom crossing" if not first else "start")
        self.next_guard_t = t

    def _set(self, t: float, phase: int, force: float, reason: str) -> None:
        self.phase = phase
        self.switches.append(Switch(self.series, phase, float(force), round(float(t), 6), reason))

    def force(self, t: float, x: np.ndarray) -> float:
        """Full force one way or the other, or none, as the phase and its switching rules say."""
        prev = self.prev if self.prev is not None else x
        self.prev = np.array(x, dtype=float)
        if self.phase == 0:
            at_rest_below = np.cos(x[1]) < 0.0 and abs(x[3]) < 1e-9
            if at_rest_below:
                self._start_series(t, x, first=True)
            else:
                self._set(t, COAST, 0.0, "wait for bottom crossing")
        d = self.direction
        if self.phase == PUSH:
            reason = ""
            if x[3] * d * self.sign_goal < 0.0 and t > self.switches[-1].time_s:
                reason = "theta_dot = 0"
            elif self.cfg.reverse_at_horizontal and np.cos(prev[1]) < 0.0 <= np.cos(x[1]):
                reason = "horizontal"
            elif t >= self.next_guard_t - 1e-12:
                self.next_guard_t = t + self.cfg.guard_period_s
                s_max, E_end = self._predict(x, self.cfg.guard_period_s)
                if s_max > self.cfg.track_margin * self.model.d / 2.0:
                    reason = "track guard"
                elif self.sign_goal * (E_end - self.cfg.energy_target * self.E0) >= 0.0:
                    reason = "energy guard"
            if reason:
                self._set(t, BRAKE, -d * self.F, reason)
        elif self.phase == BRAKE:
            if x[2] * d <= 0.0:
                self._set(t, COAST, 0.0, "s_dot = 0")
        elif self.phase == COAST:
            crossed = np.cos(x[1]) < 0.0 and np.sin(prev[1]) * np.sin(x[1]) <= 0.0 and t > 0.0
            if crossed and not np.array_equal(prev, x):
                self._start_series(t, x)
        d = self.direction
        return {PUSH: d * self.F, BRAKE: -d * self.F, COAST: 0.0}[self.phase]


# --------------------------------------------------------------------------- energy control


@dataclass
class EnergySettings:
    """Gains of the energy law: k in N/J, the cart terms k_s in N/m and k_v in N s/m; the guard
    brakes at full force when the cart's stopping point would pass track_margin x d/2."""

    k: float = ENERGY_GAIN_N_PER_J
    k_s: float = CART_POSITION_GAIN_N_PER_M
    k_v: float = CART_VELOCITY_GAIN_NS_PER_M
    track_margin: float = TRACK_MARGIN


class EnergyControl(_Pumping):
    """Astrom-Furuta: u = sat(k (E - E0) sign(theta_dot cos theta) - k_s s - k_v s_dot), with a
    guard that brakes the cart when its stopping point (full reverse force) nears a limit switch."""

    def __init__(self, model: PlantParams, force_limit: float, settings: EnergySettings | None = None):
        super().__init__(model, force_limit, settings or EnergySettings())

    def stopping_point(self, x: np.ndarray) -> float:
        """Where the cart would stop under full reverse force (cart alone, with its friction)."""
        v = abs(x[2])
        b, mass = self.model.b_VF, self.model.M + self.model.m
        dist = (mass / b) * (v - (self.F / b) * np.log1p(b * v / self.F))
        return float(x[0] + np.sign(x[2]) * dist)

    def force(self, t: float, x: np.ndarray) -> float:
        """The energy law's force, saturated, or full reverse force when the track guard acts."""
        E = float(pendulum_energy(self.model, x))
        sgn = np.sign(x[3] * np.cos(x[1]))
        if sgn == 0.0:
            sgn = -1.0  # at rest below: push in the positive direction first, as section 3.3 does
        u = self.cfg.k * (E - self.E0) * sgn - self.cfg.k_s * x[0] - self.cfg.k_v * x[2]
        reason = "energy"
        if abs(self.stopping_point(x)) > self.cfg.track_margin * self.model.d / 2.0 and x[0] * x[2] > 0:
            u = -np.sign(x[2]) * self.F
            reason = "track guard"
        u = float(np.clip(u, -self.F, self.F))
        level = float(np.sign(round(u / self.F, 2)))
        if not self.switches or np.sign(self.switches[-1].force_N) != level:
            self.switches.append(Switch(len(self.switches) + 1, 0, level * self.F, round(t, 6), reason))
        return u


# --------------------------------------------------------------------------- open-loop schedule


@dataclass(frozen=True)
class Schedule:
    """A bang-bang schedule: forces held from each switching time (the last one held on)."""

    switches: tuple[Switch, ...]

    @property
    def times(self) -> np.ndarray:
        """Switching times (s)."""
        return np.array([s.time_s for s in self.switches])

    @property
    def forces(self) -> np.ndarray:
        """Force from each switching time on (N)."""
        return np.array([s.force_N for s in self.switches])

    def force_over(self, t0: float, h: float) -> float:
        """Mean force over [t0, t0+h]: exact switching times within a fixed step.

        Parameters
        ----------
        t0, h : float
            Start and length of the step (s).

        Returns
        -------
        float
            The mean force (N).
        """
        times, forces = self.times, self.forces
        ends = np.append(times[1:], np.inf)
        overlap = np.clip(np.minimum(ends, t0 + h) - np.maximum(times, t0), 0.0, None)
        return float(forces @ overlap / h)


class ScheduleReplay:
    """Plays a schedule open-loop (no feedback at all)."""

    def __init__(self, schedule: Schedule, h: float):
        """h: the step of the simulation the schedule is played into."""
        self.schedule = schedule
        self.h = h
        self.switches = list(schedule.switches)

    def force(self, t: float, x: np.ndarray) -> float:
        """The schedule's mean force over the step from ``t``; the state is not looked at."""
        return self.schedule.force_over(t, self.h)
