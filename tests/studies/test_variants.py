"""The spec's variants recommend tries when none of its own realisations holds, and the departures
a realisation names: which integral the force cannot move, each change as a valid spec, the tiers
nearest first, and every changed field found and explained."""

import numpy as np
import pytest

from patchgen.design.lqg import design_on
from patchgen.design.model import build_model
from patchgen.design.weights import q_matrix
from patchgen.inputs.spec import check_spec, load_spec
from patchgen.inputs.spec_file import spec_toml
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.studies import variants
from patchgen.studies.departures import Departure, departures, flat, grouped, settled_spec, value_text

GP6, BENCH = load_machine("gp6"), load_bench("uw-1991")


def _reread(spec, tmp_path):
    """A spec written as TOML and read back: what recommended.toml would be."""
    p = tmp_path / "v.toml"
    p.write_text(spec_toml(spec))
    return load_spec(p)


def test_the_integral_of_theta_is_conserved_and_the_integral_of_s_is_not():
    """The plant conserves a combination of theta, s_dot, theta_dot and the integral of theta (no
    force changes it), so a pure integrator of theta leaves a pole on the axis; the integral of s
    the force does move."""
    case1 = load_spec("thesis-case1")  # both integrals
    found = variants.conserved_integrals(case1)
    assert list(found) == ["int_theta"]
    assert found["int_theta"] == "-0.0007336 theta - 0.102 s_dot - 0.04374 theta_dot + int_theta"
    # the combination as printed is a left null vector of [A B] with the leak taken out
    pure = case1.model_copy(update={"integrators": case1.integrators.model_copy(update={"int_theta_leak": 0.0,
                                                                                       "int_s": False})})
    model = build_model(pure)
    w = np.array([0.0, -0.0007336, -0.102, -0.04374, 1.0])
    assert np.abs(w @ np.hstack([model.A, model.B])).max() < 5e-4  # to the digits printed (measured 1.4e-4)
    assert variants.conserved_integrals(load_spec("bench-recommended")) == {}  # no integrals
    assert list(variants.conserved_integrals(load_spec("thesis-ch5"))) == ["int_theta"]


def test_dropping_an_integral_takes_its_weight_in_every_form_and_stays_a_valid_spec(tmp_path):
    case1 = load_spec("thesis-case1")
    d = variants.drop_integral(case1, "int_theta")
    assert d.states() == ["s", "theta", "s_dot", "theta_dot", "int_s"]
    assert d.weights.Q == {"s": 25.0, "theta": 100.0, "s_dot": 25.0, "theta_dot": 100.0, "int_s": 25.0}
    assert _reread(d, tmp_path).integrators.int_theta is False
    # a full Q loses the integral's row and column; the others keep their places
    full = case1.model_copy(update={"weights": case1.weights.model_copy(update={"Q": q_matrix(case1).tolist()})})
    check_spec(full)
    dq = variants.drop_integral(full, "int_theta")
    assert np.array_equal(np.array(dq.weights.Q), np.diag([25.0, 100.0, 25.0, 100.0, 25.0]))
    check_spec(dq)
    # Bryson excursions lose the integral's
    br = load_spec("bench-recommended")
    br = br.model_copy(update={"integrators": br.integrators.model_copy(update={"int_theta": True}),
                               "weights": br.weights.model_copy(update={"bryson": {**br.weights.bryson,
                                                                                   "int_theta": 0.1}})})
    check_spec(br)
    db = variants.drop_integral(br, "int_theta")
    assert db.weights.bryson == {"s": 0.4, "theta": 0.01, "s_dot": 0.3, "u": 3.0}
    check_spec(db)


def test_tightening_theta_scales_its_weight_by_the_step_squared():
    ch5 = load_spec("thesis-ch5")
    assert variants.tighten_theta(ch5, 4.0).weights.Q["theta"] == 1600.0  # 100 x 16
    assert variants.tighten_theta(ch5, 4.0).weights.Q["s"] == 25.0
    br = load_spec("bench-recommended")
    assert variants.tighten_theta(br, 2.0).weights.bryson == {"s": 0.4, "theta": 0.005, "s_dot": 0.3, "u": 3.0}
    full = ch5.model_copy(update={"weights": ch5.weights.model_copy(update={"Q": q_matrix(ch5).tolist()})})
    t = np.array(variants.tighten_theta(full, 2.0).weights.Q)
    assert np.array_equal(t, q_matrix(ch5) * np.outer([1, 2, 1, 1, 1], [1, 2, 1, 1, 1]))  # theta's row and column x2
    none = ch5.model_copy(update={"weights": ch5.weights.model_copy(update={"Q": {**ch5.weights.Q, "theta": 0.0}})})
    assert variants.tighten_theta(none, 2.0) is None  # no weight to tighten


def test_below_dial_sees_the_thesis_minimum_setting():
    """thesis-ch5 sets its integral of theta's coefficient (3.2e-5 / (4.19 x 14.01), far below the
    dial's 0.001) to the dial's minimum; bench-recommended dials nothing below it."""
    assert variants.below_dial(design_on(load_spec("thesis-ch5"), GP6, BENCH), GP6)
    assert not variants.below_dial(design_on(load_spec("bench-recommended"), GP6, BENCH), GP6)


