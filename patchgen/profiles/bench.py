"""Bench profiles: the real actuator, sensors and track that a patch meets (not the design's model)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from patchgen.inputs.fields import InputModel, Real, bounded, zero_or_at_least
from patchgen.inputs.validation import load_profile


class BenchActuator(InputModel):
    """Command voltage to force: K_U, lag (optional zero at the origin), dead zone, force limit."""

    model: Literal["gain", "lag", "lag_zero"]
    K_U: Real = bounded(0.01, 1000, description="N/V")
    tau: Annotated[Real, zero_or_at_least(1e-3)] = bounded(0, 10, default=0.0, description="s")
    dead_zone_V: Real = bounded(0, 100, default=0.0)
    force_limit_N: Real = bounded(0, 1e4, open_lo=True)


class BenchSensors(InputModel):
    """Sensor constants (V per SI unit) and their noise."""

    s: Real = bounded(1e-3, 1e3)
    theta: Real = bounded(1e-3, 1e3)
    s_dot: Real = bounded(1e-3, 1e3)
    noise_V_rms: dict[Literal["s", "theta", "s_dot"], Annotated[Real, Field(ge=0, le=100)]] = Field(
        default_factory=dict)
    noise_bandwidth_Hz: Real = bounded(1e-3, 1e9, default=200.0)


class BenchTrack(InputModel):
    """The track: whether limit switches cut the power at its ends."""

    limit_switches: bool = True


class BenchProfile(InputModel):
    """A whole bench: read from patchgen/profiles/benches/<id>.toml or a user path."""

    id: str = Field(min_length=1)
    name: str
    actuator: BenchActuator
    sensors: BenchSensors
    track: BenchTrack = BenchTrack()


def load_bench(name_or_path: str, source: str = "", field: str = "bench") -> BenchProfile:
    """Load a shipped bench profile by id (e.g. 'uw-1991') or a file by path.

    Parameters
    ----------
    name_or_path : str
        A shipped profile's id, or the path of a profile file.
    source, field : str
        The file and field that named the profile (a spec and its ``bench``): an unreadable
        profile is reported against them.

    Returns
    -------
    BenchProfile
        The checked profile; a bad value raises InputError naming the profile file and field.
    """
    return load_profile(BenchProfile, name_or_path, "bench", source, field)
