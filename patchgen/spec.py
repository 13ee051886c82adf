"""The design spec: what a user writes (TOML) to describe plant, sensors, actuator, weights,
integral states, estimator and target machine. Units are documented in docs/spec.md.

The spec's [actuator] is the *design model*; what the patch meets on the bench is the bench
profile named by ``bench`` (patchgen/benches/), kept apart on purpose.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr

from .errors import InputError
from .resources import resolve
from .validation import read_toml, validate

PLANT_STATES = ("s", "theta", "s_dot", "theta_dot")
MEASURED = ("s", "theta", "s_dot")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class PlantSpec(_Strict):
    """Table B.1 parameters, SI units."""

    M: float = Field(gt=0, description="cart mass, kg")
    m: float = Field(gt=0, description="pendulum mass, kg")
    l: float = Field(gt=0, description="effective pendulum length, m")
    g: float = Field(default=9.807, gt=0, description="gravity, m/s^2")
    b_VF: float = Field(ge=0, description="cart viscous friction, kg/s")
    c: float = Field(ge=0, description="pendulum rotational friction, kg m^2/s")
    d: float = Field(default=1.090, gt=0, description="usable track length between the switches, m")


class SensorSpec(_Strict):
    """Sensor constants (table A.2), volts per SI unit. theta_dot is the scale of the voltage
    that carries theta_dot on the machine (differentiator or estimator output)."""

    s: float = Field(gt=0, description="V/m")
    theta: float = Field(gt=0, description="V/rad")
    s_dot: float = Field(gt=0, description="V/(m/s)")
    theta_dot: float | None = Field(default=None, gt=0, description="V/(rad/s); default theta x 1 s")


class ActuatorSpec(_Strict):
    """The actuator model the design assumes: force per command volt, with optional lag."""

    model: Literal["gain", "lag", "lag_zero"] = "gain"
    K_U: float = Field(gt=0, description="N/V (N s/V for lag_zero)")
    tau: float = Field(default=0.0, ge=0, description="lag time constant, s")
    state_scale: float = Field(default=1.0, gt=0, description="actuator state = F_U / state_scale")
    zero: float = Field(default=1e-5, ge=0, description="lag_zero: F/F_cmd = (s + zero)/(tau s + 1), rad/s; "
                        "a zero exactly at 0 cancels the cart's position pole (not stabilisable)")
    dead_zone_V: float = Field(default=0.0, ge=0, description="not seen by a linear design; reported")


class WeightsSpec(_Strict):
    """LQR weights: Q (diagonal by state name, or a full matrix in state order) and R, or
    Bryson's maximum excursions (eq. 4.9-4.10)."""

    Q: dict[str, float] | list[list[float]] | None = None
    R: float | None = None
    bryson: dict[str, float] | None = None


class IntegratorsSpec(_Strict):
    int_s: bool = False
    int_theta: bool = False
    int_s_leak: float = Field(default=2e-5, ge=0, description="1/s, keeps the Riccati solver off the axis")
    int_theta_leak: float = Field(default=1e-5, ge=0, description="1/s")


class EstimatorSpec(_Strict):
    kind: Literal["none", "differentiator", "filtered_differentiator", "reduced_observer", "kalman"] = "none"
    W: float | list[list[float]] = 1.0
    V: list[float] | list[list[float]] = [1.0, 1.0, 1.0]
    Gamma: Literal["B"] | list[float] | list[list[float]] = "B"
    rho: float | Literal["auto"] = 1.0
    rho_max: float = Field(default=1e12, gt=0)
    rolloff_s: float | None = Field(default=None, gt=0, description="differentiator roll-off, s "
                                    "(filtered_differentiator: none = chosen from the bench noise)")
    observer_pole: float | None = Field(default=None, gt=0, description="reduced_observer: error decay "
                                        "rate, rad/s (none = chosen from the bench noise)")


class PatchSpec(_Strict):
    units: int | Literal["auto"] = Field(
        default=1, description="machines slaved together: a number, or \"auto\" for the fewest that fit "
        "(at most the profile's max_units)")
    below_resolution: Literal["round", "minimum", "omit"] = Field(
        default="round", description="a coefficient below the pot resolution: round to the dial, "
        "set the minimum dial value, or leave the signal out")


class DesignSpec(_Strict):
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
    def path(self) -> str:
        return self._path

    def states(self) -> list[str]:
        """State names in order: plant states, integral states, actuator state."""
        out = list(PLANT_STATES)
        if self.integrators.int_s:
            out.append("int_s")
        if self.integrators.int_theta:
            out.append("int_theta")
        if self.actuator.model != "gain":
            out.append("actuator")
        return out

    def error(self, field: str, message: str) -> InputError:
        return InputError(self._path, field, message)

    def theta_dot_scale(self) -> float:
        return self.sensors.theta_dot if self.sensors.theta_dot is not None else self.sensors.theta


