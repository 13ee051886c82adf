"""Simulation scenarios: initial state, disturbances, duration, noise and drift, seed (TOML files).

Noise and drift are ``"profile"`` (as the bench and machine profiles say), ``"off"``, or explicit:
noise as a table of V rms levels (``s``, ``theta``, ``s_dot`` sensors, ``amplifier`` output noise;
a level left out is zero), drift as one rate in V/s for every integrating amplifier.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, PrivateAttr, ValidationInfo, create_model, field_validator

from patchgen.inputs.errors import InputError
from patchgen.inputs.fields import InputModel, Int, Real, bounded, magnitude
from patchgen.inputs.resources import resolve
from patchgen.inputs.validation import read_toml, validate
from patchgen.plant.equations import PlantParams, push_shares
from patchgen.plant.plant_model import CART, PLANT_MODELS, ROTARY, PlantModel

MAX_DURATION_S = 1e5  # about a day: longer than any bench experiment
LEVEL_MAX_V = 100.0  # noise levels (V rms) and drift rates (V/s): far beyond any machine's rails
MAX_DISTANCE_M = 100.0  # cart position and step size: a hundred times a bench track (d = 1.09 m)
MAX_SPEED_M_S = 100.0  # cart speed: far beyond any cart a bench force can move
MAX_RATE_RAD_S = 1000.0  # pendulum rate: far beyond any swing of a bench pendulum
MAX_ARM_TURNS = 10  # a rotary arm's angle either way: far beyond any cable's wind-up
MAX_FORCE_N = 1e4  # a push: far beyond the 15 N the bench's actuator gives
DT_RANGE_S = (1e-6, 0.05)  # the engine's step: at most a quarter of the bench actuator's 0.2 s lag
RECORD_DT_RANGE_S = (1e-6, 1e3)  # history sample interval
RECORD_DT_S = 0.01  # default history sample interval: 100 samples a second, enough for the plots
MIN_RUN_STEPS = 5  # a run shorter than a few steps shows nothing (and its history's stride would overflow)
COARSEST_STEP_S = 0.01  # the engine's coarsest own step (patchgen.bench.engine.IDEAL_DT_S) when dt_s is not given
FALL_ANGLE_DEG = 30.0  # default: three times the 10 deg the standard scenarios start from
MAX_DISTURBANCES = 1000  # disturbances in one scenario: far more than any experiment has
SEED_LIMIT = 2**63  # a seed is a non-negative signed 64-bit integer, as the simulator checks too


def _initial_fields() -> dict:
    """One field per state of every plant model, in SI units (an angle in rad, or in degrees as
    ``<name>_deg``; a distance in metres, or as ``<name>_track``, a fraction of the track), a state
    at rest or upright when left out."""
    fields: dict = {}
    for plant in PLANT_MODELS.values():
        for st in plant.states:
            name, unit = st.name, st.unit
            if name in fields:
                continue
            if name in plant.rate_of and unit == "m":
                fields[name] = (magnitude(MAX_DISTANCE_M), 0.0)
                fields[f"{name}_track"] = (magnitude(0.5) | None, Field(default=None, description=(
                    f"the {plant.body}'s offset as a fraction of the track length d between the switches: sized "
                    "for whatever bench")))
            elif name in plant.rate_of:  # an angle: the pendulum's within a half turn, an arm's a few turns
                bound = math.pi if name == plant.angle else MAX_ARM_TURNS * 2 * math.pi
                fields[name] = (magnitude(bound) | None, None)
                fields[f"{name}_deg"] = (magnitude(math.degrees(bound)) | None, Field(default=None,
                                                                                      validate_default=True))
            else:
                fields[name] = (magnitude(MAX_SPEED_M_S if unit == "m/s" else MAX_RATE_RAD_S), 0.0)
    return fields


def _one_of_two(cls, v, info: ValidationInfo):
    """An angle in rad or in degrees, a distance in metres or as a fraction of the track: not both."""
    base, _, how = info.field_name.rpartition("_")
    if v is not None and info.data.get(base):
        unit = "m" if how == "track" else "rad"
        raise ValueError(f"give {base} ({unit}) or {info.field_name}, not both")
    return v


class _Initial(InputModel):
    """The initial state's methods (the fields are every plant's states: InitialState)."""

    def vector(self, plant: PlantModel = CART) -> tuple[float, ...]:
        """The plant's state at t = 0 in its order, SI units (an angle in degrees converted)."""
        out = []
        for name in plant.state_names:
            v = getattr(self, name)
            if v is None:
                v = math.radians(getattr(self, f"{name}_deg") or 0.0)
            out.append(float(v))
        return tuple(out)

    def stated(self) -> tuple[str, ...]:
        """The fields the scenario sets (off their rest values)."""
        return tuple(k for k in type(self).model_fields if getattr(self, k))

    def foreign(self, plant: PlantModel) -> str | None:
        """The first field set that is no state of ``plant`` (another plant's), else None."""
        own = set(plant.state_names)
        for k in self.stated():
            base = k.rpartition("_")[0] if k.endswith(("_deg", "_track")) else k
            if base not in own:
                return k
        return None


