"""What a bench profile says it does not know: a range for any of its parameters (the ``[uncertainty]``
table), and how a run draws its bench from them.

A range is ``key = [low, high]`` with the profile's own value inside it. The keys are the bench's
parameters by name, bare where the name is unique in the profile and section-qualified for the
sensors (``"sensors.theta"``: V/rad; ``"noise_V_rms.theta"``: V rms). The plant's parameters are
the spec's and are spread with ``patchgen simulate --spread``, not here.

``distribution`` is how a run draws inside a range: ``"uniform"`` (the default), or ``"normal"``
(the range is the mean +/- 2 sigma, the draw truncated to the range).
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import BaseModel, ConfigDict

# key -> where its nominal value sits in the profile (section, field[, entry])
RANGE_FIELDS: dict[str, tuple[str, ...]] = {
    "K_U": ("actuator", "K_U"),
    "tau": ("actuator", "tau"),
    "dead_zone_V": ("actuator", "dead_zone_V"),
    "force_limit_N": ("actuator", "force_limit_N"),
    "cart_force_N_rms": ("disturbance", "cart_force_N_rms"),
    "tip_force_N_rms": ("disturbance", "tip_force_N_rms"),
    "sensors.s": ("sensors", "s"),
    "sensors.theta": ("sensors", "theta"),
    "sensors.s_dot": ("sensors", "s_dot"),
    "noise_V_rms.s": ("sensors", "noise_V_rms", "s"),
    "noise_V_rms.theta": ("sensors", "noise_V_rms", "theta"),
    "noise_V_rms.s_dot": ("sensors", "noise_V_rms", "s_dot"),
}
UNITS = {"K_U": "N/V", "tau": "s", "dead_zone_V": "V", "force_limit_N": "N", "cart_force_N_rms": "N",
         "tip_force_N_rms": "N", "sensors.s": "V/m", "sensors.theta": "V/rad", "sensors.s_dot": "V/(m/s)",
         "noise_V_rms.s": "V", "noise_V_rms.theta": "V", "noise_V_rms.s_dot": "V"}
NORMAL_SIGMAS = 2.0  # a "normal" range is the mean +/- this many standard deviations


class BenchUncertainty(BaseModel):
    """The ``[uncertainty]`` table: ``distribution`` and a [low, high] range per parameter
    (RANGE_FIELDS' keys). The ranges are checked against the profile they belong to
    (patchgen.profiles.bench.check_bench), where a bad one names its key."""

    model_config = ConfigDict(extra="allow", frozen=True, strict=True)

    distribution: Literal["uniform", "normal"] = "uniform"

    @property
    def ranges(self) -> dict[str, tuple[float, float]]:
        """Every stated range, in RANGE_FIELDS order (an unknown key is left to the check)."""
        extra = self.model_extra or {}
        known = [k for k in RANGE_FIELDS if k in extra] + [k for k in extra if k not in RANGE_FIELDS]
        return {k: tuple(extra[k]) if isinstance(extra[k], (list, tuple)) else extra[k] for k in known}


def range_problem(value) -> str | None:
    """What is wrong with one range's value as written (None: two finite numbers, low <= high)."""
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        return "must be [low, high], two numbers"
    if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value):
        return "must be [low, high], two numbers"
    if not all(math.isfinite(v) for v in value):
        return f"must be two finite numbers (got {list(value)})"
    if value[0] > value[1]:
        return f"is reversed: low {value[0]:g} above high {value[1]:g}"
    return None


def nominal_or_none(bench: BaseModel, key: str) -> float | None:
    """The profile's own value of an uncertain parameter, None where the bench has no such signal."""
    path = RANGE_FIELDS[key]
    section = getattr(bench, path[0])
    return getattr(section, path[1]) if len(path) == 2 else nominal(bench, key)


def nominal(bench: BaseModel, key: str) -> float:
    """The profile's own value of an uncertain parameter (a RANGE_FIELDS key; 0 for a sensor
    noise the profile does not state)."""
    path = RANGE_FIELDS[key]
    section = getattr(bench, path[0])
    if len(path) == 3:
        return float(getattr(section, path[1]).get(path[2], 0.0))
    return float(getattr(section, path[1]))


def bench_at(bench: BaseModel, values: dict[str, float]) -> BaseModel:
    """The bench with some of its uncertain parameters (RANGE_FIELDS keys) at the given values.

    Parameters
    ----------
    bench : BenchProfile
        The nominal bench (patchgen.profiles.bench, which imports this module: typed here as the
        pydantic model it is).
    values : dict of str to float
        Parameter key -> value.

    Returns
    -------
    BenchProfile
        A copy with those values (not validated: see patchgen.profiles.bench.check_bench).
    """
    data = bench.model_dump()
    for key, v in values.items():
        path = RANGE_FIELDS[key]
        target = data[path[0]]
        if len(path) == 3:
            target = target[path[1]]
        target[path[-1]] = float(v)
    touched = {}  # section -> the fields set (a whole dump would put plain dicts where models were)
    for key in values:
        touched.setdefault(RANGE_FIELDS[key][0], set()).add(RANGE_FIELDS[key][1])
    return bench.model_copy(update={
        name: getattr(bench, name).model_copy(update={f: data[name][f] for f in fields})
        for name, fields in touched.items()})
