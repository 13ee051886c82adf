"""The operating procedure comes from the machine profile: each machine's sheet speaks its own terms."""

from __future__ import annotations

import pytest

from patchgen.design.lqg import design_on
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import Step, load_machine
from patchgen.render.patchfiles import patch_files

# terms only one of the two machines has (its manual's or wiki's words)
GP6_ONLY = ("POT SET", "overload lamps", "HD (hold)", "IC jack", "dial")
THAT_ONLY = ("MODE SELECTOR", "COEFF", "COEFFICIENT SELECTOR", "panel meter", "HALT", "OFF")


def _files(machine):
    spec = load_spec("thesis-ch5")
    d = design_on(spec, machine, load_bench(spec.bench))
    net = build_patch(d, machine)
    return net, patch_files(d, machine, net)


def _sheet(machine):
    net, files = _files(machine)
    return net, files["patch-sheet.md"]


@pytest.mark.parametrize("name, own, other", [("gp6", GP6_ONLY, THAT_ONLY),
                                              ("the-analog-thing", THAT_ONLY, GP6_ONLY)])
def test_each_sheet_uses_its_machines_terms(name, own, other):
    net, files = _files(load_machine(name))
    for sheet in ("patch-sheet.md", "patch-sheet.html", "pots.csv"):
        for term in other:
            assert term not in files[sheet], (sheet, term)
    md = files["patch-sheet.md"]
    for term in own:
        assert term in md, term
    # the pot a coefficient below the resolution is set on is read on the machine's own instrument
    reading = load_machine(name).procedure.pot_reading
    assert f"Settings to the {reading} resolution 0.001." in md
    assert f"design 5.49e-07 is below the {reading}: set to the minimum" in md
    # the operating steps travel in the netlist, from the same profile
    assert any(own[0] in step for step in net.operation)
    assert not any(term in step for step in net.operation for term in other)


def test_a_changed_profile_changes_the_sheet():
    gp6 = load_machine("gp6")
    steps = list(gp6.procedure.checklist)
    steps[0] = Step(text="Ask the technician on duty for the {machine} key.")
    edited = gp6.model_copy(update={"procedure": gp6.procedure.model_copy(update={"checklist": steps})})
    _, md = _sheet(edited)
    assert "Ask the technician on duty for the Comdyna GP-6 key." in md
    assert "Servo amplifier powered off" not in md


def test_steps_apply_to_the_patch_they_are_for():
    proc = load_machine("gp6").procedure
    common = dict(machine="M", resolution=0.001, reference_V=10.0)
    bare = proc.steps("checklist", units=1, integrators=(), signs=False, **common)
    full = proc.steps("checklist", units=2, integrators=("A1", "A2"), signs=True, **common)
    assert not any("IC: each IC jack" in s for s in bare)
    assert any("check each integrator (A1, A2) reads minus its IC-jack voltage" in s for s in full)
    assert "Check each sign with one feedback path at a time (all other pots at 0)." in bare
    assert any("with the sign table" in s for s in full) and not any("with the sign table" in s for s in bare)
    assert any("(M, 2 units slaved together)" in s for s in full) and any("(M)." in s for s in bare)
    assert any("to 0.001." in s for s in bare)
    ops = proc.steps("operation", units=1, integrators=("A1", "A2"), signs=False, **common)
    assert any("integrators A1, A2 to 0 V" in s for s in ops)


@pytest.mark.parametrize("text", ["Set {pots}.", "Patch {machine", "Set {0}.", "Set {machine.name}."])
def test_a_step_names_only_known_placeholders(text):
    with pytest.raises(ValueError):
        Step(text=text)
