"""ngspice against patchgen on the rotary pendulum: the QUBE-Servo 2's patch and plant as a deck
(the motor's voltage on the force node, its equations as behavioural sources), the ideal runs
agreeing within 1 % of peak, a deck with its pendulum's weight reversed not agreeing, and the
noisy run judged against the bench Monte Carlo."""

from __future__ import annotations

import dataclasses
import shutil

import pytest

from patchgen.inputs.scenario import load_scenario
from patchgen.pipeline.inputs import load_inputs, scenario_for
from patchgen.pipeline.spice import SpicePlan, run_spice, spice_job
from patchgen.spice.deck import spice_deck

pytestmark = pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not on the PATH")
QUBE = "qube-servo-2"


def _job(scenario: str, ideal: bool):
    inputs = load_inputs(QUBE, command="spice")
    return spice_job(inputs, scenario_for(scenario, inputs.spec), SpicePlan(ideal=ideal))


@pytest.mark.parametrize("scenario", ["qube-release-5deg", "qube-tap", "qube-hold-60s"])
def test_the_ideal_deck_agrees_with_patchgen(scenario):
    """Scenarios in which the patch stays inside its rails (the arm's step asks u_c past them, where
    the deck's amplifiers bound softly and patchgen's ideal run does not clip)."""
    job = _job(scenario, ideal=True)
    deck = job.deck.text
    assert "B_add x_add 0 V = " in deck and "x_alpha" in deck and "x_s " not in deck
    assert ("V_dist_0 dist_0 0 PWL(" in deck) == bool(load_scenario(scenario).disturbances)
    report = run_spice(job)
    assert set(report.comparison.signals) == {"alpha", "theta"}
    for name, s in report.comparison.signals.items():
        assert s.peak > 1e-3 and s.max_rel < 0.01, (name, s)
    assert report.agrees


def test_a_deck_whose_pendulum_falls_the_wrong_way_does_not_agree():
    """The weight's term in the pendulum's equation reversed (hanging becomes the balance point):
    the same patch, the same comparison, and it no longer agrees."""
    job = _job("qube-tap", ideal=True)
    text = job.deck.text
    line = next(ln for ln in text.splitlines() if ln.startswith("B_thdd "))
    G = job.plant.m_p * job.plant.g * job.plant.pendulum_com()
    wrong = line.replace(f" + {G!r}*sin(", f" - {G!r}*sin(")
    assert wrong != line
    bad = dataclasses.replace(job, deck=dataclasses.replace(job.deck, text=text.replace(line, wrong)))
    assert not run_spice(bad).agrees


def test_the_noisy_deck_is_judged_against_the_monte_carlo():
    job = _job("qube-release-5deg", ideal=False)
    report = run_spice(job)
    verdict = report.statistical
    assert verdict is not None and verdict.agrees and verdict.held and verdict.fraction_held == 1.0
    assert "E_force_cart_noise" in job.deck.text  # the arm's random torque, on the position's channel


def test_the_deck_is_the_same_bytes_for_the_same_seed():
    job = _job("qube-hold-60s", ideal=False)
    again = spice_deck(job.netlist, job.plant, job.bench, job.machine, job.settings)
    assert again.text == job.deck.text and again.files == job.deck.files
