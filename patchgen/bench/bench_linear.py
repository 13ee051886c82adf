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
from patchgen.plant.cart_pendulum import POSITION, POSITION_OF, RATE_OF
from patchgen.plant.drive import driven, with_rotor
from patchgen.plant.equations import PLANT_STATES, PlantParams, linear_matrices
from patchgen.profiles.bench import BenchProfile


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


def bench_plant(net: Netlist, plant: PlantParams, bench: BenchProfile, lagged: bool = True) -> BenchPlant:
    """The bench from u_c to the patch's sensor voltages, linearised about upright.

    Parameters
    ----------
    net : Netlist
        The patch: which sensors it reads.
    plant : PlantParams
        The plant's mechanism (the drive is the bench's).
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
    motor = motor_of(bench.actuator)
    lag = actuator_lag(bench) if lagged else None
    K_U = bench.actuator.K_U
    emf = 0.0
    if motor is not None and lag is not None:
        plant, emf = with_rotor(plant, motor), motor.back_emf_damping()  # the back-EMF acts inside the lag
    elif motor is not None:
        plant = driven(plant, motor)
    Ap, Bp = linear_matrices(plant)
    filters = bench.sensors.filters()
    order = sorted(filters)
    na = 0 if lag is None else 1
    n = 4 + na + 2 * len(order)
    A, B = np.zeros((n, n)), np.zeros((n, 1))
    A[:4, :4] = Ap
    if lag is None:
        B[:4] = Bp * K_U
    else:  # F' = (K_U u_c - b s_dot - F) / lag
        A[:4, 4:5] = Bp
        A[4, 4] = -1.0 / lag
        A[4, PLANT_STATES.index(RATE_OF[POSITION])] = -emf / lag
        B[4, 0] = K_U / lag
    names = list(PLANT_STATES) + ([] if lag is None else ["actuator"])
    for k, q in enumerate(order):  # y'' = wn^2 (x - y) - 2 zeta wn y'; the reading is y'
        f, i = filters[q], 4 + na + 2 * k
        A[i, i + 1] = 1.0
        A[i + 1, PLANT_STATES.index(POSITION_OF[q])] = f.wn_rad_s ** 2
        A[i + 1, i] = -f.wn_rad_s ** 2
        A[i + 1, i + 1] = -2.0 * f.zeta * f.wn_rad_s
        names += [f"{q} filter", f"{q} filter rate"]
    ids = tuple(s.id for s in net.sensors)
    C = np.zeros((len(ids), n))
    for r, (sensor, gain) in enumerate(zip(net.sensors, sensor_constants(net, bench))):
        q = sensor.quantity
        col = 4 + na + 2 * order.index(q) + 1 if q in filters else PLANT_STATES.index(q)
        C[r, col] = gain
    return BenchPlant(A, B, C, tuple(names), ids, lag)
