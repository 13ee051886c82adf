"""Machine profiles: the analog computer's amplifiers, pots, weights and imperfections, as data."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from .validation import load_profile

Role = Literal["integrator", "summer", "inverter", "differentiator"]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class AmplifierSlot(_Strict):
    """One physical amplifier on the panel and what it can be patched as."""

    id: str
    roles: list[Role]
    inputs: dict[str, int] = Field(description="count of inputs per weight, keys 'x1', 'x10'")

    def input_count(self, weight: int) -> int:
        return self.inputs.get(f"x{weight}", 0)


class Components(_Strict):
    """Passive parts behind the panel (for the SPICE export)."""

    input_resistor_x1_ohm: float = Field(gt=0)
    input_resistor_x10_ohm: float = Field(gt=0)
    feedback_resistor_ohm: float = Field(gt=0)
    integrator_capacitor_F: float = Field(gt=0)
    pot_resistance_ohm: float = Field(gt=0)
    differentiator_capacitor_F: float = Field(gt=0)
    opamp_open_loop_gain: float = Field(gt=1)
    opamp_output_resistance_ohm: float = Field(ge=0)


class Imperfections(_Strict):
    """What makes the real machine differ from ideal elements (for the simulators)."""

    integrator_offset_V: float = Field(ge=0)
    integrator_bias_A: float = Field(ge=0)
    saturation_V: float = Field(gt=0)
    amplifier_noise_V_rms: float = Field(ge=0)
    noise_bandwidth_Hz: float = Field(gt=0)
    differentiator_rolloff_s: float = Field(gt=0)


class MachineProfile(_Strict):
    """A whole machine: read from patchgen/machines/<id>.toml or a user path."""

    id: str
    name: str
    reference_V: float = Field(gt=0)
    time_scale_s: float = Field(gt=0)
    pot_count: int = Field(ge=0)
    pot_resolution: float = Field(gt=0, lt=1)
    pot_max: float = Field(gt=0)
    input_weights: list[int]
    ic_mode: str
    pot_set_mode: str
    overload_indicator: bool
    max_units: int = Field(ge=1)
    units: int = Field(default=1, ge=1, description="machines slaved together in this profile (see slaved())")
    amplifiers: list[AmplifierSlot]
    components: Components
    imperfections: Imperfections

    def slaved(self, units: int) -> MachineProfile:
        """``units`` machines slaved together as one: amplifiers U1.A1 ... U2.A8, pots times units."""
        if units == 1:
            return self
        amps = [a.model_copy(update={"id": f"U{u}.{a.id}"}) for u in range(1, units + 1) for a in self.amplifiers]
        return self.model_copy(update={"amplifiers": amps, "pot_count": self.pot_count * units, "units": units,
                                       "name": f"{self.name} x{units} (slaved)"})

    def integrator_drift_V_per_s(self) -> float:
        """Drift rate of an integrator with no input: e_os/(R C) + i_b/C (gp6.md)."""
        c = self.components
        return (self.imperfections.integrator_offset_V / (c.input_resistor_x1_ohm * c.integrator_capacitor_F)
                + self.imperfections.integrator_bias_A / c.integrator_capacitor_F)


def load_machine(name_or_path: str, source: str = "", field: str = "machine") -> MachineProfile:
    """Load a shipped profile by id (e.g. 'gp6') or a profile file by path."""
    return load_profile(MachineProfile, name_or_path, "machine", source, field)
