"""The ngspice check with the bench's noise and drift on: the deck keeps and writes only the compared
vectors at the output step, those rows are ngspice's own solution there, and the statistical
verdict agrees for a correct patch whatever ngspice's noise seed and disagrees for a mis-set pot
or a scenario that excites nothing."""

import dataclasses
import re
import shutil

import numpy as np
import pytest

from patchgen.inputs.scenario import InitialState, NoiseLevels
from patchgen.patch.netlist import Netlist
from patchgen.pipeline.inputs import load_inputs, scenario_for
from patchgen.pipeline.spice import SpicePlan, run_spice, spice_job
from patchgen.spice.deck import output_vectors, spice_deck
from patchgen.spice.elements import DeckLines
from patchgen.spice.noise import noise_table
from patchgen.spice.run import run_ngspice
from patchgen.spice.verdict import FIGURES, MIN_RMS_THETA_DEG

needs_ngspice = pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not on the PATH")

STEP_S = 0.005


@pytest.fixture(scope="module")
def job():
    """bench-recommended released from 10 deg on the bench, the profiles' noise and drift, 3 s."""
    inputs = load_inputs("bench-recommended")
    sc = scenario_for("offset-10deg", inputs.spec, 1, False).model_copy(update={"duration_s": 3.0})
    return spice_job(inputs, sc, SpicePlan(step_s=STEP_S))


def test_a_noisy_deck_saves_and_writes_only_the_compared_vectors_at_the_step(job):
    text = job.deck.text
    vecs = " ".join(v for _, v in output_vectors(job.netlist))
    assert job.deck.output_step_s == STEP_S
    assert f".save {vecs}\n.options interp\n" in text
    assert f"wrdata patch.data {vecs}\n" in text


def test_an_ideal_deck_writes_every_time_point_ngspice_takes():
    inputs = load_inputs("bench-recommended")
    ideal = spice_job(inputs, scenario_for("offset-10deg", inputs.spec, 1, True), SpicePlan(ideal=True))
    assert ideal.deck.output_step_s is None and not ideal.deck.files
    assert ".save" not in ideal.deck.text and "interp" not in ideal.deck.text


@needs_ngspice
def test_the_rows_read_are_ngspices_own_solution_at_the_compared_points(job, tmp_path):
    at_step = run_ngspice(job.deck, tmp_path / "step")
    n = round(3.0 / STEP_S) + 1
    assert len(at_step.t) == n
    assert np.abs(at_step.t - np.arange(n) * STEP_S).max() < 1e-12
    assert list(at_step.signals) == ["s", "theta", "s_dot", "theta_dot", "u_c", "force"] + [
        a.id for a in job.netlist.amplifiers]
    # the same deck writing every point it takes: the same solution (saving and interpolating the
    # output change nothing ngspice computes), of which the rows above are the values at the step
    own_points = dataclasses.replace(job.deck, text=job.deck.text.replace(".options interp\n", "")
                                     .replace(re.search(r"^\.save .*\n", job.deck.text, re.M).group(0), ""),
                                     output_step_s=None)
    every = run_ngspice(own_points, tmp_path / "every")
    assert len(every.t) > 2 * n
    for name, v in at_step.signals.items():  # measured: 3e-11 of the peak on the plant states, 4e-9 on the rest
        off = np.abs(np.interp(at_step.t, every.t, every.signals[name]) - v).max() / np.abs(every.signals[name]).max()
        assert off < (1e-10 if name in ("s", "theta", "s_dot", "theta_dot") else 1e-8), (name, off)


def _deck(job, net: Netlist, seed: int):
    """The job's deck (its noise process and tolerance) for another netlist or ngspice seed."""
    return spice_deck(net, job.plant, job.bench, job.machine, dataclasses.replace(job.settings, seed=seed))


@pytest.fixture(scope="module")
def release():
    """bench-recommended released from 10 deg, the whole 10 s scenario: the Monte Carlo's spread
    of each figure is narrow enough there for a pot at 90 % to leave it."""
    inputs = load_inputs("bench-recommended")
    return spice_job(inputs, scenario_for("offset-10deg", inputs.spec, 1, False), SpicePlan(step_s=STEP_S))


