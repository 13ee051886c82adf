"""Bench profiles: the real actuator, sensors and track that a patch meets (not the design's model)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, ClassVar, Literal

from pydantic import Field, create_model, field_validator

from patchgen.inputs.drive_fields import DERIVED_TOL, DriveFields, derived, k_u_field, k_u_of, motor_of
from patchgen.inputs.errors import InputError
from patchgen.inputs.fields import InputModel, Real, bounded, zero_or_at_least
from patchgen.inputs.resources import folder, resolve
from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.validation import load_profile, validate
from patchgen.plant.drive import INDUCTANCE
from patchgen.plant.plant_model import CART, DEFAULT, PLANT_MODELS, ROTARY, PlantModel
from patchgen.profiles.measured_plant import check_measured
from patchgen.profiles.uncertainty import (
    RANGE_FIELDS,
    BenchUncertainty,
    bench_at,
    nominal,
    nominal_or_none,
    range_problem,
)


def _motor_only(value, info):
    if value is not None and info.data.get("model") != "dc_motor":
        raise ValueError(f'is a motor figure: only for model = "dc_motor" (this actuator is {info.data.get("model")})')
    return value


def _amplifier_limit(value, info):
    if info.data.get("model") == "dc_motor":
        if value is None:
            raise ValueError("missing field: a dc_motor's amplifier limit (motor volts)")
    return _motor_only(value, info)


def _force_limit(value, info):
    if info.data.get("model") != "dc_motor":
        if value is None:
            raise ValueError("missing field (N)")
        return value
    v_lim = info.data.get("V_limit")
    if v_lim is None:
        return value
    return derived(value, info, "a x V_limit", lambda m: m.force_per_volt() * v_lim)


class BenchActuator(DriveFields):
    """Command voltage to force: K_U, lag (optional zero at the origin), dead zone, force limit;
    or a DC motor driven by voltage through an amplifier (patchgen.plant.drive): its figures,
    its inductance, and the amplifier's voltage limit, at which the command saturates."""

    K_U: Real | None = k_u_field("N/V (a dc_motor's follows from the motor: amp_gain x a)")
    tau: Annotated[Real, zero_or_at_least(1e-3)] = bounded(0, 10, default=0.0, description="s")
    L_m: Real | None = bounded(INDUCTANCE.lo, INDUCTANCE.hi, default=None, validate_default=True,
                               description="dc_motor: " + INDUCTANCE.what)
    V_limit: Real | None = bounded(1e-3, 1e4, default=None, validate_default=True,
                                   description="dc_motor: the amplifier's output limit, motor volts")
    dead_zone_V: Real = bounded(0, 100, default=0.0)
    force_limit_N: Real | None = Field(None, gt=0, le=1e4, validate_default=True,
                                       description="N (a dc_motor's follows: a x V_limit)")

    k_u_check = field_validator("K_U", mode="after")(k_u_of)
    motor_only = field_validator("L_m", mode="after")(_motor_only)
    limit_check = field_validator("V_limit", mode="after")(_amplifier_limit)
    force_check = field_validator("force_limit_N", mode="after")(_force_limit)

    def motor_lag(self) -> float:
        """A dc_motor's electrical lag L_m / R_m (s); 0 for other models."""
        m = motor_of(self)
        return 0.0 if m is None else m.electrical_lag()


class VelocityFilter(InputModel):
    """A velocity as a lab without a tachometer has it: the rate of its position's (encoder)
    reading through wn^2 / (s^2 + 2 zeta wn s + wn^2) (Quanser's IP02: 2 pi 10 rad/s, 0.9)."""

    wn_rad_s: Real = bounded(1.0, 1e5, description="rad/s")
    zeta: Real = bounded(0.05, 10)


class Sensors(InputModel):
    """A bench's sensors (one table per plant model, made by ``_sensor_table``)."""

    plant_model: ClassVar[PlantModel]

    def quanta(self) -> dict[str, float]:
        """Each encoder-read quantity's count in SI units (m, rad)."""
        out = {q: 1.0 / n for q, n in getattr(self, "counts_per_m", {}).items()}
        out.update({q: 2.0 * math.pi / n for q, n in self.counts_per_rev.items()})
        return out

    def filters(self) -> dict[str, VelocityFilter]:
        """The velocities read through a filter, by quantity."""
        return dict(self.velocity_filter)