def load_spec(path: str | Path) -> DesignSpec:
    """Read and fully check a design spec (a file, or a shipped design by name such as
    ``bench-recommended``); every problem is an InputError naming file and field."""
    spec = validate(DesignSpec, read_toml(resolve("design", path)), str(path))
    spec._path = str(path)
    check_spec(spec)
    return spec


def q_matrix(spec: DesignSpec) -> np.ndarray:
    states = spec.states()
    n = len(states)
    w = spec.weights
    if w.bryson is not None:
        Q = np.zeros((n, n))
        for name, sigma in w.bryson.items():
            if name == "u":
                continue
            Q[states.index(name), states.index(name)] = 1.0 / sigma**2
        return Q
    if isinstance(w.Q, dict):
        Q = np.zeros((n, n))
        for name, q in w.Q.items():
            Q[states.index(name), states.index(name)] = q
        return Q
    return np.array(w.Q, dtype=float)


def r_matrix(spec: DesignSpec) -> np.ndarray:
    w = spec.weights
    if w.bryson is not None:
        return np.array([[1.0 / w.bryson["u"] ** 2]])
    return np.array([[float(w.R)]])


def check_spec(spec: DesignSpec) -> None:
    """Checks that need more than one field: weights against the states, estimator shapes."""
    states = spec.states()
    w = spec.weights
    err = spec.error
    if w.bryson is not None:
        if w.Q is not None or w.R is not None:
            raise err("weights", "give either Q and R or bryson, not both")
        for name, sigma in w.bryson.items():
            if name != "u" and name not in states:
                raise err(f"weights.bryson.{name}", f"unknown state name (states: {', '.join(states)})")
            if not (sigma > 0 and np.isfinite(sigma)):
                raise err(f"weights.bryson.{name}", f"maximum excursion must be positive (got {sigma!r})")
        if "u" not in w.bryson:
            raise err("weights.bryson.u", "missing field (maximum control force, N)")
    else:
        if w.Q is None:
            raise err("weights.Q", "missing field (or give weights.bryson)")
        if w.R is None:
            raise err("weights.R", "missing field")
        if isinstance(w.Q, dict):
            for name, q in w.Q.items():
                if name not in states:
                    raise err(f"weights.Q.{name}", f"unknown state name (states: {', '.join(states)})")
                if not (q >= 0 and np.isfinite(q)):
                    raise err(f"weights.Q.{name}", f"must be >= 0 (got {q!r})")
        else:
            Q = np.array(w.Q, dtype=float)
            n = len(states)
            if Q.shape != (n, n):
                cols = Q.shape[1] if Q.ndim > 1 else 0
                raise err("weights.Q", f"must be {n}x{n} for states {', '.join(states)} (got {Q.shape[0]}x{cols})")
            if not np.allclose(Q, Q.T, atol=1e-12 * max(1.0, np.abs(Q).max())):
                raise err("weights.Q", "must be symmetric")
            if np.linalg.eigvalsh(Q).min() < -1e-10 * max(1.0, np.abs(Q).max()):
                raise err("weights.Q", "must be positive semi-definite")
        if not (w.R > 0 and np.isfinite(w.R)):
            raise err("weights.R", f"must be positive (got {w.R!r})")
    a = spec.actuator
    if a.model != "gain" and a.tau <= 0:
        raise err("actuator.tau", f"a {a.model} actuator needs a positive time constant")
    e = spec.estimator
    if e.kind == "kalman":
        n_est = 4 + (1 if a.model != "gain" else 0)
        W = np.atleast_2d(np.array(e.W, dtype=float))
        if isinstance(e.Gamma, str):
            n_w = 1
        else:
            G = np.array(e.Gamma, dtype=float)
            if G.ndim == 1:
                G = G[:, None]
            if G.shape[0] != n_est:
                raise err("estimator.Gamma", f"needs {n_est} rows (estimated states), got {G.shape[0]}")
            n_w = G.shape[1]
        if W.shape != (n_w, n_w):
            raise err("estimator.W", f"must be {n_w}x{n_w} to match Gamma (got {W.shape[0]}x{W.shape[1]})")
        if np.linalg.eigvalsh((W + W.T) / 2).min() < 0:
            raise err("estimator.W", "must be positive semi-definite")
        V = np.array(e.V, dtype=float)
        V = np.diag(V) if V.ndim == 1 else V
        if V.shape != (3, 3):
            raise err("estimator.V", f"must be 3 values or 3x3 for the measured {', '.join(MEASURED)}")
        if np.linalg.eigvalsh((V + V.T) / 2).min() <= 0:
            raise err("estimator.V", "must be positive definite")
        if isinstance(e.rho, float) and not (e.rho > 0):
            raise err("estimator.rho", f"must be positive or \"auto\" (got {e.rho!r})")