InitialState = create_model(
    "InitialState", __base__=_Initial, __module__=__name__,
    __doc__="Plant state at t = 0 (SI units; an angle in rad or in degrees, not both; the cart in metres or as "
            "a fraction of the track, not both): the pendulum within +/-180 deg, the cart within 100 m (and, "
            "against a spec, inside its track), an arm within a few turns. Each plant reads its own states; "
            "another plant's, set, is refused.",
    __validators__={"one_of_two": field_validator(
        *(k for k in _initial_fields() if k.endswith(("_deg", "_track"))), mode="after")(_one_of_two)},
    **_initial_fields())


_NEEDS = {"force_impulse": ("at", "duration_s", "force_N"), "step": ()}  # what a kind must have
_SIZES = ("size_m", "size_track", "size_rad", "size_deg")  # a step's: one of them (Disturbance._one_size)
_ALLOWED = {"force_impulse": _NEEDS["force_impulse"] + ("arm_m",), "step": _SIZES}  # what a kind may have


class Disturbance(InputModel):
    """A push or a command during the run.

    ``force_impulse``: a horizontal force ``force_N`` on the pendulum tip, on the cart, or at the
    end of a rotary pendulum's arm (along its path) from ``time_s`` for ``duration_s``. ``step``:
    the position command steps at ``time_s`` (an offset on the position sensor's reference, so the
    loop moves the cart or the arm there): a cart's by ``size_m`` (or ``size_track``, a fraction of
    the track length d), an arm's by ``size_rad`` (or ``size_deg``).
    """

    kind: Literal["force_impulse", "step"]
    time_s: Real = bounded(0, MAX_DURATION_S)
    at: Literal["pendulum_tip", "cart", "arm"] | None = Field(default=None, validate_default=True)
    duration_s: Real | None = bounded(0, MAX_DURATION_S, open_lo=True, default=None, validate_default=True)
    force_N: magnitude(MAX_FORCE_N) | None = Field(default=None, validate_default=True)
    size_rad: magnitude(MAX_ARM_TURNS * 2 * math.pi) | None = Field(default=None, validate_default=True)
    size_deg: magnitude(MAX_ARM_TURNS * 360.0) | None = Field(default=None, validate_default=True)
    size_track: magnitude(1.0) | None = Field(default=None, validate_default=True)
    size_m: magnitude(MAX_DISTANCE_M) | None = Field(default=None, validate_default=True)
    arm_m: Real | None = bounded(0, MAX_DISTANCE_M, open_lo=True, default=None, validate_default=True,
                                 description="a push on the pendulum: where, m from the pivot (none: at l, its "
                                             "centre of mass, the tip of the thesis's point mass)")

    @field_validator("size_m", mode="after")
    @classmethod
    def _one_size(cls, v, info: ValidationInfo):
        if info.data.get("kind") != "step":
            return v
        given = [k for k in _SIZES if (v if k == "size_m" else info.data.get(k)) is not None]
        if not given:
            raise ValueError("missing field (needed for kind 'step'; or size_track, a fraction of the track; an "
                             "arm's step: size_rad or size_deg)")
        if given == ["size_m", "size_track"] or given == ["size_track", "size_m"]:
            raise ValueError("give size_m (m) or size_track (a fraction of the track), not both")
        if len(given) > 1:
            raise ValueError(f"give one size, not {' and '.join(given)}")
        return v

    def step_size(self) -> float:
        """A step's size in SI units of the position it moves (m, or rad from size_deg)."""
        if self.size_deg is not None:
            return math.radians(self.size_deg)
        return self.size_rad if self.size_rad is not None else self.size_m

    @field_validator("arm_m", mode="after")
    @classmethod
    def _on_the_pendulum(cls, v, info: ValidationInfo):
        if v is not None and info.data.get("kind") == "force_impulse" and info.data.get("at") != "pendulum_tip":
            raise ValueError("is where a push on the pendulum acts: only with at = 'pendulum_tip'")
        return v

    @field_validator("at", "duration_s", "force_N", *_SIZES, "arm_m", mode="after")
    @classmethod
    def _for_kind(cls, v, info: ValidationInfo):
        kind = info.data.get("kind")
        if kind is None:  # the kind itself is wrong, and reported
            return v
        if info.field_name in _NEEDS[kind] and v is None:
            raise ValueError(f"missing field (needed for kind {kind!r})")
        if info.field_name not in _ALLOWED[kind] and v is not None:
            raise ValueError(f"does not apply to kind {kind!r}")
        return v


