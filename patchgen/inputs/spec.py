"""The design spec: what a user writes (TOML) to describe plant, sensors, actuator, weights,
integral states, estimator and target machine. Units are documented in docs/spec.md.

The spec's [actuator] is the *design model*; what the patch meets on the bench is the bench
profile named by ``bench`` (patchgen/profiles/benches/), kept apart on purpose.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, PrivateAttr, field_validator

from patchgen.inputs.drive_fields import LAG_MODELS, DriveFields, k_u_field, k_u_of
from patchgen.inputs.errors import Cure, InputError
from patchgen.inputs.fields import InputModel, Int, Real, bounded, zero_or_at_least
from patchgen.inputs.resources import resolve
from patchgen.inputs.spec_tables import PlantSpec, RotaryPlantSpec, RotarySensorSpec, SensorSpec
from patchgen.inputs.validation import read_toml, validate
from patchgen.plant.plant_model import CART, DEFAULT, PLANT_MODELS, ROTARY, PlantModel

# weights: Q entries and R within WEIGHT_RANGE (a weight is relative, and a spread of more than
# 1e16 between them leaves the Riccati solver little but rounding error); Bryson excursions
# within EXCURSION_RANGE (their squares' inverses then stay inside WEIGHT_RANGE)
WEIGHT_RANGE = (1e-8, 1e8)
EXCURSION_RANGE = (1e-4, 1e4)
NOISE_MAX = 1e12  # entries of the estimator's W and V
GAMMA_MAX = 1e6  # entries of the noise input matrix Gamma
MIN_V_EIGENVALUE = 1e-12  # the measurement noise is inverted: it must be clear of singular
RHO_LIMIT = 1e12  # LTR factor on W and its cap: the ceiling of the noise entries it scales (NOISE_MAX)
MAX_ORDER = 20  # compensator states: beyond any design patchgen builds (at most 7 model states)
MAX_UNITS = 16  # machines slaved together: the cap a machine profile's max_units has too
SYMMETRY_TOL = 1e-12  # relative: a full Q this close to its transpose is symmetric (rounding in the file)
PSD_TOL = 1e-10  # relative: an eigenvalue of Q above -1e-10 x its largest entry counts as 0
Entry = Annotated[Real, Field(ge=-NOISE_MAX, le=NOISE_MAX)]
Weight = Annotated[Real, Field(ge=-WEIGHT_RANGE[1], le=WEIGHT_RANGE[1])]


MIN_LAG_S = 1e-3  # a lag shorter than 1 ms is a gain to the loop, and would set a needlessly fine step


class ActuatorSpec(DriveFields):
    """The actuator model the design assumes: force per command volt, with optional lag, or a DC
    motor driven by voltage (its figures in patchgen.inputs.drive_fields; K_U then follows)."""

    K_U: Real | None = k_u_field("N/V (N s/V for lag_zero; a dc_motor's follows from the motor)")
    tau: Annotated[Real, zero_or_at_least(MIN_LAG_S)] = bounded(0, 10, default=0.0,
                                                               description="lag time constant, s")
    state_scale: Real = bounded(1e-3, 1e3, default=1.0, description="actuator state = F_U / state_scale")
    zero: Real = bounded(0, 1e3, default=1e-5, description="lag_zero: F/F_cmd = (s + zero)/(tau s + 1), rad/s; "
                         "a zero exactly at 0 cancels the cart's position pole (not stabilisable)")
    dead_zone_V: Real = bounded(0, 100, default=0.0, description="not seen by a linear design; reported")

    k_u_check = field_validator("K_U", mode="after")(k_u_of)


class WeightsSpec(InputModel):
    """LQR weights: Q (diagonal by state name, or a full matrix in state order) and R (per newton
    squared) or R_V (per command volt squared, as a lab that drives its cart by voltage states it:
    R = R_V / K_U^2 with the design's K_U), or Bryson's maximum excursions (eq. 4.9-4.10)."""

    Q: dict[str, Real] | list[list[Weight]] | None = None
    R: Real | None = None
    R_V: Real | None = Field(default=None, description="1/V^2: the control weight per command volt squared")
    bryson: dict[str, Real] | None = None


class IntegratorsSpec(InputModel):
    """Which integral states the design adds (thesis 4.3: integral of s, of theta)."""

    int_s: bool = False
    int_theta: bool = False
    int_s_leak: Real = bounded(0, 1, default=2e-5, description="1/s, keeps the Riccati solver off the axis")
    int_theta_leak: Real = bounded(0, 1, default=1e-5, description="1/s")


class EstimatorSpec(InputModel):
    """How the unmeasured states are obtained: none, a differentiator, a reduced observer or a Kalman estimator."""

    kind: Literal["none", "differentiator", "filtered_differentiator", "reduced_observer", "kalman"] = "none"
    W: Entry | list[list[Entry]] = 1.0
    V: list[Entry] | list[list[Entry]] = [1.0, 1.0, 1.0]
    Gamma: Literal["B"] | list[Annotated[Real, Field(ge=-GAMMA_MAX, le=GAMMA_MAX)]] | list[
        list[Annotated[Real, Field(ge=-GAMMA_MAX, le=GAMMA_MAX)]]] = "B"
    rho: Annotated[Real, Field(gt=0, le=RHO_LIMIT)] | Literal["auto"] = 1.0
    rho_max: Real = bounded(0, RHO_LIMIT, open_lo=True, default=RHO_LIMIT)
    rolloff_s: Real | None = bounded(1e-4, 1, default=None, description="differentiator roll-off, s "
                                     "(filtered_differentiator: none = chosen from the bench noise)")
    observer_pole: Real | None = bounded(1e-2, 1e4, default=None, description="reduced_observer: error decay "
                                         "rate, rad/s (none = chosen from the bench noise)")


class PatchSpec(InputModel):
    """Choices for the patch: slaved units and what to do with a coefficient below the dial's resolution."""

    units: Annotated[Int, Field(ge=1, le=MAX_UNITS)] | Literal["auto"] = Field(
        default=1, description="machines slaved together: a number, or \"auto\" for the fewest that fit "
        "(at most max_units)")
    max_units: Annotated[Int, Field(ge=1, le=MAX_UNITS)] | None = Field(
        default=None, description="the most slaved units \"auto\" may take (none: the machine profile's max_units)")
    realization: Literal["states", "compensator"] = Field(
        default="states", description="an estimator wired as its states then state feedback, or the whole "
        "compensator as one system in the form that fits the machine best")
    order: Annotated[Int, Field(ge=1, le=MAX_ORDER)] | Literal["full"] = Field(
        default="full", description="compensator: states in all (the integral part's one among them), or "
        "\"full\" for the minimal realisation")
    form: Literal["auto", "modal", "observer", "balanced"] = Field(
        default="auto", description="compensator: the state-space form, or \"auto\" for the cheapest that fits")
    reduction: Literal["auto", "truncate", "residualise"] = Field(
        default="auto", description="compensator below full order: balanced truncation, balanced singular "
        "perturbation, or \"auto\" for the one that fits best")
    below_resolution: Literal["round", "minimum", "omit"] = Field(
        default="round", description="a coefficient below the pot resolution: round to the dial, "
        "set the minimum dial value, or leave the signal out")
    scaling: Literal["snr", "sensors"] = Field(
        default="snr", description="the law as its states: each internal signal's voltage raised as far "
        "as the bench Monte Carlo's envelope and the machine's inputs and dial allow (\"snr\"), or kept at "
        "its sensor constants (\"sensors\")")


class DesignSpec(InputModel):
    """A whole design spec as read from TOML: plant, sensors, actuator, weights, estimator, machine and bench."""

    name: str
    description: str = ""
    source: str = ""
    machine: str = "gp6"
    bench: str = "uw-1991"
    plant: PlantSpec
    sensors: SensorSpec
    actuator: ActuatorSpec
    weights: WeightsSpec
    integrators: IntegratorsSpec = IntegratorsSpec()
    estimator: EstimatorSpec = EstimatorSpec()
    patch: PatchSpec = PatchSpec()

    _path: str = PrivateAttr(default="<spec>")

    @property
    def plant_model(self) -> PlantModel:
        """The plant the spec describes (its ``[plant] model``): what every layer asks for the
        plant's states, parameters and linear model."""
        return PLANT_MODELS[self.plant.model]

    @property
    def path(self) -> str:
        """The file the spec was read from (or a label for a spec built in code)."""
        return self._path

    def states(self) -> list[str]:
        """State names in order: plant states, integral states, actuator state."""
        out = list(self.plant_model.state_names)
        if self.integrators.int_s:
            out.append("int_s")
        if self.integrators.int_theta:
            out.append("int_theta")
        if self.actuator.model in LAG_MODELS:
            out.append("actuator")
        return out

    def error(self, field: str, message: str, cure: Cure | None = None) -> InputError:
        """An InputError naming this spec's file and ``field`` (to raise; a design stage's refusal),
        with the change that lifts it when the stage found one."""
        return InputError(self._path, field, message, cure)

    def changed(self, field: str, value) -> DesignSpec:
        """This spec with one field of one table set (``estimator.rolloff_s``), the same file named:
        a change a refusing stage tries before it suggests it."""
        table, key = field.split(".")
        return self.model_copy(update={table: getattr(self, table).model_copy(update={key: value})})

    def theta_dot_scale(self) -> float:
        """V per rad/s of the voltage carrying theta_dot: the spec's, else the theta sensor's."""
        return self.rate_scale(self.plant_model.angle_rate)

    def rate_scale(self, rate: str) -> float:
        """V per SI unit of the voltage carrying a rate: its own constant (a tachometer's, or the
        scale the spec gives a rate the patch finds), else its position's x 1 s."""
        own = getattr(self.sensors, rate)
        return own if own is not None else getattr(self.sensors, self.plant_model.position_of[rate])


class RotaryDesignSpec(DesignSpec):
    """A design spec for the rotary pendulum (``[plant] model = "rotary-pendulum"``): its plant
    and sensor tables; the rest as a cart's."""

    plant: RotaryPlantSpec
    sensors: RotarySensorSpec


SPEC_TYPES = {CART.name: DesignSpec, ROTARY.name: RotaryDesignSpec}  # a spec's type, by its plant model


def spec_type(data: dict, source: str) -> type[DesignSpec]:
    """The spec type for a TOML document, by its ``[plant] model`` (the cart-pendulum when left out).

    Raises
    ------
    InputError
        A model that is not a plant model patchgen knows.
    """
    table = data.get("plant")
    name = table.get("model", DEFAULT) if isinstance(table, dict) else DEFAULT
    if not isinstance(name, str) or name not in SPEC_TYPES:
        raise InputError(source, "plant.model", f"unknown plant model {name!r} (known: {', '.join(SPEC_TYPES)})")
    return SPEC_TYPES[name]


def load_spec(path: str | Path) -> DesignSpec:
    """Read and fully check a design spec.

    Parameters
    ----------
    path : str or Path
        A spec file, or a shipped design by name (``bench-recommended``).

    Returns
    -------
    DesignSpec
        The checked spec; its ``path`` is ``path`` as given.

    Raises
    ------
    InputError
        Any problem with the file or a field, naming both.
    """
    data = read_toml(resolve("design", path))
    spec = validate(spec_type(data, str(path)), data, str(path))
    spec._path = str(path)
    check_spec(spec)
    return spec


def matrix(rows: list[list[float]], field: str, err) -> np.ndarray:
    """A list of rows as a 2-D array; an empty or ragged matrix is named at the row at fault.

    Parameters
    ----------
    rows : list of list of float
        The matrix as the TOML file gives it.
    field : str
        Its field path, for the error.
    err : callable
        ``err(field, message)`` builds the error to raise (e.g. ``DesignSpec.error``).

    Returns
    -------
    ndarray
        The matrix as floats.
    """
    if not rows or not rows[0]:
        raise err(field, "an empty matrix")
    for i, row in enumerate(rows):
        if len(row) != len(rows[0]):
            raise err(f"{field}[{i}]", f"has {len(row)} values where row 0 has {len(rows[0])} "
                                       "(a matrix needs rows of one length)")
    return np.array(rows, dtype=float)


def _in_range(value: float, field: str, bounds: tuple[float, float], what: str, err) -> None:
    lo, hi = bounds
    if not lo <= value <= hi:
        raise err(field, f"{what} must be positive, between {lo:g} and {hi:g} (got {value:g})")


def check_spec(spec: DesignSpec) -> None:
    """Checks that need more than one field: weights against the states, estimator shapes.

    Parameters
    ----------
    spec : DesignSpec
        A spec whose fields are each valid on their own.

    Raises
    ------
    InputError
        The first problem, naming the field to fix.
    """
    states = spec.states()
    w = spec.weights
    err = spec.error
    if w.bryson is not None:
        if w.Q is not None or w.R is not None or w.R_V is not None:
            raise err("weights", "give either Q and R (or R_V) or bryson, not both")
        for name, sigma in w.bryson.items():
            if name != "u" and name not in states:
                raise err(f"weights.bryson.{name}", f"unknown state name (states: {', '.join(states)})")
            _in_range(sigma, f"weights.bryson.{name}", EXCURSION_RANGE, "a maximum excursion", err)
        if "u" not in w.bryson:
            raise err("weights.bryson.u", "missing field (maximum control force, N)")
    else:
        if w.Q is None:
            raise err("weights.Q", "missing field (or give weights.bryson)")
        if w.R is None and w.R_V is None:
            raise err("weights.R", "missing field (or R_V, per command volt squared)")
        if w.R is not None and w.R_V is not None:
            raise err("weights.R_V", "give R (per newton squared) or R_V (per command volt squared), not both")
        if isinstance(w.Q, dict):
            for name, q in w.Q.items():
                if name not in states:
                    raise err(f"weights.Q.{name}", f"unknown state name (states: {', '.join(states)})")
                if not (q == 0 or WEIGHT_RANGE[0] <= q <= WEIGHT_RANGE[1]):
                    raise err(f"weights.Q.{name}", f"must be >= 0: 0, or between {WEIGHT_RANGE[0]:g} and "
                                                   f"{WEIGHT_RANGE[1]:g} (got {q:g})")
        else:
            Q = matrix(w.Q, "weights.Q", err)
            n = len(states)
            if Q.shape != (n, n):
                raise err("weights.Q", f"must be {n}x{n} for states {', '.join(states)} "
                                       f"(got {Q.shape[0]}x{Q.shape[1]})")
            tiny = np.argwhere((Q != 0) & (np.abs(Q) < WEIGHT_RANGE[0]))
            if len(tiny):
                i, j = tiny[0]
                raise err(f"weights.Q[{i}][{j}]", f"a weight is 0 or at least {WEIGHT_RANGE[0]:g} in magnitude "
                                                  f"(got {Q[i, j]:g})")
            if not np.allclose(Q, Q.T, atol=SYMMETRY_TOL * max(1.0, np.abs(Q).max())):
                raise err("weights.Q", "must be symmetric")
            if np.linalg.eigvalsh(Q).min() < -PSD_TOL * max(1.0, np.abs(Q).max()):
                raise err("weights.Q", "must be positive semi-definite")
        if w.R is not None:
            _in_range(w.R, "weights.R", WEIGHT_RANGE, "a control weight", err)
        else:
            _in_range(w.R_V, "weights.R_V", WEIGHT_RANGE, "a control weight", err)
            _in_range(w.R_V / spec.actuator.K_U ** 2, "weights.R_V", WEIGHT_RANGE,
                      f"a control weight once divided by K_U^2 = {spec.actuator.K_U ** 2:g}", err)
    a = spec.actuator
    if a.model in LAG_MODELS and a.tau <= 0:
        raise err("actuator.tau", f"a {a.model} actuator needs a positive time constant (at least {MIN_LAG_S:g} s)")
    if a.model == "dc_motor" and a.tau > 0:
        raise err("actuator.tau", "a dc_motor's design model has no lag: its current follows the voltage (state "
                                  "the armature's inductance L_m in the bench profile, whose simulation has it)")
    plant = spec.plant_model
    read = spec.sensors.measured
    for q in plant.measurable:
        if read.count(q) > 1:
            raise err("sensors.measured", f"names {q} twice")
    for p in plant.rate_of:
        if p not in read:
            raise err("sensors.measured", f"must include {p}: a position is read on its sensor (the patch finds "
                                          "a rate from its position, not the other way round)")
    if len(spec.sensors.derived()) > 1 and spec.estimator.kind == "reduced_observer":
        rate = plant.rate_of[plant.position]
        raise err("estimator.kind", f"the reduced observer is built for a measured {rate}: with {rate} left out of "
                                    "sensors.measured, choose \"differentiator\", \"filtered_differentiator\" or "
                                    "\"kalman\"")
    if spec.estimator.kind == "kalman":
        _check_kalman(spec, len(plant.states) + (1 if a.model in LAG_MODELS else 0))
    if plant is ROTARY:
        _check_rotary(spec)


def _check_rotary(spec: DesignSpec) -> None:
    """What the rotary pendulum's design does not take (yet): a force drive, integral states."""
    a = spec.actuator
    if a.model in ("dc_motor", "lag_zero"):
        raise spec.error("actuator.model", f'"{a.model}" drives a cart: the rotary pendulum\'s motor is its plant\'s '
                         '([plant] R_m, k_t, k_m), so its actuator is the amplifier, "gain" (or "lag"), K_U in motor '
                         'volts per command volt')
    for name in ("int_s", "int_theta"):
        if getattr(spec.integrators, name):
            raise spec.error(f"integrators.{name}", "integral states are built for the cart-pendulum only: leave it "
                                                    "false for the rotary pendulum")


def _check_kalman(spec: DesignSpec, n_est: int) -> None:
    """Shapes and definiteness of the Kalman estimator's noise model."""
    e = spec.estimator
    err = spec.error
    W = np.atleast_2d(e.W) if isinstance(e.W, float) else matrix(e.W, "estimator.W", err)
    if isinstance(e.Gamma, str):
        n_w = 1
    elif not e.Gamma:
        raise err("estimator.Gamma", "an empty matrix")
    else:
        G = np.array(e.Gamma, dtype=float)[:, None] if not isinstance(e.Gamma[0], list) else \
            matrix(e.Gamma, "estimator.Gamma", err)
        if G.shape[0] != n_est:
            raise err("estimator.Gamma", f"needs {n_est} rows (estimated states), got {G.shape[0]}")
        n_w = G.shape[1]
    if W.shape != (n_w, n_w):
        raise err("estimator.W", f"must be {n_w}x{n_w} to match Gamma (got {W.shape[0]}x{W.shape[1]})")
    if np.linalg.eigvalsh((W + W.T) / 2).min() < 0:
        raise err("estimator.W", "must be positive semi-definite")
    if not W.any():
        raise err("estimator.W", "W = 0 puts no process noise on the model: the filter could not move the cart's "
                                 "pole at the origin (W must not be 0)")
    if not isinstance(e.Gamma, str) and not G.any():
        raise err("estimator.Gamma", "a zero matrix puts no process noise on the model: the filter could not move "
                                     "the cart's pole at the origin")
    if e.rho == "auto" and e.rho_max < 1:
        raise err("estimator.rho_max", f"rho = 'auto' searches rho = 1, 10, 100, ...: rho_max = {e.rho_max:g} would "
                                       "stop it before its first step (at least 1, or give rho itself)")
    if e.V and isinstance(e.V[0], list):
        V = matrix(e.V, "estimator.V", err)
    else:
        V = np.diag(np.array(e.V, dtype=float)) if e.V else np.zeros((0, 0))
    read = spec.sensors.read()
    if V.shape != (len(read), len(read)):
        raise err("estimator.V", f"must be {len(read)} values or {len(read)}x{len(read)} for the measured "
                                 f"{', '.join(read)}")
    if np.linalg.eigvalsh((V + V.T) / 2).min() < MIN_V_EIGENVALUE:
        raise err("estimator.V", f"must be positive definite (smallest eigenvalue at least {MIN_V_EIGENVALUE:g})")
