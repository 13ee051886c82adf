"""The held fraction's 95 % interval (Wilson) against scipy's, and the sequential decision."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.stats import binomtest

from patchgen.studies.ranking import TARGET, ScenarioOutcome, decision, weakest, wilson


@given(st.integers(1, 5000).flatmap(lambda n: st.tuples(st.integers(0, n), st.just(n))))
def test_wilson_interval_is_scipys(held_runs):
    held, runs = held_runs
    ref = binomtest(held, runs).proportion_ci(confidence_level=0.95, method="wilson")
    lo, hi = wilson(held, runs)
    assert lo == pytest.approx(ref.low, abs=1e-12) and hi == pytest.approx(ref.high, abs=1e-12)
    assert 0.0 <= lo <= held / runs <= hi <= 1.0


def test_wilson_at_the_ends_has_its_closed_form():
    z2 = 1.959963984540054 ** 2
    for n in (1, 40, 80, 200):
        assert wilson(n, n)[0] == pytest.approx(n / (n + z2), rel=1e-12)  # all held
        assert wilson(0, n)[1] == pytest.approx(z2 / (n + z2), rel=1e-12)  # none held
    # every run held: the lower end first passes 0.95 at 73 runs
    assert min(n for n in range(1, 200) if wilson(n, n)[0] >= TARGET) == math.ceil(TARGET * z2 / (1 - TARGET))


@pytest.mark.parametrize("held, runs", [(-1, 10), (11, 10), (0, 0)])
def test_wilson_refuses_impossible_counts(held, runs):
    with pytest.raises(ValueError):
        wilson(held, runs)


def _o(name, held, runs):
    return ScenarioOutcome(name, runs, held, runs - held, 0, 0, 0.0)


def test_decision_needs_every_scenario_clear():
    assert decision([_o("a", 80, 80), _o("b", 80, 80)]) == "holds"
    assert decision([_o("a", 80, 80), _o("b", 79, 80)]) == "undecided"  # 79/80: lower end 0.933
    assert decision([_o("a", 80, 80), _o("b", 30, 40)]) == "fails"  # 30/40: upper end 0.86
    assert decision([]) == "undecided"
    assert weakest([_o("a", 80, 80), _o("b", 30, 40)]).scenario == "b"