FORCE_LEVEL_MAX_N = 1e3  # an explicit random force's rms: as a bench profile's bound
Level = Annotated[Real, Field(ge=0, le=LEVEL_MAX_V)]


class NoiseLevels(InputModel):
    """Noise: as the profiles say, off, or explicit levels in V rms (sensors and every
    amplifier's output; the levels count only in mode 'explicit')."""

    mode: Literal["profile", "off", "explicit"] = "explicit"
    s: Level | None = None
    theta: Level | None = None
    s_dot: Level | None = None
    amplifier: Level | None = None
    alpha: Level | None = None  # a rotary pendulum's arm encoder
    alpha_dot: Level | None = None
    cart_force_N: Annotated[Real, Field(ge=0, le=FORCE_LEVEL_MAX_N)] | None = None  # N rms
    arm_torque_Nm: Annotated[Real, Field(ge=0, le=FORCE_LEVEL_MAX_N)] | None = None  # N m rms, on a rotary arm
    tip_force_N: Annotated[Real, Field(ge=0, le=FORCE_LEVEL_MAX_N)] | None = None  # N rms

    def level(self, name: str) -> float:
        """An explicit level, V rms (forces: N rms); one left out is zero."""
        return getattr(self, name, None) or 0.0


class Scenario(InputModel):
    """One simulation case. ``dt_s`` overrides the engine's step; ``record_dt_s`` is the history
    sample interval; ``fall_angle_deg`` is where the pendulum counts as fallen."""

    name: str = ""
    description: str = ""
    duration_s: Real = bounded(0, MAX_DURATION_S, open_lo=True)
    dt_s: Real | None = bounded(*DT_RANGE_S, default=None)
    record_dt_s: Real = bounded(*RECORD_DT_RANGE_S, default=RECORD_DT_S)
    seed: Int = Field(default=0, ge=0, lt=SEED_LIMIT)
    fall_angle_deg: Real = bounded(0, 180, open_lo=True, default=FALL_ANGLE_DEG)
    initial: InitialState = InitialState()
    disturbances: list[Disturbance] = Field(default_factory=list, max_length=MAX_DISTURBANCES)
    noise: NoiseLevels = NoiseLevels(mode="profile")
    drift: Literal["profile", "off"] | Level = "profile"

    _path: str = PrivateAttr(default="<scenario>")

    def excites(self) -> bool:
        """Whether anything disturbs the balanced pendulum: an initial state off rest, a push or
        step, or noise and random forces. Holding a scenario with none proves nothing."""
        levels = (self.noise.level(k) for k in NoiseLevels.model_fields if k != "mode")
        return (bool(self.initial.stated()) or bool(self.disturbances)
                or self.noise.mode == "profile" or (self.noise.mode == "explicit" and any(levels)))

    def judged(self) -> Scenario:
        """The scenario, when a patch may be judged in it; an InputError when nothing disturbs
        the pendulum (a patch that does nothing at all would hold it)."""
        if not self.excites():
            raise InputError(self.path, "initial", "nothing disturbs the pendulum (at rest upright, no push or "
                             "step, noise off): any patch holds it, so it cannot judge one; start it off rest, "
                             "push it, or give it noise")
        return self

    def on_track(self, track_m: float) -> Scenario:
        """The scenario in SI for a track of length ``track_m`` (the plant's d): an offset and
        step sizes given as fractions of the track become metres; one in metres stays."""
        if self.initial.s_track is None and all(x.size_track is None for x in self.disturbances):
            return self
        initial = self.initial
        if initial.s_track is not None:
            initial = initial.model_copy(update={"s": initial.s_track * track_m, "s_track": None})
        steps = [x.model_copy(update={"size_m": x.size_track * track_m, "size_track": None})
                 if x.size_track is not None else x for x in self.disturbances]
        return self.model_copy(update={"initial": initial, "disturbances": steps})

    def on_pendulum(self, plant: PlantParams) -> Scenario:
        """The scenario's pushes as the simulator applies them to ``plant``: a push on the pendulum
        at ``arm_m`` becomes a push on the cart and one at l (patchgen.plant.equations.push_shares),
        as the nominal pendulum has them; one at l stays as it is."""
        return self._pushes_shared(lambda arm_m: push_shares(plant, arm_m)[::-1], "cart")

    def on_arm(self, plant) -> Scenario:
        """The scenario's pushes as the simulator applies them to a rotary pendulum (a RotaryParams):
        a push on the pendulum at ``arm_m`` from its pivot does its work as arm_m / L_p of it at the
        tip and the rest at the arm's end (the same generalised forces: F L_r on the arm, F arm_m
        cos(theta) on the pendulum); one at the tip, or at the arm's end, stays as it is."""
        return self._pushes_shared(lambda arm_m: (arm_m / plant.L_p, 1.0 - arm_m / plant.L_p), "arm")

    def _pushes_shared(self, shares, body: str) -> Scenario:
        """Each push at a stated point of the pendulum split as ``shares(arm_m)`` says: (the share
        where the simulator's tip force acts, the share on ``body``)."""
        if all(x.arm_m is None for x in self.disturbances):
            return self
        out = []
        for x in self.disturbances:
            if x.arm_m is None:
                out.append(x)
                continue
            tip, rest = shares(x.arm_m)
            out.append(x.model_copy(update={"force_N": x.force_N * tip, "arm_m": None}))
            if rest:
                out.append(x.model_copy(update={"force_N": x.force_N * rest, "arm_m": None, "at": body}))
        return self.model_copy(update={"disturbances": out})

    @property
    def path(self) -> str:
        """The file it was read from (or a label for a scenario built in code)."""
        return self._path

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
    """Read and check a scenario.

    Parameters
    ----------
    path : str or Path
        A scenario file, or a shipped scenario by name (``hold-120s``).

    Returns
    -------
    Scenario
        The checked scenario; its name defaults to the file's stem.

    Raises
    ------
    InputError
        Any problem with the file or a field (a run shorter than MIN_RUN_STEPS steps, a
        disturbance after the end among them).
    """
    sc = validate(Scenario, read_toml(resolve("scenario", path)), str(path))
    sc = sc if sc.name else sc.model_copy(update={"name": Path(str(path)).stem})
    sc._path = str(path)
    step = sc.dt_s or COARSEST_STEP_S
    if sc.duration_s < MIN_RUN_STEPS * step:
        of = f"dt_s = {step:g} s" if sc.dt_s else f"the simulator's own step, up to {step:g} s"
        raise InputError(sc.path, "duration_s", f"{sc.duration_s:g} s is shorter than {MIN_RUN_STEPS} simulation "
                         f"steps ({of}): at least {MIN_RUN_STEPS * step:g} s")
    for i, d in enumerate(sc.disturbances):
        if d.time_s >= sc.duration_s:
            raise InputError(sc.path, f"disturbances[{i}].time_s", f"{d.time_s:g} s is not before the end of "
                             f"the run (duration_s = {sc.duration_s:g} s)")
    return sc


