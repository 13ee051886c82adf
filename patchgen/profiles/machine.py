"""Machine profiles: the analog computer's amplifiers, pots, weights and imperfections, as data."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from patchgen.inputs.errors import InputError
from patchgen.inputs.fields import InputModel, Int, Real, bounded
from patchgen.inputs.validation import load_profile
from patchgen.plant.plant_model import CART, PlantModel

Role = Literal["integrator", "summer", "inverter", "differentiator"]
MAX_UNITS = 16  # slaved machines in one profile


class AmplifierSlot(InputModel):
    """One physical amplifier on the panel and what it can be patched as."""

    id: str = Field(min_length=1)
    roles: list[Role] = Field(min_length=1)
    inputs: dict[str, Annotated[Int, Field(ge=0, le=100)]] = Field(
        description="count of inputs per weight, keys 'x1', 'x10'")

    def input_count(self, weight: int) -> int:
        """How many inputs of weight ``weight`` (1 for x1) this amplifier has; 0 if none."""
        return self.inputs.get(f"x{weight}", 0)


OHM = (1.0, 1e12)
FARAD = (1e-15, 1.0)


class Components(InputModel):
    """Passive parts behind the panel (for the SPICE export)."""

    input_resistor_x1_ohm: Real = bounded(*OHM)
    input_resistor_x10_ohm: Real = bounded(*OHM)
    feedback_resistor_ohm: Real = bounded(*OHM)
    integrator_capacitor_F: Real = bounded(*FARAD)
    pot_resistance_ohm: Real = bounded(*OHM)
    differentiator_capacitor_F: Real = bounded(*FARAD)
    opamp_open_loop_gain: Real = bounded(1, 1e12, open_lo=True)
    opamp_output_resistance_ohm: Real = bounded(0, 1e6)
    external_resistor_tolerance: Real = bounded(0, 0.5, default=0.01,
                                                description="of an external resistor (1 %: E96 metal film)")
    external_capacitor_tolerance: Real = bounded(0, 0.5, default=0.05,
                                                 description="of an external capacitor (5 %: film)")

    def input_resistor_ohm(self, weight: int) -> float:
        """The input resistor of a weight-``weight`` input: the profile's own value for x1 and
        x10, else the x1 resistor divided by the weight (gain = feedback / input resistance)."""
        named = {1: self.input_resistor_x1_ohm, 10: self.input_resistor_x10_ohm}
        return float(named.get(weight, self.input_resistor_x1_ohm / weight))


class Imperfections(InputModel):
    """What makes the real machine differ from ideal elements (for the simulators)."""

    integrator_offset_V: Real = bounded(0, 1)
    integrator_bias_A: Real = bounded(0, 1e-3)
    saturation_V: Real = bounded(0, 1000, open_lo=True)
    amplifier_noise_V_rms: Real = bounded(0, 10)
    noise_bandwidth_Hz: Real = bounded(1e-3, 1e9)
    differentiator_rolloff_s: Real = bounded(1e-4, 1)
    drift_source: str = Field(default="profile figure", min_length=1, max_length=200,
                              description="where the drift figures come from (printed beside the drift rate)")


class IntegratorMode(InputModel):
    """One way an integrator can be set to integrate: its rate k0 = 1/(R C) on a x1 input (a
    weight-w input integrates w times faster), how the technician selects it, and the source."""

    name: str = Field(min_length=1, max_length=40, description="the mode's name, e.g. 'standard' or 'SLOW'")
    k0_per_s: Real = bounded(1e-6, 1e9, description="1/s: d(out)/dt = -k0 x (a x1 input at 1 V)")
    jumper: str | None = Field(default=None, min_length=1, max_length=40,
                               description="the integrator's jack patched to its own output to select "
                                           "this mode (THE ANALOG THING: SLOW); none for the default")
    source: str = Field(default="profile figure", min_length=1, max_length=200)

    @property
    def time_scale_s(self) -> float:
        """T = 1/k0: the time a x1 input at one machine unit takes to ramp the output one unit."""
        return 1.0 / self.k0_per_s


# What a procedure step may name, filled in for each patch (see Procedure.steps)
PLACEHOLDERS = ("machine", "units", "resolution", "reference_V", "integrators", "at_rest", "by_hand")


class Step(InputModel):
    """One step of a procedure, in the machine's own words; ``{name}`` placeholders from
    PLACEHOLDERS are filled in for the patch."""

    text: str = Field(min_length=1, max_length=1000)
    # always, or only for a patch with integrators (ICs to set), with a sign table, or without one
    when: Literal["always", "integrators", "signs", "no_signs"] = "always"

    @field_validator("text")
    @classmethod
    def _placeholders(cls, text: str) -> str:
        try:
            text.format(**{k: "" for k in PLACEHOLDERS})
        except (AttributeError, KeyError, IndexError, ValueError) as exc:
            raise ValueError(f"{{...}} may name only {', '.join(PLACEHOLDERS)} ({exc})") from None
        return text


class Procedure(InputModel):
    """How a patch is run on this machine, as its manual words it: the operating steps a netlist
    carries, the bench checklist a sheet prints, how a pot is set (the pot table's title), what
    its setting is read on (the sheet's pot table) and what an integrator's IC input is called (the
    checks' test voltages)."""

    pot_setting: str = Field(min_length=1, max_length=200)
    pot_reading: str = Field(min_length=1, max_length=100,
                             description="what a pot's setting is read on, e.g. 'dial' or 'panel meter'")
    ic_input: str = Field(default="IC jack", min_length=1, max_length=40,
                          description="what an integrator's initial-condition input is called, e.g. 'IC jack'")
    operation: list[Step] = Field(min_length=1, max_length=50)
    checklist: list[Step] = Field(min_length=1, max_length=50)

    def steps(self, which: str, *, machine: str, units: int, resolution: float, reference_V: float,
              integrators: tuple[str, ...], signs: bool, plant: PlantModel = CART) -> list[str]:
        """The steps of one list that apply to a patch, placeholders filled in.

        Parameters
        ----------
        which : {"operation", "checklist"}
            The netlist's operating steps or the sheet's bench checklist.
        machine, units, resolution, reference_V
            The patch's machine name, slaved units, pot resolution and reference (V).
        integrators : tuple of str
            Ids of the patch's integrators and lags (the ``integrators`` steps apply when any).
        signs : bool
            Whether the sheet has a sign table (chooses the ``signs`` or ``no_signs`` steps).
        plant : PlantModel
            Whose words fill ``at_rest`` (how it is held while the patch is set) and ``by_hand``.

        Returns
        -------
        list of str
            The steps, in the profile's order.
        """
        applies = {"always": True, "integrators": bool(integrators), "signs": signs, "no_signs": not signs}
        values = {"machine": machine, "units": f", {units} units slaved together" if units > 1 else "",
                  "resolution": f"{resolution:g}", "reference_V": f"{reference_V:g}",
                  "integrators": ", ".join(integrators), "at_rest": plant.at_rest, "by_hand": plant.by_hand}
        return [s.text.format(**values) for s in getattr(self, which) if applies[s.when]]


class MachineProfile(InputModel):
    """A whole machine: read from patchgen/profiles/machines/<id>.toml or a user path."""

    id: str = Field(min_length=1)
    name: str
    reference_V: Real = bounded(0, 1000, open_lo=True)
    time_scale_s: Real | None = bounded(1e-6, 1e6, default=None,
                                       description="integrator time scale T = 1/k0 of a machine with one "
                                                   "integrator mode; with integrator_modes, the slowest's")
    integrator_modes: list[IntegratorMode] = Field(default_factory=list, max_length=10)
    pot_count: Int = bounded(0, 1000)
    pot_resolution: Real = bounded(1e-9, 0.5)
    pot_max: Real = bounded(0, 100, open_lo=True)
    input_weights: list[Annotated[Int, Field(ge=1, le=1000)]] = Field(min_length=1, max_length=10)
    procedure: Procedure
    max_units: Int = bounded(1, MAX_UNITS)
    units: Int = bounded(1, MAX_UNITS, default=1,
                         description="machines slaved together in this profile (see slaved())")
    amplifiers: list[AmplifierSlot] = Field(min_length=1, max_length=1000)
    components: Components
    imperfections: Imperfections
    signed_coefficients: bool = Field(
        default=False, description="each input's coefficient is set with its sign (a programmed coefficient "
                                   "matrix, the LUCIDAC): no inverters, every block's output at +1 polarity")
    programmed: bool = Field(
        default=False, description="set from a configuration the machine loads, not patched with cords: "
                                   "integrator modes are chosen in it, so none needs a jumper")

    @model_validator(mode="after")
    def _one_time_scale(self) -> MachineProfile:
        """Fill in what the profile left to be derived: a single-mode machine's one mode from its
        time_scale_s, a multi-mode machine's time_scale_s from its slowest mode (the scale every
        realisation is built at; patchgen.patch.time_scales moves a block to a faster mode).
        Neither or both given is refused by load_machine with the field named."""
        if self.integrator_modes and self.time_scale_s is None:
            object.__setattr__(self, "time_scale_s", 1.0 / min(m.k0_per_s for m in self.integrator_modes))
        elif not self.integrator_modes and self.time_scale_s is not None:
            object.__setattr__(self, "integrator_modes", [IntegratorMode(
                name="standard", k0_per_s=1.0 / self.time_scale_s, source="time_scale_s")])
        return self

    def modes(self) -> list[IntegratorMode]:
        """The integrator modes, slowest first (the order a block is tried in)."""
        return sorted(self.integrator_modes, key=lambda m: m.k0_per_s)

    def slaved(self, units: int) -> MachineProfile:
        """``units`` machines slaved together as one: amplifiers U1.A1 ... U2.A8, pots times units."""
        if units == 1:
            return self
        amps = [a.model_copy(update={"id": f"U{u}.{a.id}"}) for u in range(1, units + 1) for a in self.amplifiers]
        return self.model_copy(update={"amplifiers": amps, "pot_count": self.pot_count * units, "units": units,
                                       "name": f"{self.name} x{units} (slaved)"})

    def integrator_drift_V_per_s(self, time_scale_s: float | None = None) -> float:
        """Drift rate of an integrator with no input: e_os/(R C) + i_b/C (gp6.md), with C the
        capacitor that gives the integrator's time scale T = R C on its x1 input resistor R (the
        slowest mode's by default): a faster mode drifts faster in proportion."""
        R = self.components.input_resistor_x1_ohm
        C = (self.time_scale_s if time_scale_s is None else time_scale_s) / R
        return self.imperfections.integrator_offset_V / (R * C) + self.imperfections.integrator_bias_A / C


def load_machine(name_or_path: str, source: str = "", field: str = "machine") -> MachineProfile:
    """Load a shipped profile by id (e.g. 'gp6') or a profile file by path.

    Parameters
    ----------
    name_or_path, source, field : str
        As for patchgen.profiles.bench.load_bench, the field being the spec's ``machine``.

    Returns
    -------
    MachineProfile
        The checked profile (amplifier ids unique, input keys among the weights); a bad value
        raises InputError naming the profile file and field.
    """
    return load_profile(MachineProfile, name_or_path, "machine", source, field, check=_check_profile)


def _check_profile(profile: MachineProfile, source: str) -> None:
    """One time scale given (time_scale_s or integrator_modes), mode names unique, at most one
    mode without a jumper; amplifier ids unique and their input keys the profile's weights."""
    if {"time_scale_s", "integrator_modes"} <= profile.model_fields_set:
        raise InputError(source, "time_scale_s", "give time_scale_s (one integrator mode) or [[integrator_modes]], "
                         "not both")
    if not profile.integrator_modes:
        raise InputError(source, "time_scale_s", "missing: give time_scale_s (one integrator mode) or "
                         "[[integrator_modes]]")
    names = [m.name for m in profile.integrator_modes]
    for i, m in enumerate(profile.integrator_modes):
        if names.index(m.name) != i:
            raise InputError(source, f"integrator_modes[{i}].name", f"{m.name!r} is used twice")
    if not profile.programmed and sum(m.jumper is None for m in profile.integrator_modes) > 1:
        raise InputError(source, "integrator_modes", "more than one mode without a jumper: the technician could "
                         "not tell them apart")
    keys = {f"x{w}" for w in profile.input_weights}
    seen: set[str] = set()
    for i, a in enumerate(profile.amplifiers):
        if a.id in seen:
            raise InputError(source, f"amplifiers[{i}].id", f"{a.id!r} is used twice")
        seen.add(a.id)
        for k in a.inputs:
            if k not in keys:
                raise InputError(source, f"amplifiers[{i}].inputs.{k}",
                                 f"not an input weight of this machine (input_weights give {', '.join(sorted(keys))})")


def the_machine(name: str) -> str:
    """A machine's name with "the" before it, unless the name starts with it (THE ANALOG THING)."""
    return name if name.lower().startswith("the ") else f"the {name}"