@needs_ngspice
@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_a_correct_patch_agrees_whatever_ngspices_noise_seed(release, seed):
    """False alarms: the correct patch's deck, each with its own noise, is a plausible Monte
    Carlo run (measured over seeds 1-8: every figure within 0.8 of the Monte Carlo's 5-95 % width
    of its median, where the envelope reaches about 1.85)."""
    report = run_spice(dataclasses.replace(release, deck=_deck(release, release.netlist, seed)))
    v = report.statistical
    assert v.agrees and v.held and v.fraction_held == 1.0, v.reasons()
    for e in v.envelopes.values():
        assert abs(e.value - e.p50) < 1.2 * (e.p95 - e.p5), e
    summary = report.summary()
    assert summary["agrees"] and summary["signals_information_only"] and "tolerance" not in summary
    assert set(summary["verdict"]["figures"]) == set(FIGURES)


def _scaled_theta_pot(net: Netlist, fraction: float) -> Netlist:
    data = net.model_dump(by_alias=True)
    pot = next(p for p in data["pots"] if p["source"] == "theta")
    pot["setting"] = round(fraction * pot["setting"], 3)
    return Netlist.model_validate(data)


@needs_ngspice
@pytest.mark.parametrize(("fraction", "rms_theta_deg"), [(0.7, 5.66), (0.9, 1.716)])
def test_a_mis_set_theta_pot_disagrees(release, fraction, rms_theta_deg):
    """Power: theta's pot at 70 % lets the pendulum fall; at 90 % it holds, but its RMS theta lies
    about 4 of the Monte Carlo's 5-95 % widths above the median (measured 1.716 deg against
    1.567), outside the envelope."""
    wrong = run_spice(dataclasses.replace(release, deck=_deck(release, _scaled_theta_pot(release.netlist, fraction),
                                                              release.scenario.seed)))
    v = wrong.statistical
    assert not v.agrees and not wrong.summary()["agrees"]
    rms = v.envelopes["rms_theta_deg"]
    assert not rms.inside and rms.value == pytest.approx(rms_theta_deg, rel=0.03)
    assert v.held is (fraction > 0.8)


@needs_ngspice
def test_a_quiet_scenario_cannot_agree(tmp_path):
    """No noise, no drift, upright, nothing pushed: any patch sits still, so the check refuses to
    call that agreement."""
    inputs = load_inputs("bench-recommended")
    quiet = scenario_for("offset-10deg", inputs.spec, 1, False).model_copy(update={
        "duration_s": 2.0, "noise": NoiseLevels(mode="off"), "drift": "off", "initial": InitialState()})
    v = run_spice(spice_job(inputs, quiet, SpicePlan(step_s=STEP_S))).statistical
    assert not v.excited and not v.agrees
    assert v.envelopes["rms_theta_deg"].p50 < MIN_RMS_THETA_DEG


def test_the_noise_table_is_each_sample_formatted_as_before():
    """The table written a block at a time is, row by row, time to 9 significant digits and each
    source's sample to 6, as a per-value format gives them; signed zeros, tiny and large values
    included, and a block boundary (4096 rows) crossed."""
    d = DeckLines(np.random.default_rng(3))
    odd = [-0.0, 1e-300, 123456789.0, -2.5e-5]
    d.noise.append(("nz_0", 0.001, np.r_[odd, np.random.default_rng(4).normal(0, 1, 5000)]))
    d.noise.append(("nz_1", 0.004, np.random.default_rng(5).normal(0, 0.01, 1300)))
    text, dt = noise_table(d, 5.0)
    t = np.arange(5001) * 0.001
    cols = [np.interp(t, np.arange(len(v)) * step, v) for _, step, v in d.noise]
    expected = "".join(f"{ti:.9g} " + " ".join(f"{c[k]:.6g}" for c in cols) + "\n" for k, ti in enumerate(t))
    assert dt == 0.001 and text == expected
    assert text.splitlines()[:3] == ["0 -0 " + f"{cols[1][0]:.6g}", "0.001 1e-300 " + f"{cols[1][1]:.6g}",
                                     "0.002 1.23457e+08 " + f"{cols[1][2]:.6g}"]
