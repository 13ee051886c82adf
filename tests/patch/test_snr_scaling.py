"""Scaling for signal-to-noise: the law is unchanged, every limit holds, and no block could be
made larger without passing one (the programme's optimum, checked from the outside)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from patchgen.inputs.errors import ResourceError
from patchgen.patch.build import build_patch
from patchgen.patch.readback import wired_law
from patchgen.patch.realization import realize
from patchgen.patch.snr_scaling import FIXED, HEADROOM, SCALE_WORTH, BlockPeak, dial_floor, rescaled, snr_scales
from patchgen.profiles.machine import load_machine
from tests.conftest import design_from_path, design_path

# the law as its states: a differentiator with a lag state, an integral state, a Kalman estimator
NAMES = ("bench-recommended", "thesis-ch5", "quanser-ip02")
W = np.logspace(-1, 2.5, 12)  # rad/s, across every crossover of the shipped loops


@pytest.fixture(scope="module", params=[(n, m) for n in NAMES for m in ("gp6", "the-analog-thing")],
                ids=lambda p: f"{p[0]}-{p[1]}")
def case(request):
    name, machine = request.param
    d, _ = design_from_path(design_path(name))
    m = load_machine(machine)
    return d, m, realize(d, m)


def _limits_hold(real, scaled, alpha, peaks, m):
    """Every limit of the module's docstring, read off the scaled realisation."""
    top, floor = max(m.input_weights) * m.pot_max, dial_floor(m)
    for name, a in alpha.items():
        p = peaks.get(name)
        if p is not None and p.least > 0 and name not in FIXED:
            if p.most > HEADROOM * m.reference_V:  # brought down, never past HEADROOM
                assert HEADROOM * m.reference_V * (1 - 1e-5) <= a * p.most <= p.most, name
            else:
                assert 1.0 <= a and a * p.most <= HEADROOM * m.reference_V * (1 + 1e-9), name
        else:
            assert a == 1.0, name
    for before, after in zip(real.blocks, scaled.blocks):
        for t0, t1 in zip(before.terms, after.terms):
            c0, c1 = abs(t0.coeff), abs(t1.coeff)
            if before.kind == "differentiate" or c0 == 0.0:
                continue
            assert c1 <= max(top, c0) * (1 + 1e-9), (before.name, t0.signal)
            assert c1 >= min(floor, c0) * (1 - 1e-9), (before.name, t0.signal)
            if any(c0 == w for w in m.input_weights):
                assert c1 == pytest.approx(c0, rel=1e-9), (before.name, t0.signal)


def _no_block_can_grow(real, alpha, peaks, m):
    """Stage 2's optimum, from outside: each block scaled up is at least SCALE_WORTH larger (less
    is not worth re-dialling: it keeps its scale), and 0.01 % more passes some limit."""
    for name, a in alpha.items():
        p = peaks.get(name, BlockPeak(0, 0))
        if name in FIXED or p.least <= 0 or p.most > HEADROOM * m.reference_V or a == 1.0:
            continue
        assert a >= SCALE_WORTH * (1 - 1e-9), (name, a)
        bigger = {**alpha, name: a * 1.0001}
        with pytest.raises(AssertionError):
            _limits_hold(real, rescaled(real, bigger), bigger, peaks, m)


@settings(max_examples=30, deadline=None)
@given(data=st.data())
def test_random_envelopes_keep_every_limit_and_reach_one(case, data):
    d, m, real = case
    peaks = {b.name: BlockPeak(*sorted(data.draw(st.tuples(*[st.floats(1e-3, 1.5 * m.reference_V)] * 2))))
             for b in real.blocks}
    alpha = snr_scales(real, peaks, m).factors
    assert set(alpha) == {b.name for b in real.blocks} and alpha["u_c"] == 1.0
    scaled = rescaled(real, alpha)
    _limits_hold(real, scaled, alpha, peaks, m)
    _no_block_can_grow(real, alpha, peaks, m)
    # the worst free block's share of the reference is never lowered unless its own peak had to come down
    free = [n for n in alpha if n not in FIXED]
    if free and all(peaks[n].most <= HEADROOM * m.reference_V for n in free):
        assert min(alpha[n] * peaks[n].least for n in free) >= min(peaks[n].least for n in free) * (1 - 1e-9)


def test_the_scaled_patch_wires_the_same_law(case):
    """Through the whole patch stage: the law read back from the netlist, within the dial's
    quantisation, is the law of the unscaled patch, while each scaled block's amplifier carries
    its signal at the new volts per unit."""
    d, m, real = case
    peaks = {b.name: BlockPeak(0.05 * m.reference_V, 0.1 * m.reference_V) for b in real.blocks}
    alpha = snr_scales(real, peaks, m).factors
    assert any(a > 1.5 for n, a in alpha.items() if n not in FIXED), alpha  # 10 % is far below the headroom
    plain, scaled = build_patch(d, m), build_patch(d, m, scales=alpha)
    g0, g1 = wired_law(plain).freqresp(W), wired_law(scaled).freqresp(W)
    # each pot is within half a dial step of its coefficient: the laws differ by the steps alone
    assert np.abs(g1 - g0).max() <= 0.01 * np.abs(g0).max(), np.abs(g1 - g0).max() / np.abs(g0).max()
    vpu = {b.name: b.volts_per_unit for b in real.blocks}
    for a in scaled.amplifiers:
        q = a.carries.quantity
        if q in vpu and q not in FIXED:
            assert a.carries.volts_per_unit == pytest.approx(vpu[q] * alpha[q], rel=1e-9), a.id


