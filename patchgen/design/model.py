"""The design's linear model: plant (eq. 2.28) plus optional integral states and actuator state.

State order (conventions.md): the plant's (s, theta, s_dot, theta_dot for the cart; alpha, theta,
alpha_dot, theta_dot for the rotary pendulum), [int_s], [int_theta], [actuator]. The input is the
plant's (the cart's force u in N; the rotary arm's motor volts); u = -K x.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from patchgen.inputs.drive_fields import LAG_MODELS, motor_of
from patchgen.inputs.spec import DesignSpec
from patchgen.plant.drive import driven
from patchgen.plant.equations import PlantParams
from patchgen.plant.plant_model import PlantModel
from patchgen.plant.rotary_equations import RotaryParams


@dataclass(frozen=True)
class LinearModel:
    """The design model x' = A x + B u, y = C x, u the plant's input (the cart's force in N, the
    rotary arm's motor volts), states named."""

    states: tuple[str, ...]
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray  # the measured outputs (the cart's s, theta, s_dot)
    measured: tuple[str, ...]
    n_plant: int  # plant states (4)
    estimated: tuple[str, ...]  # states a Kalman estimator carries: plant + actuator
    plant: PlantModel  # whose states the first n_plant are (their roles: position, angle, rates)

    def index(self, name: str) -> int:
        """The position of a named state."""
        return self.states.index(name)

    def submodel(self, names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A, B, C restricted to the named states (for the estimator model)."""
        idx = [self.index(n) for n in names]
        return self.A[np.ix_(idx, idx)], self.B[idx, :], self.C[:, idx]


def plant_params(spec: DesignSpec) -> PlantParams | RotaryParams:
    """The spec's plant figures as the plant equations take them (the cart's mechanism alone: a
    motor's rotor and back-EMF are the drive's, patchgen.plant.drive; the rotary arm's motor is its
    plant's own)."""
    return spec.plant_model.params(spec.plant.model_dump())


def design_plant(spec: DesignSpec, plant: PlantParams | RotaryParams | None = None) -> PlantParams | RotaryParams:
    """The plant the design's force acts on: the mechanism with the spec's drive folded in (a
    dc_motor's rotor mass and back-EMF damping; no change for a force actuator)."""
    return driven(plant or plant_params(spec), motor_of(spec.actuator))


def build_model(spec: DesignSpec, plant: PlantParams | RotaryParams | None = None) -> LinearModel:
    """Assemble A, B, C for the spec's states (optionally for a perturbed plant: its mechanism,
    the spec's drive folded in as for the nominal one)."""
    model = spec.plant_model
    Ap, Bp = model.linear(design_plant(spec, plant))
    states = spec.states()
    n, n_p = len(states), len(model.states)
    A = np.zeros((n, n))
    B = np.zeros((n, 1))
    A[:n_p, :n_p] = Ap
    integ = spec.integrators
    if integ.int_s:
        i = states.index("int_s")
        A[i, states.index(model.position)] = 1.0
        A[i, i] = -integ.int_s_leak
    if integ.int_theta:
        i = states.index("int_theta")
        A[i, states.index(model.angle)] = 1.0
        A[i, i] = -integ.int_theta_leak
    act = spec.actuator
    if act.model not in LAG_MODELS:  # a gain, or a dc_motor: F = K_U u_c on the driven plant
        B[:n_p] = Bp
    else:
        # x_a' = -x_a/tau + u/(tau*scale); lag: F = scale*x_a;
        # lag_zero, F/u = (s + z)/(tau s + 1): F = u/tau + (z - 1/tau)*scale*x_a
        i = states.index("actuator")
        tau, scale = act.tau, act.state_scale
        A[i, i] = -1.0 / tau
        B[i, 0] = 1.0 / (tau * scale)
        if act.model == "lag":
            A[:n_p, i] = Bp[:, 0] * scale
        else:
            A[:n_p, i] = Bp[:, 0] * (act.zero - 1.0 / tau) * scale
            B[:n_p] = Bp / tau
    read = spec.sensors.read()
    C = np.zeros((len(read), n))
    for r, name in enumerate(read):
        C[r, states.index(name)] = 1.0
    estimated = tuple(s for s in states if not s.startswith("int_"))
    return LinearModel(tuple(states), A, B, C, read, n_p, estimated, model)


def open_loop_poles(model: LinearModel) -> np.ndarray:
    """Eigenvalues of the design model's A, sorted by real then imaginary part."""
    return _sorted(np.linalg.eigvals(model.A))


def plant_zeros(spec: DesignSpec, output: str) -> np.ndarray:
    """Finite transmission zeros of output/u for the plant alone (the cart's eq. 2.28)."""
    model = spec.plant_model
    Ap, Bp = model.linear(design_plant(spec))
    C = np.zeros((1, len(model.states)))
    C[0, model.state_names.index(output)] = 1.0
    return _sorted(transmission_zeros(Ap, Bp, C))


def transmission_zeros(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Finite zeros of a SISO (A, B, C, 0): generalised eigenvalues of the Rosenbrock pencil."""
    n = A.shape[0]
    M = np.block([[A, B], [C, np.zeros((1, 1))]])
    N = np.zeros((n + 1, n + 1))
    N[:n, :n] = np.eye(n)
    z = sla.eigvals(M, N)
    return z[np.isfinite(z) & (np.abs(z) < 1e12)]


def _sorted(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=complex)
    v = np.where(np.abs(v.imag) < 1e-12 * np.maximum(1.0, np.abs(v)), v.real + 0j, v)
    return v[np.lexsort((v.imag, v.real))]