def test_tiers_go_nearest_first():
    """Each structural change alone, then both, with the spec's weights; then for each step of
    theta's weight: the weights alone, with one change, with both."""
    ch5 = load_spec("thesis-ch5")
    names = [[v.name for v in tier] for tier in variants.tiers(ch5, GP6, BENCH, below=True)]
    one = ["int_theta dropped", "coefficients below the dial left out"]
    both = ["int_theta dropped, coefficients below the dial left out"]
    expected = [one, both]
    for q in (4, 16, 64):
        expected += [[f"theta weighted x{q}"], [f"{n}, theta weighted x{q}" for n in one],
                     [f"{both[0]}, theta weighted x{q}"]]
    assert names == expected
    # nothing below the dial: no change of the dial policy is offered
    assert [[v.name for v in t] for t in variants.tiers(ch5, GP6, BENCH, below=False)][:2] == [
        ["int_theta dropped"], ["theta weighted x4"]]
    # no integral and nothing below the dial: only the weights
    br = load_spec("bench-recommended")
    assert [[v.name for v in t] for t in variants.tiers(br, GP6, BENCH, below=False)] == [
        ["theta weighted x4"], ["theta weighted x16"], ["theta weighted x64"]]


def test_every_variant_is_a_valid_spec_with_every_change_explained(tmp_path):
    ch5 = load_spec("thesis-ch5")
    for tier in variants.tiers(ch5, GP6, BENCH, below=True):
        for v in tier:
            check_spec(v.spec)
            assert _reread(v.spec, tmp_path).model_dump() == v.spec.model_dump()
            deps = departures(ch5, v.spec, v.whys)  # raises on a change with no reason
            assert deps and all(d.why for d in deps)
    v = variants.tiers(ch5, GP6, BENCH, below=True)[0][0]
    assert [(d.field, d.was, d.now) for d in departures(ch5, v.spec, v.whys)] == [
        ("weights.Q.int_theta", 100.0, None), ("integrators.int_theta", True, False)]


def test_departures_are_found_by_comparing_fields_and_open_fields_are_not_departures():
    ch5 = load_spec("thesis-ch5")
    est = ch5.estimator.model_copy(update={"kind": "reduced_observer", "rolloff_s": None, "observer_pole": 14.1})
    sp = ch5.model_copy(update={"estimator": est, "name": "another"})  # a label is not a departure
    deps = departures(ch5, sp, {"estimator": "why"})
    # observer_pole was left open (unset) by the spec: choosing it is what the spec asked
    assert [(d.field, d.was, d.now) for d in deps] == [("estimator.kind", "differentiator", "reduced_observer"),
                                                      ("estimator.rolloff_s", 0.01, None)]
    with pytest.raises(ValueError, match="estimator.kind departs from the spec"):
        departures(ch5, sp, {"actuator": "why"})
    d = Departure("weights.Q.int_theta", 100.0, None, "its weight goes with the state")
    assert d.line() == "weights.Q.int_theta 100 -> not set: its weight goes with the state"
    assert d.as_dict() == {"field": "weights.Q.int_theta", "from": 100.0, "to": None,
                           "why": "its weight goes with the state"}
    assert [value_text(x) for x in (True, 0.2, "lag", [1.0, 2.0])] == ["true", "0.2", '"lag"', "[1, 2]"]
    same = (Departure("a", 1, 2, "w"), Departure("b", 3, 4, "w"), Departure("c", 5, 6, "x"))
    assert grouped(same) == ["a 1 -> 2, b 3 -> 4: w", "c 5 -> 6: x"]
    assert "name" not in flat(ch5) and flat(ch5)["weights.Q.int_theta"] == 100.0


def test_the_settled_spec_fixes_what_the_design_chose_and_the_units():
    br = load_spec("bench-recommended")
    d = design_on(br, GP6, BENCH)
    s = settled_spec(br, d, 2)
    assert s.estimator.rolloff_s == d.estimator.rolloff_s and d.estimator.chosen_from_noise
    assert s.patch.units == 2
    assert departures(br, s, {"patch.units": "two units"}) == (Departure("patch.units", 1, 2, "two units"),)


def test_none_chosen_names_the_worst_corner_when_the_drawn_runs_held():
    """A realisation that held in 97 % of the runs drawn over the bench's ranges but in none at a
    corner is refused for the corner, and the verdict says so (not that 97 % is too few)."""
    from patchgen.render.recommendation_files import verdict_text
    from patchgen.studies.bench_corners import BenchStudy, CornerOutcome
    from patchgen.studies.candidate import Candidate, Recommendation
    from patchgen.studies.ranking import ScenarioOutcome

    held = ScenarioOutcome("hold-120s", 200, 194, 0, 6, 0, 1.0)
    corner = CornerOutcome({"tau": 0.3}, ScenarioOutcome("hold-120s", 64, 0, 0, 64, 0, 1.0))
    st = BenchStudy("hold-120s", {"tau": (0.1, 0.3)}, "uniform", None, (corner,), ())
    c = Candidate("filtered differentiator", "filtered_differentiator", None, None, None, None,
                  bench_loop="stable", outcomes=(held,), bench_study=st)
    rec = Recommendation(load_spec("thesis-ch5"), (), 200, None, (c,), {"tau": (0.1, 0.3)}, variants=("v",))
    assert rec.best is None
    assert verdict_text(rec) == (
        "None chosen: the best realisation with a loop stable on the bench (nor in its one variant tried), "
        "filtered differentiator, held in only 0.0% of the runs at the worst corner of the bench's ranges (at least "
        "95% at every corner is needed).")