def test_bench_recommendeds_actuator_state_uses_twice_the_range():
    """The measured envelope of bench-recommended on uw-1991 (offset-10deg, the largest of the
    standard scenarios for both blocks: the actuator state 1.28 V, theta_dot 4.16 V): the actuator
    state doubles (its u_c input then at the x10 input's top), theta_dot rises to HEADROOM."""
    d, _ = design_from_path(design_path("bench-recommended"))
    m = load_machine("gp6")
    real = realize(d, m)
    scaling = snr_scales(real, {"actuator": BlockPeak(1.28, 1.28), "theta_dot": BlockPeak(4.16, 4.16)}, m)
    alpha = scaling.factors
    assert scaling.why == {"actuator": "actuator's coefficient on u_c at the largest weighted input (10)",
                           "theta_dot": "its predicted peak at 80 % of the reference"}
    assert alpha["actuator"] == pytest.approx(2.0, rel=1e-5)
    assert alpha["theta_dot"] * 4.16 == pytest.approx(HEADROOM * m.reference_V, rel=1e-5)
    u_c = rescaled(real, alpha).block("u_c")
    assert math.isclose(abs(next(t.coeff for t in u_c.terms if t.signal == "actuator")), 3.5201 / 2, rel_tol=1e-3)


def test_an_amplifier_belongs_to_its_block_its_gain_stages_or_a_stage_of_its_own():
    """A gain stage scales with its block; a partial sum and a sensor's inverter have scales of their own."""
    from patchgen.patch.snr_scaling import block_of, block_peaks

    assert [block_of(q) for q in ("actuator", "partial u_c", "theta_x1.42", "xhat_theta_x12", "c2_in")] == \
        ["actuator", "u_c", "theta", "xhat_theta", "c2_in"]
    d, _ = design_from_path(design_path("bench-recommended"))
    real = realize(d, load_machine("gp6"))
    got = block_peaks(real, {"A1": "actuator", "A5": "theta_dot", "A6": "u_c", "A7": "partial u_c", "A9": "theta_x2",
                             "A2": "s", "A3": "theta_dot_x10"},
                      {"A1": 1.0, "A5": 4.0, "A6": 6.0, "A7": 7.0, "A9": 9.0, "A2": 2.0, "A3": 8.0})
    assert got == {"actuator": BlockPeak(1.0, 1.0), "theta_dot": BlockPeak(4.0, 8.0), "u_c": BlockPeak(6.0, 6.0),
                   "partial u_c": BlockPeak(7.0, 7.0), "inverted s": BlockPeak(2.0, 2.0)}


def test_a_partial_sum_and_a_sensors_inverter_take_scales_of_their_own(case):
    """The stages the allocation adds: a partial sum past the reference comes down towards
    HEADROOM and a sensor's inverter at 5 % rises, each on a pot of its own, the law read back unchanged
    (within the dial's steps) and each stage's amplifier carrying its signal at its new scale."""
    from patchgen.patch.snr_scaling import INVERTED, PARTIAL, block_peaks
    from patchgen.pipeline.scaling import partial_sums, sensor_inverters

    d, m, real = case
    plain = build_patch(d, m)
    parts, inverters = partial_sums(plain), sensor_inverters(plain)
    if not parts and not inverters:
        pytest.skip("this patch has neither a partial sum nor a sensor's inverter")
    ref = m.reference_V
    volts = {a.id: (1.5 if a.carries.quantity.startswith(PARTIAL) else 0.05 if a.role == "inverter" else 0.5) * ref
             for a in plain.amplifiers}
    peaks = block_peaks(real, {a.id: a.carries.quantity for a in plain.amplifiers}, volts)
    scaling = snr_scales(real, peaks, m, parts, inverters)
    alpha = scaling.factors
    for b in parts:  # down to HEADROOM, or as far as a coefficient's dial floor lets it (bench-recommended's s)
        p = PARTIAL + b
        assert alpha[p] < 1.0 and (alpha[p] * peaks[p].most == pytest.approx(HEADROOM * ref, rel=1e-5)
                                   or "dial floor" in scaling.why[p]), (b, scaling.why[p])
    for s in inverters:
        assert alpha[INVERTED + s] >= 2.0, s  # raised, as the worst signal at 5 %
    try:
        scaled = build_patch(d, m, scales=alpha)
    except ResourceError as exc:  # each stage scaled takes a pot: two of them are more than THAT's 8
        assert (d.spec.name, m.id) == ("bench-recommended", "the-analog-thing") and "pots" in exc.message
        return
    g0, g1 = wired_law(plain).freqresp(W), wired_law(scaled).freqresp(W)
    assert np.abs(g1 - g0).max() <= 0.01 * np.abs(g0).max()
    for a in scaled.amplifiers:
        q = a.carries.quantity
        if q.startswith(PARTIAL):
            block = real.block(q.removeprefix(PARTIAL))
            assert a.carries.volts_per_unit == pytest.approx(block.volts_per_unit * alpha[q], rel=1e-9)
        elif a.role == "inverter" and q in real.sensors:
            assert a.carries.volts_per_unit == pytest.approx(real.sensors[q] * alpha[INVERTED + q], rel=1e-9)
