"""What a run needs, read and checked once before anything is computed: the spec and the machine
and bench profiles it names (one ``Inputs``), and each scenario (inside the spec's track, within
the simulation bounds). Every pipeline function takes them resolved; no stage reads them again."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from patchgen.bench import budget
from patchgen.inputs.errors import InputError
from patchgen.inputs.resources import folder, resolve
from patchgen.inputs.scenario import Scenario, check_on_arm, check_on_track, check_plant, load_scenario
from patchgen.inputs.spec import DesignSpec, load_spec
from patchgen.plant.plant_model import CART, PLANT_MODELS
from patchgen.profiles.bench import BenchProfile, bench_source, check_reads, load_bench
from patchgen.profiles.machine import MachineProfile, load_machine

MAX_SPICE_POINTS = 10**6  # transient points of an ngspice run (duration / --step)
# the plant models each command takes (identify reads recordings and takes no spec)
EVERY_PLANT = tuple(PLANT_MODELS)
COMMAND_PLANTS = {command: EVERY_PLANT
                  for command in ("design", "patch", "simulate", "check", "export", "spice", "recommend", "swingup",
                                  "sweep", "bench-test")}


def plants_of(command: str) -> tuple[str, ...]:
    """The plant models ``command`` takes (COMMAND_PLANTS; the cart alone for any other)."""
    return COMMAND_PLANTS.get(command, (CART.name,))


class Inputs(NamedTuple):
    """A spec and the machine and bench it runs on, each loaded and checked."""

    spec: DesignSpec
    machine: MachineProfile
    bench: BenchProfile


def load_inputs(path: str, bench: str | None = None, bench_source_name: str = "bench",
                machine: str | None = None, *, plants: tuple[str, ...] | None = None, command: str = "") -> Inputs:
    """The spec and the machine and bench profiles it names, each fully checked.

    Parameters
    ----------
    path : str
        A spec file or a shipped design's name.
    bench : str, optional
        A bench profile (a shipped id or a path) replacing the spec's.
    bench_source_name : str
        What ``bench`` is called in an error about it (the option that gave it).
    machine : str, optional
        A machine profile (a shipped id or a path) replacing the spec's ``machine``, in the spec
        too (a file by its absolute path), so that every later stage and a spec written from it
        (recommend's recommended.toml) name it; an error about it is the field ``machine``'s.
    plants : tuple of str, optional
        The plant models the command takes (patchgen.plant.plant_model; by default ``command``'s,
        plants_of); another is refused.
    command : str
        The command, as a refusal names it.
    """
    spec = load_spec(path)
    plants = plants_of(command) if plants is None else plants
    if spec.plant.model not in plants:
        takes = ", ".join(c for c, p in COMMAND_PLANTS.items() if spec.plant.model in p)
        raise InputError(spec.path, "plant.model", f"{spec.plant.model}: patchgen {command} takes the "
                         f"{' or '.join(plants)} so far (a {spec.plant.model} is taken by {takes})")
    name, source, field = (bench, bench_source_name, "") if bench is not None else (spec.bench, spec.path, "bench")
    profile = load_bench(name, source, field)
    if profile.plant != spec.plant.model:
        raise InputError(bench_source(name, source, field), "plant", f"is a {profile.plant} bench; the spec "
                         f"{spec.path} is a {spec.plant.model}'s")
    check_reads(profile, spec.sensors.read(), bench_source(name, source, field))
    if machine is None:
        return Inputs(spec, load_machine(spec.machine, spec.path), profile)
    chosen = load_machine(machine, "machine", "")
    found = resolve("machine", machine, "machine", "")
    own = isinstance(found, Path) and found != folder("machine").joinpath(f"{machine}.toml")  # not a shipped id
    named = str(found.absolute()) if own else machine
    return Inputs(spec.model_copy(update={"machine": named}), chosen, profile)


def scenario_for(path: str, spec: DesignSpec, runs: int = 1, ideal: bool = False) -> Scenario:
    """The scenario, checked against the spec's track and, before any design, against the
    simulation bounds at the coarsest step the engine would take (the exact check follows in
    patchgen.bench.simulate, once the circuit's time constants are known)."""
    from patchgen.bench.engine import default_step

    sc = load_scenario(path)
    check_plant(sc, spec.plant_model, spec.path)
    if spec.plant_model is CART:
        sc = sc.on_track(spec.plant.d)  # fractions of the track in metres
        check_on_track(sc, spec.plant.d, spec.path)
    else:
        check_on_arm(sc, spec.plant.alpha_limit, spec.path)
    step = sc.dt_s or default_step([], ideal)
    budget.check(sc, runs, step=step, stride=max(1, round(sc.record_dt_s / step)), history=True,
                 usual_step=default_step([], ideal))
    return sc


def check_spice_points(sc: Scenario, step_s: float) -> None:
    """An ngspice transient of at most MAX_SPICE_POINTS output points."""
    points = sc.duration_s / step_s
    if points > MAX_SPICE_POINTS:
        raise InputError("step_s", "", f"{sc.duration_s:g} s of {sc.path} at {step_s:g} s is {points:.3g} points; "
                                       f"at most {MAX_SPICE_POINTS:.0e} (a larger --step)")