def _sensor_table(plant: PlantModel, class_name: str):
    """The ``[sensors]`` table of a bench of ``plant``: a constant per quantity its sensors may
    read (a rate's optional: none, no signal), their noise, the encoders' counts (per metre of a
    distance, per revolution of an angle) and the velocities read through a filter."""
    units = plant.units
    rates = tuple(q for q in plant.measurable if q in plant.position_of)
    fields = {}
    for q in plant.measurable:
        if q in rates:
            fields[q] = (Real | None, bounded(1e-3, 1e3, default=None, description=(
                f"V/({units[q]}); none: the bench has no velocity signal (no tachometer, no filter), and a patch "
                f"finds {q} from {plant.position_of[q]}")))
        else:
            fields[q] = (Real, bounded(1e-3, 1e3))
    fields["noise_V_rms"] = (dict[Literal[plant.measurable], Annotated[Real, Field(ge=0, le=100)]],
                             Field(default_factory=dict))
    fields["noise_bandwidth_Hz"] = (Real, bounded(1e-3, 1e9, default=200.0))
    distances = tuple(q for q in plant.rate_of if units[q] == "m")
    angles = tuple(q for q in plant.rate_of if units[q] == "rad")
    if distances:
        fields["counts_per_m"] = (dict[Literal[distances], Annotated[Real, Field(ge=1, le=1e9)]], Field(
            default_factory=dict, description="an encoder's counts per metre of a distance it reads"))
    fields["counts_per_rev"] = (dict[Literal[angles], Annotated[Real, Field(ge=4, le=1e9)]], Field(
        default_factory=dict, description="an encoder's counts per revolution of an angle it reads (quadrature "
                                          "counts: 4 x the lines)"))
    fields["velocity_filter"] = (dict[Literal[rates], VelocityFilter], Field(
        default_factory=dict, description="a velocity from a filter of its position's reading, not a tachometer"))
    table = create_model(class_name, __base__=Sensors, __module__=__name__,
                         __doc__="Sensor constants (V per SI unit), their noise, and how each is measured: an "
                                 "encoder's counts, a velocity through a filter of its position's reading (none "
                                 f"stated: a tachometer, read directly); of {plant.what}.", **fields)
    table.plant_model = plant
    return table


BenchSensors = _sensor_table(CART, "BenchSensors")
RotaryBenchSensors = _sensor_table(ROTARY, "RotaryBenchSensors")


# Random forces on the plant while it balances, when a bench profile does not state its own. No
# source measures them: the thesis reports neither air currents nor cable drag. Assumed, small
# beside what a patch must answer (the dead zone alone is 2.8 N on the uw-1991 bench) but never zero,
# so that no simulated pendulum stays up that the patch does not balance.
ASSUMED_CART_FORCE_N_RMS = 0.1  # N: cable drag, track and belt irregularities
ASSUMED_TIP_FORCE_N_RMS = 0.01  # N: air currents, about a third of a degree of lean on table B.1's pendulum
ASSUMED_FORCE_BANDWIDTH_HZ = 5.0  # Hz: slow, as drafts and drag are
# N m on a rotary pendulum's arm: cable drag, a tenth of what a QUBE-Servo 2's motor gives at 1 V
# (k_t / R_m = 5 mN m/V); its pendulum is a tenth of table B.1's in length, so a tenth of the tip force
ASSUMED_ARM_TORQUE_NM_RMS = 5e-4


class BenchDisturbance(InputModel):
    """Random forces on the plant (rms over a flat band from 0 to bandwidth_Hz): on the cart, and
    horizontal at the pendulum's tip. On in every run that is not ideal (scenario noise "off" or
    explicit levels override them)."""

    cart_force_N_rms: Real = bounded(0, 1e3, default=ASSUMED_CART_FORCE_N_RMS)
    tip_force_N_rms: Real = bounded(0, 1e3, default=ASSUMED_TIP_FORCE_N_RMS)
    bandwidth_Hz: Real = bounded(1e-3, 1e4, default=ASSUMED_FORCE_BANDWIDTH_HZ)

    @property
    def position_rms(self) -> float:
        """The random generalised force on the position (the cart's, N)."""
        return self.cart_force_N_rms


