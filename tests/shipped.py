"""Every shipped design on both machines, as a test takes it: its spec with the machine switched,
its patch, and the files patchgen patch writes for it."""

from __future__ import annotations

from patchgen.inputs.errors import ResourceError
from patchgen.inputs.resources import shipped
from patchgen.inputs.spec import load_spec
from patchgen.pipeline.inputs import plants_of

MACHINES = ("gp6", "the-analog-thing")


def patched_designs(command: str = "patch") -> list[str]:
    """The shipped designs of a plant model ``command`` takes (patchgen.pipeline.inputs.plants_of)."""
    return [name for name in shipped("design") if load_spec(name).plant.model in plants_of(command)]


def shipped_cases() -> list[tuple[str, str]]:
    """(design, machine) for every shipped design patchgen patches, on each machine."""
    return [(name, machine) for name in patched_designs() for machine in MACHINES]


def spec_on(name: str, machine: str):
    """A shipped design's spec with its machine switched (its file and name unchanged)."""
    spec = load_spec(name)
    return spec if spec.machine == machine else spec.model_copy(update={"machine": machine})


def patch_of(name: str, machine: str, predict: bool = False):
    """(report, machine profile, bench profile) of ``patchgen patch`` for the design on the machine,
    or None when the machine lacks what the patch needs (thesis-case1-noint's pots)."""
    from patchgen.pipeline.inputs import Inputs
    from patchgen.pipeline.patch import PatchPlan, run_patch
    from patchgen.profiles.bench import load_bench
    from patchgen.profiles.machine import load_machine

    spec = spec_on(name, machine)
    profile, bench = load_machine(machine), load_bench(spec.bench)
    try:
        report = run_patch(Inputs(spec, profile, bench), PatchPlan(predict=predict))
    except ResourceError:
        return None
    return report, profile, bench


def patch_files_of(name: str, machine: str, predict: bool = False) -> dict[str, str] | None:
    """The files ``patchgen patch`` writes for the design on the machine (None: it does not fit)."""
    from patchgen.render.bench_sheet import patch_report_files

    made = patch_of(name, machine, predict)
    return None if made is None else patch_report_files(*made)
