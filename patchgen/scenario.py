"""Simulation scenarios: initial state, disturbances, duration, noise and drift, seed (TOML files).

Noise and drift are ``"profile"`` (as the bench and machine profiles say), ``"off"``, or explicit:
noise as a table of V rms levels (``s``, ``theta``, ``s_dot`` sensors, ``amplifier`` output noise;
a level left out is zero), drift as one rate in V/s for every integrating amplifier.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from .resources import resolve
from .validation import read_toml, validate


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class InitialState(_Strict):
    """Plant state at t = 0 (SI units; the angle in rad or in degrees, not both)."""

    s: float = 0.0
    theta: float | None = None
    theta_deg: float | None = None
    s_dot: float = 0.0
    theta_dot: float = 0.0

    @model_validator(mode="after")
    def _one_angle(self) -> InitialState:
        if self.theta is not None and self.theta_deg is not None:
            raise ValueError("give theta (rad) or theta_deg, not both")
        return self

    def vector(self) -> tuple[float, float, float, float]:
        """[s, theta, s_dot, theta_dot] in SI units."""
        th = self.theta if self.theta is not None else math.radians(self.theta_deg or 0.0)
        return (self.s, th, self.s_dot, self.theta_dot)


_NEEDS = {"force_impulse": ("at", "duration_s", "force_N"), "step": ("size_m",)}


class Disturbance(_Strict):
    """A push or a command during the run.

    ``force_impulse``: a horizontal force ``force_N`` on the pendulum tip or on the cart from
    ``time_s`` for ``duration_s``. ``step``: the cart position command steps by ``size_m`` at
    ``time_s`` (an offset on the s sensor's reference, so the loop moves the cart there).
    """

    kind: Literal["force_impulse", "step"]
    time_s: float = Field(ge=0)
    at: Literal["pendulum_tip", "cart"] | None = None
    duration_s: float | None = Field(default=None, gt=0)
    force_N: float | None = None
    size_m: float | None = None

    @model_validator(mode="after")
    def _fields_for_kind(self) -> Disturbance:
        for name in _NEEDS[self.kind]:
            if getattr(self, name) is None:
                raise ValueError(f"{name} is needed for kind {self.kind!r}")
        for name in {n for names in _NEEDS.values() for n in names} - set(_NEEDS[self.kind]):
            if getattr(self, name) is not None:
                raise ValueError(f"{name} does not apply to kind {self.kind!r}")
        return self


class NoiseLevels(_Strict):
    """Noise: as the profiles say, off, or explicit levels in V rms (sensors and every
    amplifier's output; the levels count only in mode 'explicit')."""

    mode: Literal["profile", "off", "explicit"] = "explicit"
    s: float | None = Field(default=None, ge=0)
    theta: float | None = Field(default=None, ge=0)
    s_dot: float | None = Field(default=None, ge=0)
    amplifier: float | None = Field(default=None, ge=0)

    def level(self, name: str) -> float:
        """An explicit level in V rms (one left out is zero)."""
        return getattr(self, name, None) or 0.0


class Scenario(_Strict):
    """One simulation case. ``dt_s`` overrides the engine's step; ``record_dt_s`` is the history
    sample interval; ``fall_angle_deg`` is where the pendulum counts as fallen."""

    name: str = ""
    description: str = ""
    duration_s: float = Field(gt=0)
    dt_s: float | None = Field(default=None, gt=0)
    record_dt_s: float = Field(default=0.01, gt=0)
    seed: int = Field(default=0, ge=0, lt=2**63)
    fall_angle_deg: float = Field(default=30.0, gt=0, le=180)
    initial: InitialState = InitialState()
    disturbances: list[Disturbance] = Field(default_factory=list)
    noise: NoiseLevels = NoiseLevels(mode="profile")
    drift: Literal["profile", "off"] | float = "profile"

    @field_validator("noise", mode="before")
    @classmethod
    def _noise_word(cls, v):
        if isinstance(v, str) and v in ("profile", "off"):
            return {"mode": v}
        if not isinstance(v, (dict, NoiseLevels)):
            raise ValueError("must be 'profile', 'off' or a table of V rms levels "
                             "(s, theta, s_dot, amplifier)")
        return v

    @field_validator("drift", mode="before")
    @classmethod
    def _drift_word(cls, v):
        if isinstance(v, str) and v not in ("profile", "off"):
            raise ValueError("must be 'profile', 'off' or a rate in V/s")
        if isinstance(v, bool) or (not isinstance(v, str) and not isinstance(v, (int, float))):
            raise ValueError("must be 'profile', 'off' or a rate in V/s")
        if isinstance(v, (int, float)) and v < 0:
            raise ValueError("a drift rate is a magnitude in V/s (>= 0); its sign is drawn per run")
        return v


def load_scenario(path: str | Path) -> Scenario:
    """Read and check a scenario TOML file, or a shipped scenario by name (``hold-120s``); its name
    defaults to the file's stem."""
    sc = validate(Scenario, read_toml(resolve("scenario", path)), str(path))
    return sc if sc.name else sc.model_copy(update={"name": Path(str(path)).stem})
