"""The bench linearised about upright, from the command voltage u_c to the voltages the patch
reads: the plant with its drive (a DC motor's rotor and back-EMF), the actuator's lag, and the
sensors as the bench has them (a velocity through its filter). Encoder counts, the dead zone and
the limits are not linear; the simulation has them.

What the wired loop's poles and margins on the bench (patchgen.bench.diagnosis) close the patch
around: the same bench the simulator runs, so that a velocity filter that takes a patch's phase
margin from 58 to 18 deg shows in its margins as in its runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from patchgen.bench.circuit import sensor_constants
from patchgen.inputs.drive_fields import LAG_MODELS, motor_of
from patchgen.patch.netlist import Netlist
from patchgen.plant.drive import driven, with_rotor
from patchgen.plant.equations import PlantParams
from patchgen.plant.plant_model import model_of
from patchgen.plant.rotary_equations import RotaryParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.measured_plant import as_on_bench


@dataclass(frozen=True)
class BenchPlant:
    """x' = A x + B u_c, and the sensors' voltages y = C x (one row per sensor, by id)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    states: tuple[str, ...]
    sensors: tuple[str, ...]
    lag_s: float | None  # the actuator's lag in the model (None: none)

    def rows(self, ids: tuple[str, ...]) -> np.ndarray:
        """C for the named sensors, in that order."""
        return self.C[[self.sensors.index(i) for i in ids]]


def actuator_lag(bench: BenchProfile) -> float | None:
    """The bench actuator's lag (s): a lag model's tau, a motor's electrical lag; None for none."""
    act = bench.actuator
    motor = motor_of(act)
    if motor is not None:
        return motor.electrical_lag() or None
    return act.tau if act.model in LAG_MODELS and act.tau > 0 else None


def bench_plant(net: Netlist, plant: PlantParams | RotaryParams, bench: BenchProfile,
                lagged: bool = True) -> BenchPlant:
    """The bench from u_c to the patch's sensor voltages, linearised about upright.

    Parameters
    ----------
    net : Netlist
        The patch: which sensors it reads.
    plant : PlantParams or RotaryParams
        The plant's mechanism (a cart's drive is the bench's; a rotary arm's motor is its own).
    bench : BenchProfile
        Actuator (gain, lag, motor), sensor constants and filters.
    lagged : bool
        Keep the actuator's lag (False: the force follows the command at once, as an ideal
        actuator would; a motor's back-EMF and rotor stay, they are the plant's).

    Returns
    -------
    BenchPlant
        States: the plant's, the actuator's force when it lags, two per filtered velocity.
    """
    plant = as_on_bench(plant, bench)
    motor = motor_of(bench.actuator)
    lag = actuator_lag(bench) if lagged else None
    K_U = bench.actuator.K_U
    emf = 0.0
    if motor is not None and lag is not None:
        plant, emf = with_rotor(plant, motor), motor.back_emf_damping()  # the back-EMF acts inside the lag
    elif motor is not None:
        plant = driven(plant, motor)
    pm = model_of(plant)
    Ap, Bp = pm.linear(plant)
    states, n_p = pm.state_names, len(pm.states)
    filters = bench.sensors.filters()
    order = sorted(filters)
    na = 0 if lag is None else 1
    n = n_p + na + 2 * len(order)
    A, B = np.zeros((n, n)), np.zeros((n, 1))
    A[:n_p, :n_p] = Ap
    if lag is None:
        B[:n_p] = Bp * K_U
    else:  # F' = (K_U u_c - b s_dot - F) / lag
        A[:n_p, n_p:n_p + 1] = Bp
        A[n_p, n_p] = -1.0 / lag
        A[n_p, states.index(pm.rate_of[pm.position])] = -emf / lag
        B[n_p, 0] = K_U / lag
    names = list(states) + ([] if lag is None else ["actuator"])
    for k, q in enumerate(order):  # y'' = wn^2 (x - y) - 2 zeta wn y'; the reading is y'
        f, i = filters[q], n_p + na + 2 * k
        A[i, i + 1] = 1.0
        A[i + 1, states.index(pm.position_of[q])] = f.wn_rad_s ** 2
        A[i + 1, i] = -f.wn_rad_s ** 2
        A[i + 1, i + 1] = -2.0 * f.zeta * f.wn_rad_s
        names += [f"{q} filter", f"{q} filter rate"]
    ids = tuple(s.id for s in net.sensors)
    C = np.zeros((len(ids), n))
    for r, (sensor, gain) in enumerate(zip(net.sensors, sensor_constants(net, bench))):
        q = sensor.quantity
        col = n_p + na + 2 * order.index(q) + 1 if q in filters else states.index(q)
        C[r, col] = gain
    return BenchPlant(A, B, C, tuple(names), ids, lag)
