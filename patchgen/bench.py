"""Bench profiles: the real actuator, sensors and track that a patch meets (not the design's model)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from .validation import load_profile


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class BenchActuator(_Strict):
    """Command voltage to force: K_U, lag (optional zero at the origin), dead zone, force limit."""

    model: Literal["gain", "lag", "lag_zero"]
    K_U: float = Field(gt=0, description="N/V")
    tau: float = Field(default=0.0, ge=0, description="s")
    dead_zone_V: float = Field(default=0.0, ge=0)
    force_limit_N: float = Field(gt=0)


class BenchSensors(_Strict):
    """Sensor constants (V per SI unit) and their noise."""

    s: float = Field(gt=0)
    theta: float = Field(gt=0)
    s_dot: float = Field(gt=0)
    noise_V_rms: dict[Literal["s", "theta", "s_dot"], float] = Field(default_factory=dict)
    noise_bandwidth_Hz: float = Field(default=200.0, gt=0)


class BenchTrack(_Strict):
    limit_switches: bool = True


class BenchProfile(_Strict):
    id: str
    name: str
    actuator: BenchActuator
    sensors: BenchSensors
    track: BenchTrack = BenchTrack()


def load_bench(name_or_path: str, source: str = "", field: str = "bench") -> BenchProfile:
    """Load a shipped bench profile by id (e.g. 'uw-1991') or a file by path."""
    return load_profile(BenchProfile, name_or_path, "bench", source, field)
