"""Each run's bench drawn from the profile's ranges (``patchgen simulate --bench-spread``): which
ranges a simulation draws, where each lands in the engine's per-run arrays, and the draw itself.

A range the simulation cannot feel is not drawn: ``ideal`` has no lag, dead zone, force limit or
noise, and a scenario whose noise is "off" or explicit sets the noise levels and random forces
itself. A run draws after everything else it draws (patchgen.bench.engine.draw_batch), so a run
without a bench spread draws the same bytes as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr, ndtri

from patchgen.bench.lanes import A_DEAD_ZONE, A_FORCE_LIMIT, A_K_U, A_TAU
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.uncertainty import NORMAL_SIGMAS

ACTUATOR_KEYS = {"K_U": A_K_U, "tau": A_TAU, "dead_zone_V": A_DEAD_ZONE, "force_limit_N": A_FORCE_LIMIT}
NOISE_KEYS = ("cart_force_N_rms", "tip_force_N_rms", "noise_V_rms.s", "noise_V_rms.theta", "noise_V_rms.s_dot")


@dataclass(frozen=True)
class BenchSpread:
    """The ranges a simulation draws each run's bench from, and where each value goes.

    ``target`` per key: ("actuator", column of ACTUATOR_VECTOR), ("gain", sensor indices) or
    ("noise", channel indices, std per unit value: the channel's innovation std is value x this).
    """

    keys: tuple[str, ...]
    low: np.ndarray
    high: np.ndarray
    distribution: str
    target: tuple[tuple, ...]

    @property
    def ranges(self) -> dict[str, tuple[float, float]]:
        """Key -> (low, high), as drawn."""
        return {k: (float(lo), float(hi)) for k, lo, hi in zip(self.keys, self.low, self.high)}


def active_ranges(bench: BenchProfile, ideal: bool, noise_from_profile: bool) -> dict[str, tuple[float, float]]:
    """The profile's ranges that a simulation feels (see the module docstring).

    Parameters
    ----------
    bench : BenchProfile
        Its ``[uncertainty]`` ranges.
    ideal : bool
        Every imperfection off: only K_U and the sensor constants remain.
    noise_from_profile : bool
        The scenario takes its noise levels and random forces from the profiles.

    Returns
    -------
    dict of str to (float, float)
        In the profile's order.
    """
    out = {}
    for key, (lo, hi) in bench.uncertainty.ranges.items():
        if ideal and key not in ("K_U", "sensors.s", "sensors.theta", "sensors.s_dot"):
            continue
        if key in NOISE_KEYS and not noise_from_profile:
            continue
        if key == "tau" and bench.actuator.model == "gain":
            continue
        out[key] = (float(lo), float(hi))
    return out


def plan(ranges: dict[str, tuple[float, float]], distribution: str, sensor_quantities: tuple[str, ...],
         sensor_ids: tuple[str, ...], unit_std: dict[str, tuple[tuple[int, ...], float]]) -> BenchSpread | None:
    """Where each range lands in a run's arrays (None: nothing to draw).

    Parameters
    ----------
    ranges : dict of str to (float, float)
        The ranges drawn (active_ranges).
    distribution : str
        "uniform" or "normal".
    sensor_quantities : tuple of str
        The plant quantity each of the circuit's sensors reads.
    sensor_ids : tuple of str
        The circuit's sensor ids (their noise channels are their indices).
    unit_std : dict of str to (tuple of int, float)
        Per noise key: its channels and their innovation std per unit of the key's value.
    """
    if not ranges:
        return None
    target = []
    for key in ranges:
        if key in ACTUATOR_KEYS:
            target.append(("actuator", ACTUATOR_KEYS[key]))
        elif key.startswith("sensors."):
            q = key.split(".", 1)[1]
            target.append(("gain", tuple(i for i, s in enumerate(sensor_quantities) if s == q)))
        else:
            chans, per = unit_std[key]
            target.append(("noise", chans, per))
    return BenchSpread(tuple(ranges), np.array([r[0] for r in ranges.values()]),
                       np.array([r[1] for r in ranges.values()]), distribution, tuple(target))


def draw(spread: BenchSpread, rng: np.random.Generator) -> np.ndarray:
    """One run's values, one per key: uniform in its range, or a normal with the range as
    +/- NORMAL_SIGMAS sigma, truncated to it (by its quantile, one uniform draw per key)."""
    u = rng.random(len(spread.keys))
    if spread.distribution == "normal":
        lo = ndtr(-NORMAL_SIGMAS)
        u = 0.5 + ndtri(lo + u * (1.0 - 2.0 * lo)) / (2.0 * NORMAL_SIGMAS)
    return spread.low + (spread.high - spread.low) * u


def apply(spread: BenchSpread, values: np.ndarray, actuator: np.ndarray, gains: np.ndarray,
          noise_std: np.ndarray) -> None:
    """Write one run's drawn values into its rows of the engine's arrays (in place)."""
    apply_values(spread, dict(zip(spread.keys, values)), actuator, gains, noise_std)


def apply_values(spread: BenchSpread, values: dict[str, float], actuator: np.ndarray, gains: np.ndarray,
                 noise_std: np.ndarray) -> None:
    """Write some keys' values (key -> value, each one of ``spread.keys``) into one run's rows of
    the engine's arrays (in place), as :func:`apply` writes a draw; the keys not given keep theirs."""
    for key, v in values.items():
        tgt = spread.target[spread.keys.index(key)]
        if tgt[0] == "actuator":
            actuator[tgt[1]] = v
        elif tgt[0] == "gain":
            gains[list(tgt[1])] = v
        else:
            noise_std[list(tgt[1])] = v * tgt[2]


def drawn_values(spread: BenchSpread, actuator: np.ndarray, gains: np.ndarray, noise_std: np.ndarray) -> np.ndarray:
    """One run's drawn values read back from its rows of the engine's arrays (apply's inverse), one
    per key: what runs.csv reports, taken from what the engine was given."""
    out = np.empty(len(spread.keys))
    for i, tgt in enumerate(spread.target):
        if tgt[0] == "actuator":
            out[i] = actuator[tgt[1]]
        elif tgt[0] == "gain":
            out[i] = gains[tgt[1][0]] if tgt[1] else np.nan
        else:
            out[i] = noise_std[tgt[1][0]] / tgt[2] if tgt[1] and tgt[2] else np.nan
    return out
