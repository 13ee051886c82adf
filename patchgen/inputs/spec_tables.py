"""A spec's plant-made tables: ``[plant]`` (one field per parameter of the spec's plant model) and
``[sensors]`` (a constant per state, what the bench reads, what reads it), made from the plant
model (patchgen.plant.plant_model) so that each plant is said once, in plant/."""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

from pydantic import Field, create_model

from patchgen.inputs.fields import InputModel, Real, bounded
from patchgen.plant.plant_model import CART, PLANT_MODELS, ROTARY, PlantModel


def _plant_table(plant: PlantModel, class_name: str):
    """The ``[plant]`` table of a spec for one plant model: its ``model`` and one field per parameter."""
    def field(p):
        if p.name in plant.optional:
            return Real | None, bounded(p.lo, p.hi, default=None, description=p.what)
        return Real, bounded(p.lo, p.hi, description=p.what, **({} if p.default is None else {"default": p.default}))
    return create_model(
        class_name, __base__=InputModel, __module__=__name__,
        __doc__=f"The plant's parameters, SI units, within the bounds of a bench-sized one: {plant.what}; one field "
                "per parameter of the plant model (patchgen.plant.plant_model).",
        model=(Literal[plant.name], Field(plant.name, description="the plant model: " + ", ".join(PLANT_MODELS))),
        **{p.name: field(p) for p in plant.parameters})


PlantSpec = _plant_table(CART, "PlantSpec")  # table B.1's parameters
RotaryPlantSpec = _plant_table(ROTARY, "RotaryPlantSpec")


SENSOR_RANGE = (1e-3, 1e3)  # V per SI unit: a millivolt to a kilovolt per metre, radian, m/s


class Sensors(InputModel):
    """Sensor constants, volts per SI unit of each quantity the bench reads (table A.2 for the
    cart), and the scale of the voltage that carries each rate the patch finds."""

    plant_model: ClassVar[PlantModel]

    def constants(self) -> dict[str, float]:
        """Volts per SI unit of each quantity the bench's sensors read, by name, in the plant's order."""
        return {q: getattr(self, q) for q in self.plant_model.measurable if q in self.measured}

    def read(self) -> tuple[str, ...]:
        """The quantities the sensors read, in the plant's order."""
        return tuple(q for q in self.plant_model.measurable if q in self.measured)

    def derived(self) -> tuple[str, ...]:
        """The rates the patch finds from their positions: the pendulum's always, first, as the
        thesis's; any other without a sensor (the cart's s_dot, the rotary arm's alpha_dot)."""
        plant = self.plant_model
        rates = [r for r in plant.rate_of.values() if r not in self.measured]
        return tuple(sorted(rates, key=lambda r: r != plant.angle_rate))


def _sensor_table(plant: PlantModel, class_name: str):
    """The ``[sensors]`` table for one plant model: a constant per state (a position's and a rate
    its reference bench reads required; another rate's its position's x 1 s unless given), what
    the bench reads and what each sensor is called."""
    units = plant.units
    fields = {}
    for name in plant.state_names:
        unit = units[name]
        if name in plant.rate_of:  # a position: always read
            fields[name] = (Real, bounded(*SENSOR_RANGE, description=f"V/{unit}"))
        elif name in plant.measured:
            fields[name] = (Real, bounded(*SENSOR_RANGE, description=f"V/({unit})"))
        else:
            fields[name] = (Real | None, bounded(*SENSOR_RANGE, default=None, description=(
                f"V/({unit}); default {plant.position_of[name]} x 1 s")))
    default = ", ".join(plant.measured)
    fields["measured"] = (list[Literal[plant.measurable]], Field(
        default_factory=lambda: list(plant.measured), description=f"what the bench's sensors read (default "
        f"{default}); a rate left out is the patch's to find from its position, as {plant.angle_rate} is, and its "
        "constant is then the scale of its voltage on the machine"))
    fields["labels"] = (dict[Literal[plant.measurable], Annotated[str, Field(min_length=1, max_length=80)]], Field(
        default_factory=dict, description="what reads each quantity, as the sheet names it (default: the plant's "
                                          "reference bench's sensors)"))
    table = create_model(class_name, __base__=Sensors, __module__=__name__,
                         __doc__=f"Sensor constants of {plant.what}, volts per SI unit.", **fields)
    table.plant_model = plant
    return table


SensorSpec = _sensor_table(CART, "SensorSpec")
RotarySensorSpec = _sensor_table(ROTARY, "RotarySensorSpec")
