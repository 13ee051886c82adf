"""The plant interface: what a layer above asks of a pendulum, whichever it is.

Each plant model (patchgen.plant.cart_pendulum, patchgen.plant.rotary_pendulum) describes itself
in module constants; a PlantModel gathers them with the plant's parameter type and its linear
model, so that the spec, the design and the layers after them ask ``spec.plant_model`` rather than
import one plant's names. A spec's ``[plant] model`` names the plant (PLANT_MODELS; the
cart-pendulum when left out, as every spec before the rotary pendulum).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from patchgen.plant import cart_pendulum, rotary_pendulum
from patchgen.plant.cart_pendulum import Parameter, State
from patchgen.plant.equations import PlantParams
from patchgen.plant.equations import linear_matrices as cart_linear
from patchgen.plant.rotary_equations import RotaryParams
from patchgen.plant.rotary_equations import linear_matrices as rotary_linear


@dataclass(frozen=True)
class PlantModel:
    """One plant as every layer above the plant sees it.

    Attributes
    ----------
    name : str
        How a spec's ``[plant] model`` names it.
    what : str
        One line a report prints.
    states : tuple of State
        The plant's states in the order every vector uses: positions, then their rates.
    input, input_unit : str
        What drives the linear model's B (the cart's force F_U in N; the rotary arm's motor volts V_m).
    input_noun, input_what : str
        The input in a word or two (a table's heading) and in full (a control law's note).
    position, angle : str
        The state a travel limit and a step act on; the one a fall is judged on.
    rate_of : mapping of str to str
        Each position-like state's rate.
    measurable : tuple of str
        What a bench's sensors may read (positions always; a rate where a tachometer gives it).
    measured : tuple of str
        What the named bench's sensors read when a spec does not say.
    sensor_labels : mapping of str to str
        What reads each measured quantity on the plant's reference bench, as a sheet names it.
    parameters : tuple of Parameter
        The physical parameters, in the order of the parameter type's fields.
    optional : tuple of str
        Parameters with no default number that may be left out (a rod's inertia: its mass and length's).
    params_type : type
        The frozen dataclass the plant's equations take.
    linear : callable
        params -> (A, B), the linear model about upright for the input ``input``.
    """

    name: str
    what: str
    states: tuple[State, ...]
    input: str
    input_unit: str
    input_noun: str
    input_what: str
    position: str
    angle: str
    rate_of: Mapping[str, str]
    measurable: tuple[str, ...]
    measured: tuple[str, ...]
    sensor_labels: Mapping[str, str]
    parameters: tuple[Parameter, ...]
    params_type: type
    linear: Callable[[Any], tuple[np.ndarray, np.ndarray]] = field(repr=False)
    optional: tuple[str, ...] = ()

    @property
    def state_names(self) -> tuple[str, ...]:
        """The states' names, in order."""
        return tuple(s.name for s in self.states)

    @property
    def units(self) -> dict[str, str]:
        """Each state's SI unit, by name."""
        return {s.name: s.unit for s in self.states}

    @property
    def position_of(self) -> dict[str, str]:
        """The position each rate is the rate of."""
        return {rate: position for position, rate in self.rate_of.items()}

    @property
    def angle_rate(self) -> str:
        """The pendulum's rate: the one a patch always finds, first among the derived rates."""
        return self.rate_of[self.angle]

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The parameters' names, in order."""
        return tuple(p.name for p in self.parameters)

    @property
    def uncertain(self) -> tuple[str, ...]:
        """The parameters a sweep or a sensitivity may put off."""
        return tuple(p.name for p in self.parameters if p.uncertain)

    def params(self, values: Mapping[str, float | None]) -> Any:
        """The plant's parameter object from checked values by name (a spec's ``[plant]``)."""
        known = {f.name for f in fields(self.params_type)}
        return self.params_type(**{k: v for k, v in values.items() if k in known})


CART = PlantModel(
    name="cart-pendulum", what="a pendulum on a cart driven along a track (Shaw's thesis; a Quanser IP02)",
    states=cart_pendulum.STATES, input="F_U", input_unit="N", input_noun="force",
    input_what="force on the cart", position=cart_pendulum.POSITION,
    angle=cart_pendulum.ANGLE, rate_of=cart_pendulum.RATE_OF, measurable=cart_pendulum.MEASURED,
    measured=cart_pendulum.MEASURED, sensor_labels=cart_pendulum.SENSOR_LABELS,
    parameters=cart_pendulum.PARAMETERS, params_type=PlantParams, linear=cart_linear)

ROTARY = PlantModel(
    name="rotary-pendulum", what="a pendulum on an arm turned by a DC motor (Furuta's; a Quanser QUBE-Servo 2)",
    states=rotary_pendulum.STATES, input=rotary_pendulum.INPUT, input_unit=rotary_pendulum.INPUT_UNIT,
    input_noun="motor voltage", input_what="voltage on the arm's motor",
    position=rotary_pendulum.POSITION, angle=rotary_pendulum.ANGLE, rate_of=rotary_pendulum.RATE_OF,
    measurable=rotary_pendulum.MEASURABLE, measured=rotary_pendulum.MEASURED,
    sensor_labels=rotary_pendulum.SENSOR_LABELS, parameters=rotary_pendulum.PARAMETERS, params_type=RotaryParams,
    linear=rotary_linear, optional=rotary_pendulum.FROM_ROD)

PLANT_MODELS = {m.name: m for m in (CART, ROTARY)}
DEFAULT = CART.name  # a spec that names no plant model: every spec written before the rotary pendulum


def plant_model(name: str) -> PlantModel:
    """The plant model a spec names (KeyError for a name not in PLANT_MODELS)."""
    return PLANT_MODELS[name]