def check_on_track(sc: Scenario, track_m: float, spec_path: str) -> None:
    """The initial cart position must be inside the track between the limit switches, or the run
    would end before it starts.

    Parameters
    ----------
    sc : Scenario
        The scenario.
    track_m : float
        The track length d of the spec's plant (m); the switches sit at +/- d/2.
    spec_path : str
        The spec that gave d, named in the error.

    Raises
    ------
    InputError
        Naming the scenario's ``initial.s``.
    """
    sc = sc.on_track(track_m)
    if abs(sc.initial.s) >= track_m / 2:
        raise InputError(sc.path, "initial.s", f"{sc.initial.s:g} m is outside the track: the limit switches of "
                         f"{spec_path} are at +/-{track_m / 2:g} m (plant.d = {track_m:g} m)")


# what a disturbance field says of the plant it is for: a cart's sizes and push, an arm's
_CART_ONLY, _ARM_ONLY = ("size_m", "size_track"), ("size_rad", "size_deg")


def check_plant(sc: Scenario, plant: PlantModel, spec_path: str) -> None:
    """The scenario speaks of ``plant``: its initial state names only the plant's states, a step
    is sized as the plant's position is (a cart's in m, an arm's in rad), a push acts on the
    pendulum or on the plant's own body.

    Raises
    ------
    InputError
        Naming the scenario's field, and the spec's plant.
    """
    foreign = sc.initial.foreign(plant)
    if foreign is not None:
        raise InputError(sc.path, f"initial.{foreign}", f"is no state of {spec_path}'s plant, a {plant.name} "
                         f"(its states: {', '.join(plant.state_names)})")
    unit = plant.units[plant.position]
    for i, d in enumerate(sc.disturbances):
        wrong = _ARM_ONLY if unit == "m" else _CART_ONLY
        for k in wrong:
            if getattr(d, k) is not None:
                raise InputError(sc.path, f"disturbances[{i}].{k}", f"sizes another plant's step: {spec_path}'s "
                                 f"{plant.position} is in {unit} ({', '.join(k for k in _SIZES if k not in wrong)})")
        if d.at in ("cart", "arm") and d.at != plant.body:
            raise InputError(sc.path, f"disturbances[{i}].at", f"{d.at!r}: {spec_path}'s plant has no {d.at} (a "
                             f"{plant.name}: 'pendulum_tip' or {plant.body!r})")


def check_on_arm(sc: Scenario, limit_rad: float, spec_path: str) -> None:
    """A rotary pendulum's arm must start inside its cable's wind-up (``limit_rad``, the spec's
    plant.alpha_limit), or the run would end before it starts.

    Raises
    ------
    InputError
        Naming the scenario's ``initial.alpha`` (or ``initial.alpha_deg``).
    """
    alpha = sc.initial.vector(ROTARY)[0]
    if abs(alpha) >= limit_rad:
        field = "initial.alpha_deg" if sc.initial.alpha_deg is not None else "initial.alpha"
        raise InputError(sc.path, field, f"{math.degrees(alpha):g} deg is past the cable's wind-up of {spec_path} "
                         f"at +/-{math.degrees(limit_rad):g} deg (plant.alpha_limit)")


def fits(sc: Scenario, plant: PlantModel) -> bool:
    """Whether the scenario speaks of ``plant`` (check_plant passes): a step-cart is no rotary
    pendulum's scenario, an arm's step no cart's; a release or a tap at the tip is either's."""
    try:
        check_plant(sc, plant, "")
    except InputError:
        return False
    return True
