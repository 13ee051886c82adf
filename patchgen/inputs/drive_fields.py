"""The [actuator] table's fields for a cart driven by a DC motor, shared by the design spec and
the bench profile: the motor's figures (patchgen.plant.drive.MOTOR_PARAMETERS, each with its
bounds) and the amplifier's gain from command volts to motor volts.

The fields exist for every actuator model but mean something only for ``model = "dc_motor"``:
there the figures without a default are required and K_U (N per command volt) follows from them,
K_U = amp_gain x a; for any other model none may be given.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, ValidationInfo, create_model, field_validator

from patchgen.inputs.fields import InputModel, Real, bounded
from patchgen.plant.drive import MOTOR_PARAMETERS, DCMotor

ACTUATOR_MODELS = Literal["gain", "lag", "lag_zero", "dc_motor"]
LAG_MODELS = ("lag", "lag_zero")  # the models whose force is a state (the design's "actuator")
DERIVED_TOL = 1e-9  # relative: a derived figure written back (a dumped profile read again) must agree to this
_REQUIRED = tuple(p.name for p in MOTOR_PARAMETERS if p.default is None)


def _motor_field(value, info: ValidationInfo):
    """A motor figure: required for a dc_motor (None: its default), refused for any other model."""
    model = info.data.get("model")
    if model == "dc_motor":
        if value is None and info.field_name in _REQUIRED:
            raise ValueError("missing field: a dc_motor actuator needs "
                             + ", ".join(_REQUIRED) + " (docs/spec.md)")
    elif value is not None and model is not None:
        raise ValueError(f'is a motor figure: only for model = "dc_motor" (this actuator is {model})')
    return value


DriveFields = create_model(
    "DriveFields", __base__=InputModel, __module__=__name__,
    __doc__="An [actuator] table's model and, for a dc_motor, the motor's figures and amplifier gain.",
    __validators__={"motor_fields": field_validator(*(p.name for p in MOTOR_PARAMETERS), "amp_gain",
                                                    mode="after")(_motor_field)},
    model=(ACTUATOR_MODELS, "gain"),
    **{p.name: (Real | None, bounded(p.lo, p.hi, default=None, validate_default=True,
                                     description=p.what + ("" if p.default is None else f" (default {p.default:g})")))
       for p in MOTOR_PARAMETERS},
    amp_gain=(Real | None, bounded(0.01, 100, default=None, validate_default=True,
                                   description="dc_motor: motor volts per command volt (default 1)")),
)


def _motor(figures: dict, inductance: float | None = None) -> DCMotor:
    """A DCMotor from an [actuator] table's figures by name, a default for each one not given."""
    return DCMotor(**{p.name: (p.default if figures.get(p.name) is None else figures[p.name])
                      for p in MOTOR_PARAMETERS}, L_m=inductance or 0.0)


def motor_of(section) -> DCMotor | None:
    """The DCMotor a validated [actuator] table states, defaults filled in; None for other models."""
    if section.model != "dc_motor":
        return None
    return _motor({p.name: getattr(section, p.name) for p in MOTOR_PARAMETERS}, getattr(section, "L_m", None))


def amp_gain_of(section) -> float:
    """Motor volts per command volt (1 unless stated)."""
    return 1.0 if section.amp_gain is None else section.amp_gain


def derived(value, info: ValidationInfo, what: str, of) -> float | None:
    """A figure that follows from the motor for a dc_motor (``of(motor)``): taken from it when not
    given, refused when given otherwise; for other models the value as given."""
    if info.data.get("model") != "dc_motor":
        return value
    if any(info.data.get(k) is None for k in _REQUIRED):
        return value  # the missing figure is reported on its own
    want = of(_motor(info.data))
    if value is not None and not math.isclose(value, want, rel_tol=DERIVED_TOL):
        raise ValueError(f"follows from the motor for a dc_motor ({what} = {want:.6g}): leave it out (got {value:g})")
    return want


def k_u_field(description: str):
    """K_U: given for gain, lag and lag_zero actuators; for a dc_motor amp_gain x a."""
    return Field(None, ge=0.01, le=1000, validate_default=True, description=description)


def k_u_of(value, info: ValidationInfo):
    """K_U validated: a dc_motor's from its motor, any other model's required."""
    if info.data.get("model") != "dc_motor":
        if value is None:
            raise ValueError("missing field (force per command volt, N/V)")
        return value
    gain = info.data.get("amp_gain")
    return derived(value, info, "amp_gain x a", lambda m: (1.0 if gain is None else gain) * m.force_per_volt())