class BenchTrack(InputModel):
    """The track: whether limit switches cut the power at its ends."""

    limit_switches: bool = True
    watchdog_m: Real | None = bounded(1e-3, 10, default=None, description=(
        "|s| beyond which the lab's control cuts the motor, m, as a Quanser IP02's scripts do at 0.3 m (none: the "
        "switches alone)"))

    def cut_at(self, track_m: float) -> float | None:
        """|s| (m) at which the motor is cut on a track of ``track_m``: the watchdog's, or the switches' at
        half the track, the nearer; None when neither acts."""
        ends = ([track_m / 2] if self.limit_switches else []) + ([self.watchdog_m] if self.watchdog_m else [])
        return min(ends) if ends else None


class BenchProfile(InputModel):
    """A whole bench: read from patchgen/profiles/benches/<id>.toml or a user path."""

    id: str = Field(min_length=1)
    name: str
    plant: Literal[CART.name] = Field(CART.name, description="the plant model the bench carries: "
                                      + ", ".join(PLANT_MODELS))
    actuator: BenchActuator
    sensors: BenchSensors
    track: BenchTrack = BenchTrack()
    disturbance: BenchDisturbance = BenchDisturbance()
    uncertainty: BenchUncertainty = BenchUncertainty()
    measured_plant: dict[str, Real] = Field(
        default_factory=dict, description="the plant's figures as measured on this bench, where they differ from "
        "a spec's: the bench's stages simulate them, the design keeps the spec's (patchgen.profiles.measured_plant)")
    recordings: list[Annotated[str, Field(min_length=1)]] = Field(
        default_factory=list, description="the recordings an identified profile was fitted to (patchgen identify)")
    scenarios: list[Annotated[str, Field(min_length=1, max_length=1000)]] = Field(
        default_factory=list, max_length=50,
        description="the scenarios this bench is judged in (shipped names, or files, a relative path read "
                    "beside the profile first); none: every shipped one (STANDARD_SCENARIOS)")


def _input_limit(value, info):
    """A rotary bench's input limit: its amplifier's V_limit (given again, it must agree)."""
    limit = info.data.get("V_limit")
    if limit is None or value is None:
        return limit if value is None else value
    if not math.isclose(value, limit, rel_tol=DERIVED_TOL):
        raise ValueError(f"is the amplifier's V_limit on a rotary bench ({limit:g} V): leave it out (got {value:g})")
    return limit


class RotaryBenchActuator(BenchActuator):
    """The amplifier that drives a rotary pendulum's motor (its motor is the plant's): motor volts
    per command volt K_U (V/V), an optional lag and dead zone, and the volts it can give, V_limit.
    The plant's input is the motor's voltage, so its limit (force_limit_N's place) is V_limit."""

    model: Literal["gain", "lag"] = "gain"
    K_U: Real | None = k_u_field("V/V: motor volts per command volt")
    V_limit: Real = bounded(1e-3, 1e4, description="the amplifier's output limit, motor volts")
    force_limit_N: Real | None = Field(None, gt=0, le=1e4, validate_default=True,
                                       description="the plant input's limit: V_limit, motor volts")

    limit_check = field_validator("V_limit", mode="after")(lambda v: v)
    force_check = field_validator("force_limit_N", mode="after")(_input_limit)


class RotaryDisturbance(InputModel):
    """Random forces on a rotary pendulum (rms over a flat band from 0 to bandwidth_Hz): a torque
    on the arm about the motor's axis, and a force at the pendulum's tip across it."""

    arm_torque_Nm_rms: Real = bounded(0, 1e2, default=ASSUMED_ARM_TORQUE_NM_RMS)
    tip_force_N_rms: Real = bounded(0, 1e3, default=ASSUMED_TIP_FORCE_N_RMS / 10)
    bandwidth_Hz: Real = bounded(1e-3, 1e4, default=ASSUMED_FORCE_BANDWIDTH_HZ)

    @property
    def position_rms(self) -> float:
        """The random generalised force on the position (the arm's torque, N m)."""
        return self.arm_torque_Nm_rms


