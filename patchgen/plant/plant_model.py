"""The plant interface: what a layer above asks of a pendulum, whichever it is.

Each plant model (patchgen.plant.cart_pendulum, patchgen.plant.rotary_pendulum) describes itself
in module constants of the same names; a PlantModel gathers them with the plant's parameter type and its linear
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
    body : str
        What the position is of, as a sentence names it ("cart", "arm").
    rate_of : mapping of str to str
        Each position-like state's rate.
    measurable : tuple of str
        What a bench's sensors may read (positions always; a rate where a tachometer gives it).
    measured : tuple of str
        What the named bench's sensors read when a spec does not say.
    sensor_labels : mapping of str to str
        What reads each measured quantity on the plant's reference bench, as a sheet names it.
    at_rest, by_hand : str
        How a sheet says the plant is held while a patch is set, and what a person moves by hand.
    limit_event, kept_inside : str
        What ends a run at the position's limit, as a table heads it ("limit switch"), and what a
        held run kept besides the pendulum up ("the cart inside the limit switches").
    hand_words : mapping of str to str
        How each hand-moved state is moved, in a sign check's row.
    sign_words : str
        The signs of the hand-moved states, said once above the sign check.
    parameters : tuple of Parameter
        The physical parameters, in the order of the parameter type's fields.
    step : float
        The position step of the plant's shipped step scenario (SI): a patch's amplitudes are scaled
        over the loop released from it, as from a 10 deg lean.
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
    body: str
    rate_of: Mapping[str, str]
    measurable: tuple[str, ...]
    measured: tuple[str, ...]
    sensor_labels: Mapping[str, str]
    at_rest: str
    by_hand: str
    limit_event: str
    kept_inside: str
    hand_words: Mapping[str, str]
    sign_words: str
    parameters: tuple[Parameter, ...]
    params_type: type
    linear: Callable[[Any], tuple[np.ndarray, np.ndarray]] = field(repr=False)
    step: float
    optional: tuple[str, ...]

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

    def state_units(self) -> dict[str, str]:
        """Each state's SI unit, a design's added states too: its integrals and its actuator's."""
        units = self.units
        return {**units, "int_s": f"{units[self.position]} s", "int_theta": f"{units[self.angle]} s",
                "actuator": self.input_unit}

    def position_heading(self) -> str:
        """A table's heading for the largest |position| of a run: "max |s| (m)"."""
        return f"max |{self.position}| ({self.units[self.position]})"

    @property
    def position_key(self) -> str:
        """The JSON key of a run's largest |position|, named with its state and unit: "max_abs_s_m",
        "max_abs_alpha_rad"."""
        return f"max_abs_{self.position}_{self.units[self.position]}"

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


def _described(module, params_type: type, linear) -> PlantModel:
    """A plant model from the module that describes the plant (its constants by the names above)."""
    m = module
    return PlantModel(
        name=m.NAME, what=m.WHAT, states=m.STATES, input=m.INPUT, input_unit=m.INPUT_UNIT, input_noun=m.INPUT_NOUN,
        input_what=m.INPUT_WHAT, position=m.POSITION, angle=m.ANGLE, body=m.BODY, rate_of=m.RATE_OF,
        measurable=m.MEASURABLE, measured=m.MEASURED, sensor_labels=m.SENSOR_LABELS, at_rest=m.AT_REST,
        limit_event=m.LIMIT_EVENT, kept_inside=m.KEPT_INSIDE, by_hand=m.BY_HAND, hand_words=m.HAND_WORDS,
        sign_words=m.SIGN_WORDS,
        parameters=m.PARAMETERS, params_type=params_type, linear=linear, step=m.STEP, optional=m.OPTIONAL)


CART = _described(cart_pendulum, PlantParams, cart_linear)
ROTARY = _described(rotary_pendulum, RotaryParams, rotary_linear)

PLANT_MODELS = {m.name: m for m in (CART, ROTARY)}
DEFAULT = CART.name  # a spec that names no plant model: every spec written before the rotary pendulum


def model_of(params: Any) -> PlantModel:
    """The plant model whose parameter type ``params`` is (a PlantParams is the cart's): so that a
    stage handed a plant's figures asks them which plant they are."""
    for model in PLANT_MODELS.values():
        if isinstance(params, model.params_type):
            return model
    raise TypeError(f"{type(params).__name__} is no plant model's parameters")
