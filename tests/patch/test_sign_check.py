"""The sign check, for every shipped design on both machines: a step per pot, each moving only what a
person can move (the cart or the pendulum by hand, or a test voltage from a spare pot, on a rate
sensor's input or an integrator's IC jack) and each expecting what the patch does, worked out here
again from the netlist alone, and the other way round with the pot's sign flipped (before, the
table asked to 'make positive' u_c, the actuator state, the integral of theta, c1 or c4_in)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from patchgen.patch.netlist import Netlist
from patchgen.patch.sign_check import SignStep, sign_check
from patchgen.patch.static_check import spare_pots
from patchgen.render.sign_sheet import sign_rows
from tests.shipped import patch_of, shipped_cases

pytestmark = pytest.mark.heavy(6)  # seconds, roughly: see tests/conftest.py


@pytest.fixture(scope="module")
def checked():
    """(design-machine) -> (netlist, machine, its sign check), for every shipped design that fits."""
    out = {}
    for name, machine in shipped_cases():
        made = patch_of(name, machine)
        if made is not None:
            report, profile, _ = made
            plant = report.design.spec.plant_model  # whose position and angle are moved by hand
            out[f"{name}-{machine}"] = (report.netlist, profile, sign_check(report.netlist, profile, plant), plant)
    return out


def _expected(net: Netlist, step: SignStep, flip: str | None = None) -> float:
    """The reading a step expects, from the netlist's own inputs: only the step's pots at their
    settings (``flip``'s sign reversed), the moved input at +1 (an integrator at its IC value), the
    other integrators at 0 and each differentiator passing the change while the hand moves."""
    ids = [a.id for a in net.amplifiers]
    pots = {p.id: p for p in net.pots}
    A, b = np.eye(len(ids)), np.zeros(len(ids))
    sensors = {step.drive.target: 1.0} if step.drive.kind != "ic" else {}
    gains: dict[str, list[tuple[str, float]]] = {}
    for i, a in enumerate(net.amplifiers):
        gains[a.id] = [(inp.source, inp.weight * (0.0 if inp.pot and inp.pot not in step.on else
                                                  pots[inp.pot].setting if inp.pot else 1.0)
                        * (-1.0 if flip is not None and inp.pot == flip else 1.0)) for inp in a.inputs]
        if a.role == "integrator" or (a.role == "differentiator" and not step.moving):
            b[i] = -step.drive.volts if step.drive.kind == "ic" and a.id == step.drive.target else 0.0
            continue
        for src, g in gains[a.id]:
            if src in ids:
                A[i, ids.index(src)] += g
            else:
                b[i] -= g * sensors.get(src, 0.0)
    out = dict(zip(ids, np.linalg.lstsq(A, b, rcond=None)[0]))
    if not step.ramp:
        return out[step.read]
    return -sum(g * {**sensors, **out}.get(src, 0.0) for src, g in gains[step.read])


def test_a_step_per_pot_each_moving_what_a_person_can_move(checked):
    for key, (net, machine, steps, plant) in checked.items():
        assert [s.pot for s in steps] == [p.id for p in net.pots], key
        sensors = {s.id: s.quantity for s in net.sensors}
        roles = {a.id: a.role for a in net.amplifiers}
        free = spare_pots(net, machine)
        for s in steps:
            assert s.on[0] == s.pot and set(s.on) <= {p.id for p in net.pots}, (key, s)
            d = s.drive
            if d.kind == "hand":
                assert sensors[d.target] in (plant.position, plant.angle), (key, s)  # moved by hand
                continue
            assert d.kind in ("input", "ic"), (key, s)
            assert ((sensors[d.target] not in (plant.position, plant.angle)) if d.kind == "input"
                    else roles[d.target] == "integrator")
            m = re.fullmatch(r"spare pot (\S+) at ([0-9.]+) from ([+−])10 V", d.source)
            assert m and m.group(1) == free[0], (key, s)
            assert float(m.group(2)) * 10 == pytest.approx(abs(d.volts)) and 0 < float(m.group(2)) <= 1
            assert (m.group(3) == "+") == (d.volts > 0)


def test_every_step_expects_what_the_patch_does_and_sees_its_pots_sign(checked):
    for key, (net, _, steps, _) in checked.items():
        for s in steps:
            value = _expected(net, s)
            assert np.sign(value) == s.expect and abs(value) > 1e-9, (key, s, value)
            assert np.sign(_expected(net, s, flip=s.pot)) == -s.expect, (key, s)


def test_the_internal_signs_are_checked_through_a_sensor_or_a_test_voltage(checked):
    """bench-recommended's pots from u_c, the actuator state and its own feedback: each moved from
    the cart or through the integrator's IC jack, read where it shows."""
    net, _, steps, _ = checked["bench-recommended-gp6"]
    by = {s.pot: s for s in steps}
    assert net.pot("P1").source == "A6" and (by["P1"].drive.kind, by["P1"].drive.target) == ("hand", "s")
    assert by["P1"].on == ("P1", "P3") and by["P1"].read == "A1" and by["P1"].ramp
    assert (by["P2"].drive.kind, by["P2"].drive.target, by["P2"].read) == ("ic", "A1", "A1")  # A1's own feedback
    assert (by["P7"].drive.kind, by["P7"].read) == ("ic", net.output.source)
    assert by["P6"].moving and by["P6"].drive.target == "theta"  # through the differentiator


def test_the_sheet_asks_only_for_moves(checked):
    pattern = re.compile(r"(move the cart toward \+s|lean the pendulum toward \+s|turn the arm toward \+α|"
                         r"lean the pendulum toward \+α) by hand(, read while it moves)?"
                         r"|\S+ input at [+−][0-9.]+ V \(spare pot \S+ at [0-9.]+ from [+−]10 V\), its sensor cord out"
                         r"|(\S+)'s IC (jack|input) at [+−][0-9.]+ V \(spare pot \S+ at [0-9.]+ from [+−]10 V\): "
                         r"(\S+) at [+−][0-9.]+ V")
    for key, (net, machine, steps, plant) in checked.items():
        for row in sign_rows(steps, net, machine.procedure.ic_input, plant):
            assert pattern.fullmatch(row["move"]), (key, row)
            assert "positive" not in row["move"].lower()
            assert row["way"] in ("+", "−", "+ while it moves", "− while it moves", "rises", "falls",
                                  "falls back to 0", "rises back to 0"), (key, row)


def test_a_path_hidden_at_u_c_is_read_at_its_own_amplifier(tmp_path):
    """bench-recommended's reduced observer on two units: theta through U1.P2 reaches u_c only
    beside theta's own x10 cord into a lag, which swamps it there; its row reads U1.A6 instead."""
    from patchgen.design.lqg import design_on
    from patchgen.inputs.spec import load_spec
    from patchgen.patch.build import build_patch
    from patchgen.profiles.bench import load_bench
    from patchgen.profiles.machine import load_machine
    from tests.conftest import design_path

    text = re.sub(r'^kind = .*$', 'kind = "reduced_observer"', design_path("bench-recommended").read_text(),
                  flags=re.M)
    (tmp_path / "two.toml").write_text(text + '\n[patch]\nunits = "auto"\n')
    spec = load_spec(str(tmp_path / "two.toml"))
    machine = load_machine(spec.machine)
    net = build_patch(design_on(spec, machine, load_bench(spec.bench)), machine)
    steps = {s.pot: s for s in sign_check(net, machine)}
    assert net.units == 2 and set(steps) == {p.id for p in net.pots}
    p2 = steps["U1.P2"]
    assert (p2.drive.kind, p2.drive.target, p2.read) == ("hand", "theta", "U1.A6")
    assert np.sign(_expected(net, p2)) == p2.expect == -np.sign(_expected(net, p2, flip="U1.P2"))