NO_TRACK = BenchTrack(limit_switches=False)  # a rotary bench's: no switches, no watchdog


class RotaryBenchProfile(BenchProfile):
    """A rotary pendulum's bench (``plant = "rotary-pendulum"``): its amplifier, its encoders, the
    forces on it. It has no track: the arm's limit is the plant's (alpha_limit, the cable)."""

    plant: Literal[ROTARY.name]
    actuator: RotaryBenchActuator
    sensors: RotaryBenchSensors
    disturbance: RotaryDisturbance = RotaryDisturbance()
    track: BenchTrack = Field(NO_TRACK, description="none: a rotary bench has no track")

    @field_validator("track", mode="after")
    @classmethod
    def _no_track(cls, value: BenchTrack) -> BenchTrack:
        if value != NO_TRACK:
            raise ValueError("a rotary pendulum has no track: the arm's limit is the spec's [plant] alpha_limit")
        return value


BENCH_TYPES = {CART.name: BenchProfile, ROTARY.name: RotaryBenchProfile}  # a profile's type, by its plant


def bench_type(document: dict, label: str) -> type[BenchProfile]:
    """The profile type of a parsed bench file, by its ``plant`` (the cart-pendulum when left out)."""
    name = document.get("plant", DEFAULT)
    if not isinstance(name, str) or name not in BENCH_TYPES:
        raise InputError(label, "plant", f"unknown plant model {name!r} (known: {', '.join(BENCH_TYPES)})")
    return BENCH_TYPES[name]


STANDARD_SCENARIOS = ("offset-10deg", "finger-push", "step-cart", "hold-120s")  # the shipped set


def bench_scenarios(bench: BenchProfile) -> tuple[str, ...]:
    """The scenarios a patch is judged in on this bench: the profile's own, else the shipped set."""
    return tuple(bench.scenarios) or STANDARD_SCENARIOS


def check_reads(bench: BenchProfile, read: tuple[str, ...], bench_source: str) -> None:
    """Every quantity a design reads is one this bench measures (a velocity without a signal is
    the patch's to find: leave it out of the spec's sensors.measured).

    Raises
    ------
    InputError
        Naming the bench's missing sensor.
    """
    for q in read:
        if getattr(bench.sensors, q, None) is None:
            raise InputError(bench_source, f"sensors.{q}", f"missing: the spec reads {q} on this bench (or leave {q} "
                             "out of the spec's sensors.measured, and the patch finds it)")


def bench_source(name_or_path: str, source: str = "", field: str = "bench") -> str:
    """The file a bench profile is read from, as an error names it (a shipped one by its path too)."""
    return str(resolve("bench", name_or_path, source, field))


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
    bench = load_profile(bench_type, name_or_path, "bench", source, field, check=check_bench)
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


def check_bench(bench: BenchProfile, source: str) -> None:
    """The checks of the ``[uncertainty]`` table: each key a parameter of the bench, each range two
    finite numbers low <= high, the profile's own value inside it, and both ends values the
    profile itself would accept (positive where the field must be).

    Raises
    ------
    InputError
        The first bad range, naming ``uncertainty.<key>``.
    """
    check_measured(bench, source)
    for q in bench.sensors.velocity_filter:
        if getattr(bench.sensors, q) is None:
            raise InputError(source, f"sensors.velocity_filter.{q}", "filters a velocity the bench gives no signal "
                             f"of: state its constant sensors.{q} (V per SI unit of the filter's output)")
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
        if RANGE_FIELDS[key][0] == "sensors" and len(RANGE_FIELDS[key]) == 2 and nominal_or_none(bench, key) is None:
            raise InputError(source, field, f"the bench has no {RANGE_FIELDS[key][1]} signal to be uncertain about")
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
                validate(type(bench), bench_at(bench, {key: v}).model_dump(), source)
            except InputError as exc:
                raise InputError(source, field, f"{end} end {v:g}: {exc.field} {exc.message}") from None
