"""Allocation on its own: a realization's blocks placed on the GP-6, read back from the netlist."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from patchgen.inputs.errors import ResourceError
from patchgen.patch.allocation import allocate, weight_for
from patchgen.patch.readback import wired_law
from patchgen.patch.realization import Block, Realization, Term
from patchgen.profiles.machine import load_machine

GP6 = load_machine("gp6")
SENSORS = {"s": 5.0, "theta": 4.19, "s_dot": 0.5941}  # table A.2, V per SI unit


def _sum_law(coeffs: dict[str, float]) -> Realization:
    terms = tuple(Term(s, c) for s, c in coeffs.items())
    return Realization("unit", dict(SENSORS), (Block("u_c", "sum", terms, 1.0, "V", "control voltage"),), 14.01,
                       "round")


coefficient = st.floats(0.002, 9.9).flatmap(lambda m: st.sampled_from([m, -m]))


@settings(max_examples=60, deadline=None)
@given(st.dictionaries(st.sampled_from(list(SENSORS)), coefficient, min_size=1)
       .filter(lambda c: sum(abs(v) > 1 for v in c.values()) <= 2))  # the GP-6 summer has two x10 inputs
def test_a_sum_of_sensor_voltages_reads_back_to_its_coefficients(coeffs):
    net = allocate(_sum_law(coeffs), GP6)
    law = wired_law(net)
    assert law.Ac.shape == (0, 0)  # no dynamics in a pure sum
    got = dict(zip(law.inputs, law.Dc[0]))
    for s in SENSORS:
        want = coeffs.get(s, 0.0)
        # a pot is set to the dial's resolution: the realised gain is within half a step x weight
        tol = 0.5 * GP6.pot_resolution * weight_for(abs(want), GP6) + 1e-12
        assert got[s] == pytest.approx(want, abs=tol), (s, got, coeffs)
        assert np.sign(got[s]) == np.sign(want)  # every sign, through every inversion


def test_an_integral_state_wires_an_integrator_with_the_machine_time_scale():
    real = Realization("unit", dict(SENSORS), (
        Block("int_theta", "integrate", (Term("theta", 1.0),), 4.19, "rad s", "integral of theta"),
        Block("u_c", "sum", (Term("theta", -2.5), Term("int_theta", 0.5)), 1.0, "V", "control voltage")),
        14.01, "round")
    net = allocate(real, GP6)
    assert sum(a.role == "integrator" for a in net.amplifiers) == 1
    law = wired_law(net)
    # u_c(jw) / v_theta(jw) = -2.5 + 0.5 / (T jw), T = 1 s
    w = np.array([0.1, 1.0, 10.0])
    theta = law.inputs.index("theta")
    got = law.freqresp(w)[:, theta]
    np.testing.assert_allclose(got, -2.5 + 0.5 / (GP6.time_scale_s * 1j * w), rtol=1e-3)


def test_more_coefficients_than_pots_is_one_line_naming_the_machine():
    blocks = tuple(Block(f"x{i}", "sum", (Term("s", 0.3 + 0.01 * i), Term("theta", 0.4)), 1.0, "V", "filler")
                   for i in range(5))
    real = Realization("unit", dict(SENSORS), blocks + (
        Block("u_c", "sum", tuple(Term(f"x{i}", 0.5) for i in range(5)), 1.0, "V", "control voltage"),), 14.01,
        "round")
    with pytest.raises(ResourceError) as exc:
        allocate(real, GP6, source="unit.toml")
    assert exc.value.field == "machine" and "\n" not in str(exc.value)


def test_weight_is_the_smallest_that_reaches():
    assert weight_for(0.5, GP6) == 1 and weight_for(1.0, GP6) == 1
    assert weight_for(1.0001, GP6) == 10 and weight_for(9.99, GP6) == 10
    assert weight_for(12.0, GP6) == 10  # the largest when none does (the allocator then refuses)


@pytest.mark.parametrize("policy", ["minimum", "round", "omit"])
def test_rounding_noise_is_no_coefficient(policy):
    """A term zero to rounding beside its block gets no pot, whatever the resolution policy."""
    real = Realization("unit", dict(SENSORS), (
        Block("u_c", "sum", (Term("s", 0.3), Term("theta", -2.5), Term("s_dot", 3.9e-16)), 1.0, "V", "control"),),
        14.01, policy)
    net = allocate(real, GP6)
    assert {p.source for p in net.pots} == {"s", "theta"}
    assert any("rounding noise" in n and "s_dot" in n for n in net.notes)
    law = wired_law(net)
    assert dict(zip(law.inputs, law.Dc[0]))["s_dot"] == 0.0


def test_a_small_but_real_coefficient_keeps_the_minimum_setting():
    """Section 5.3's integral gain (5.5e-7 beside 2.67) is tiny but no rounding noise: the thesis
    wired it at the dial's minimum, and so does the 'minimum' policy."""
    real = Realization("unit", dict(SENSORS), (
        Block("u_c", "sum", (Term("theta", -2.67), Term("s", 5.49e-7)), 1.0, "V", "control"),), 14.01, "minimum")
    net = allocate(real, GP6)
    assert {p.source for p in net.pots} == {"s", "theta"}
    assert dict(zip(wired_law(net).inputs, wired_law(net).Dc[0]))["s"] == pytest.approx(GP6.pot_resolution)
