"""The rotary pendulum's law through the patch layer: the QUBE-Servo 2's design realised in volts,
allocated on each machine, read back from the netlist as the design's controller, with the
arm's and pendulum's encoders as its sensors and a hand-moved sign check on both angles.

The patch command itself refuses a rotary spec until the bench simulates it (its signal-to-noise
scaling and its sheet's prediction run on the bench): these tests build the patch with the
sensor-constant scaling and no prediction, as that command will."""

from __future__ import annotations

import numpy as np
import pytest

import patchgen
from patchgen.patch.build import build_patch
from patchgen.patch.readback import si_controller
from patchgen.patch.sign_check import sign_check
from patchgen.pipeline.inputs import load_inputs
from patchgen.plant.plant_model import PLANT_MODELS, ROTARY
from patchgen.profiles.machine import load_machine
from patchgen.render.sheet import gain_unit

QUBE = "qube-servo-2"


def _design(machine: str):
    inputs = load_inputs(QUBE, plants=tuple(PLANT_MODELS))
    spec = inputs.spec.changed("patch.scaling", "sensors").model_copy(update={"machine": machine})
    from patchgen.design.lqg import design_on

    profile = load_machine(machine)
    return design_on(spec, profile, inputs.bench), profile


@pytest.mark.parametrize("machine", ["gp6", "the-analog-thing"])
def test_the_patched_law_is_the_design_s_controller(machine):
    """The netlist read back in SI units (from alpha and theta in rad to the motor's volts) has the
    design's frequency response within the dial's rounding, over the loop's band."""
    d, profile = _design(machine)
    net = build_patch(d, profile)
    assert [s.quantity for s in net.sensors] == ["alpha", "theta"]
    assert [s.unit for s in net.sensors] == ["rad", "rad"]
    assert [s.label for s in net.sensors] == ["arm encoder (DAQ output)", "pendulum encoder (DAQ output)"]
    assert net.output.K_U_N_per_V == 1.0  # motor volts per command volt: the plant's input per volt
    got, want = si_controller(net), d.controller
    w = np.logspace(0, 2, 7)

    def response(c, i):
        out = []
        for wk in w:
            s = 1j * wk
            out.append((c.Cc @ np.linalg.solve(s * np.eye(len(c.Ac)) - c.Ac, c.Bc[:, i]) + c.Dc[0, i]).item())
        return np.array(out)

    for i in range(2):
        g, h = response(got, i), response(want, i)
        np.testing.assert_allclose(g, h, rtol=5e-3)  # each pot at the dial's 0.001 step
        assert np.all(np.sign(g.real) == np.sign(h.real))


def test_the_sign_check_moves_the_arm_and_the_pendulum_by_hand():
    d, profile = _design("gp6")
    net = build_patch(d, profile)
    hand = {s.drive.target for s in sign_check(net, profile, ROTARY) if s.drive.kind == "hand"}
    assert hand == {"alpha", "theta"}  # both encoders' angles, moved by hand
    assert {s.drive.target for s in sign_check(net, profile) if s.drive.kind == "hand"} == {"theta"}  # as a cart's


def test_gains_are_in_motor_volts_per_unit():
    assert [gain_unit(s, ROTARY) for s in ROTARY.state_names] == ["V/rad", "V/rad", "V s/rad", "V s/rad"]
    assert gain_unit("s_dot") == "N s/m" and gain_unit("theta") == "N/rad"  # the cart's, unchanged


def test_the_design_api_designs_the_qube():
    d = patchgen.load_design(QUBE)
    assert d.states == ("alpha", "theta", "alpha_dot", "theta_dot")


def test_the_sheet_speaks_of_the_arm_not_the_cart():
    """The sheet a technician follows for the rotary patch: the law in motor volts, the arm held at
    its centre while the patch is set, the arm and the pendulum moved by hand in the sign check."""
    from patchgen.pipeline.inputs import Inputs
    from patchgen.pipeline.patch import PatchPlan, run_patch
    from patchgen.render.bench_sheet import patch_report_files

    inputs = load_inputs(QUBE, plants=tuple(PLANT_MODELS))
    spec = inputs.spec.changed("patch.scaling", "sensors")
    report = run_patch(Inputs(spec, inputs.machine, inputs.bench), PatchPlan(predict=False))
    md = patch_report_files(report, inputs.machine, inputs.bench)["patch-sheet.md"]
    assert "u = −K x (V); u_c = u / K_U, K_U = 1 V/V" in md
    assert "the arm held at its centre, the pendulum hanging" in md
    assert "turn the arm toward +α by hand" in md and "+α is the way a positive u_c turns the arm" in md
    assert "cart" not in md.lower()
