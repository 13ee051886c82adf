"""Bench profiles: the real actuator, sensors and track that a patch meets (not the design's model)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field

from patchgen.inputs.errors import InputError
from patchgen.inputs.fields import InputModel, Real, bounded, zero_or_at_least
from patchgen.inputs.resources import folder, resolve
from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.validation import load_profile, validate
from patchgen.profiles.uncertainty import RANGE_FIELDS, BenchUncertainty, range_problem


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


# Random forces on the plant while it balances, when a bench profile does not state its own. No
# source measures them: the thesis reports neither air currents nor cable drag. Assumed, small
# beside what a patch must answer (the dead zone alone is 2.8 N on the uw-1991 bench) but never zero,
# so that no simulated pendulum stays up that the patch does not balance.
ASSUMED_CART_FORCE_N_RMS = 0.1  # N: cable drag, track and belt irregularities
ASSUMED_TIP_FORCE_N_RMS = 0.01  # N: air currents, about a third of a degree of lean on table B.1's pendulum
ASSUMED_FORCE_BANDWIDTH_HZ = 5.0  # Hz: slow, as drafts and drag are


class BenchDisturbance(InputModel):
    """Random forces on the plant (rms over a flat band from 0 to bandwidth_Hz): on the cart, and
    horizontal at the pendulum's tip. On in every run that is not ideal (scenario noise "off" or
    explicit levels override them)."""

    cart_force_N_rms: Real = bounded(0, 1e3, default=ASSUMED_CART_FORCE_N_RMS)
    tip_force_N_rms: Real = bounded(0, 1e3, default=ASSUMED_TIP_FORCE_N_RMS)
    bandwidth_Hz: Real = bounded(1e-3, 1e4, default=ASSUMED_FORCE_BANDWIDTH_HZ)


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
    disturbance: BenchDisturbance = BenchDisturbance()
    uncertainty: BenchUncertainty = BenchUncertainty()
    recordings: list[Annotated[str, Field(min_length=1)]] = Field(
        default_factory=list, description="the recordings an identified profile was fitted to (patchgen identify)")
    scenarios: list[Annotated[str, Field(min_length=1, max_length=1000)]] = Field(
        default_factory=list, max_length=50,
        description="the scenarios this bench is judged in (shipped names, or files, a relative path read "
                    "beside the profile first); none: every shipped one (STANDARD_SCENARIOS)")


STANDARD_SCENARIOS = ("offset-10deg", "finger-push", "step-cart", "hold-120s")  # the shipped set


def bench_scenarios(bench: BenchProfile) -> tuple[str, ...]:
    """The scenarios a patch is judged in on this bench: the profile's own, else the shipped set."""
    return tuple(bench.scenarios) or STANDARD_SCENARIOS


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
    bench = load_profile(BenchProfile, name_or_path, "bench", source, field, check=check_bench)
    return _scenarios_found(bench, resolve("bench", name_or_path, source, field))


def _scenarios_found(bench: BenchProfile, where) -> BenchProfile:
    """The profile with each of its scenarios found (a relative path beside the profile first, as
    patchgen.inputs.resources.resolve looks) and read: a file is kept by its path, a shipped one by
    its name; a scenario that cannot be found or read is an InputError naming the profile's
    ``scenarios[i]`` or the scenario's own field."""
    if not bench.scenarios:
        return bench
    label = str(where) if isinstance(where, Path) else bench.id
    found = []
    for i, name in enumerate(bench.scenarios):
        path = resolve("scenario", name, label, f"scenarios[{i}]")
        if path == folder("scenario").joinpath(f"{name}.toml"):
            found.append(name)  # a shipped scenario, by its name
            continue
        if not (isinstance(path, Path) and path.is_file()):
            raise InputError(label, f"scenarios[{i}]", f"{name!r}: no such scenario file (looked for beside the "
                                                      "profile, then in the working folder)")
        found.append(str(path))
        load_scenario(found[-1]).judged()
    return bench.model_copy(update={"scenarios": found})


def nominal(bench: BenchProfile, key: str) -> float:
    """The profile's own value of an uncertain parameter (a RANGE_FIELDS key; 0 for a sensor
    noise the profile does not state)."""
    path = RANGE_FIELDS[key]
    section = getattr(bench, path[0])
    if len(path) == 3:
        return float(getattr(section, path[1]).get(path[2], 0.0))
    return float(getattr(section, path[1]))


def bench_at(bench: BenchProfile, values: dict[str, float]) -> BenchProfile:
    """The bench with some of its uncertain parameters (RANGE_FIELDS keys) at the given values.

    Parameters
    ----------
    bench : BenchProfile
        The nominal bench.
    values : dict of str to float
        Parameter key -> value.

    Returns
    -------
    BenchProfile
        A copy with those values (not validated: see check_bench).
    """
    data = bench.model_dump()
    for key, v in values.items():
        path = RANGE_FIELDS[key]
        target = data[path[0]]
        if len(path) == 3:
            target = target[path[1]]
        target[path[-1]] = float(v)
    return bench.model_copy(update={
        name: getattr(bench, name).model_copy(update=data[name]) for name in ("actuator", "sensors", "disturbance")})


def check_bench(bench: BenchProfile, source: str) -> None:
    """The checks of the ``[uncertainty]`` table: each key a parameter of the bench, each range two
    finite numbers low <= high, the profile's own value inside it, and both ends values the
    profile itself would accept (positive where the field must be).

    Raises
    ------
    InputError
        The first bad range, naming ``uncertainty.<key>``.
    """
    for key, rng in bench.uncertainty.ranges.items():
        field = f"uncertainty.{key}"
        if key not in RANGE_FIELDS and isinstance(rng, dict) and any(f"{key}.{k}" in RANGE_FIELDS for k in rng):
            sub = next(k for k in rng if f"{key}.{k}" in RANGE_FIELDS)
            raise InputError(source, field, f"a table, not a range: TOML reads {key}.{sub} unquoted as a table; "
                                            f'write the key quoted, "{key}.{sub}" = [low, high]')
        if key not in RANGE_FIELDS:
            raise InputError(source, field, "not a parameter of the bench (its parameters: "
                             + ", ".join(RANGE_FIELDS) + "; the plant's are the spec's, spread with --spread)")
        problem = range_problem(rng)
        if problem:
            raise InputError(source, field, problem)
        lo, hi = float(rng[0]), float(rng[1])
        nom = nominal(bench, key)
        where = ".".join(RANGE_FIELDS[key])
        if not lo <= nom <= hi:
            raise InputError(source, field, f"[{lo:g}, {hi:g}] does not contain the profile's own value "
                             f"({where} = {nom:g})")
        if key == "tau" and bench.actuator.model != "gain" and lo <= 0:
            raise InputError(source, field, f"low end must be above 0: the actuator model {bench.actuator.model} "
                             "needs a lag")
        for end, v in (("low", lo), ("high", hi)):
            try:
                validate(BenchProfile, bench_at(bench, {key: v}).model_dump(), source)
            except InputError as exc:
                raise InputError(source, field, f"{end} end {v:g}: {exc.field} {exc.message}") from None
