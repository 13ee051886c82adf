"""The sheet's 'predicted on the bench' on its own: how runs are summed up, the table's text, runs
already made standing in for new ones, and the linearised verdict."""

from __future__ import annotations

import pytest

from patchgen.bench.diagnosis import diagnose
from patchgen.bench.prediction import STANDARD, Prediction, predict
from patchgen.bench.results import Overload, RunSummary
from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.pipeline.prediction import BenchPrediction
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.render.bench_sheet import diagnosis_note, failure_banner, prediction_rows

GP6 = load_machine("gp6")
BENCH = load_bench("uw-1991")


@pytest.fixture(scope="module")
def patch():
    spec = load_spec("bench-recommended")
    return build_patch(design_on(spec, GP6, BENCH), GP6), plant_params(spec)


def _run(i: int, held: bool = True, theta: float = 1.0, s: float = 0.1, trip: float | None = None,
         fall: float | None = None, overloads: tuple[str, ...] = ()) -> RunSummary:
    return RunSummary(run=i, held=held, limit_switch_tripped=trip is not None, trip_time_s=trip,
                      fallen=fall is not None, fall_time_s=fall, max_abs_theta_deg=theta, max_abs_s_m=s,
                      rms_theta_deg=0.1, max_abs_u_c_V=1.0, max_abs_force_N=5.0, actuator_limit_time_s=0.0,
                      overloads=tuple(Overload(a, 1.0, 0.01) for a in overloads), final_state=(0.0, 0.0, 0.0, 0.0))


def test_runs_already_made_are_summed_up(patch):
    net, plant = patch
    hold = [_run(0, theta=2.0), _run(1, held=False, trip=3.5, theta=9.0, s=0.545, overloads=("A8", "A7")),
            _run(2, overloads=("A7",)), _run(3, held=False, fall=1.25, theta=30.0)]
    done = {"hold-120s": hold + [_run(4, theta=99.0)],  # one run more than asked for: ignored
            **{name: [_run(0, s=0.2)] for name in STANDARD if name != "hold-120s"}}
    got = predict(net, plant, BENCH, GP6, runs_hold=4, done=done)
    assert [p.scenario for p in got] == list(STANDARD)
    h = got[-1]
    assert (h.runs, h.fraction_held, h.max_theta_deg, h.max_s_m) == (4, 0.5, 30.0, 0.545)
    assert h.first_trip_s is None and h.first_fall_s is None  # run 0's events, not the others'
    assert h.overloads == "A7, A8" and got[0].overloads == "none"
    assert h.description == load_scenario("hold-120s").description


def test_a_run_made_before_is_the_run_made_now(patch):
    net, plant = patch
    fresh = predict(net, plant, BENCH, GP6, scenarios=("step-cart",))
    sc = load_scenario("step-cart")
    before = simulate(net, plant, BENCH, GP6, sc, runs=1, keep_history=False).runs
    assert predict(net, plant, BENCH, GP6, scenarios=("step-cart",), done={"step-cart": before}) == fresh
    (p,) = fresh
    assert p.runs == 1 and p.fraction_held == 1.0 and p.first_trip_s is None
    # the command steps the cart by 0.2 m: it travels at least that far, with the pendulum held near upright
    assert 0.2 <= p.max_s_m < 0.5 and p.max_theta_deg < 2.0


def test_rows_are_the_sheet_text():
    preds = [Prediction("hold-120s", "hold", 20, 0.95, None, None, 1.2345, 0.12345, "none"),
             Prediction("step-cart", "step", 1, 0.0, 2.345, 3.0, 45.0, 0.5449, "A7, A8")]
    header, rows = prediction_rows(preds)
    assert len(header) == len(rows[0]) == 8
    assert rows[0] == ["hold-120s", "20", "95 %", "no", "no", "1.23", "0.123", "none"]
    assert rows[1] == ["step-cart", "1", "0 %", "at 2.35 s", "at 3.00 s", "45.00", "0.545", "A7, A8"]


def test_diagnosis_note_gives_both_actuators_verdicts(patch):
    net, plant = patch
    pred = BenchPrediction((), tuple(diagnose(net, plant, BENCH)), None, 1)
    note = diagnosis_note(pred)
    assert note.startswith("Linearised: wired loop with the ideal actuator (pure gain K_U): stable")
    assert "; wired loop with the bench actuator (lag 0.2 s): stable (rightmost pole -0." in note
    assert note.endswith(" 1/s).") and "UNSTABLE" not in note


def test_the_banner_names_each_failing_scenario(patch):
    net, plant = patch
    loops = tuple(diagnose(net, plant, BENCH))
    held = Prediction("hold-120s", "hold", 20, 0.95, None, None, 1.0, 0.1, "none")
    failed = Prediction("step-cart", "step", 20, 0.9, None, 3.0, 45.0, 0.5, "A7")
    assert BenchPrediction((held,), loops, None, 20).holds
    assert failure_banner("uw-1991", BenchPrediction((held,), loops, None, 20)) == ""
    pred = BenchPrediction((held, failed), loops, None, 20)
    assert not pred.holds and pred.failing == (failed,)
    assert failure_banner("uw-1991", pred) == ("Predicted to fail on the uw-1991 bench: held in step-cart 90 % of "
                                               "runs. See 'Predicted on the bench'.")


def test_a_small_hold_run_in_parts_is_the_hold_run_whole(patch):
    """The hold's 20 runs, two parts of 10 on two threads, are the 20 runs of one call, in order."""
    import numba

    from patchgen.bench.prediction import _side_by_side

    assert _side_by_side(lambda first, n: list(range(first, first + n)), 20) == list(range(20))
    net, plant = patch
    sc = load_scenario("hold-120s").model_copy(update={"duration_s": 3.0})
    whole = simulate(net, plant, BENCH, GP6, sc, runs=20, keep_history=False).runs
    threads = numba.get_num_threads()
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    try:
        parts = _side_by_side(lambda first, n: simulate(net, plant, BENCH, GP6, sc, runs=n, first_run=first,
                                                        keep_history=False).runs, 20)
    finally:
        numba.set_num_threads(threads)
    assert parts == whole and [r.run for r in parts] == list(range(20))


def test_signal_levels_are_each_amplifiers_largest_output_over_every_run(patch):
    """The sheet's signal levels: each amplifier's largest |output| over every scenario's runs (the
    hold's Monte Carlo included, run by run as simulate gives them), its share of the reference
    and its ratio to the machine's noise floor in dB; bench-recommended's actuator state uses
    little of its range (measured: 12.7 % at most, in offset-10deg), and the sheet says so."""
    import math

    from patchgen.pipeline.prediction import amplifier_levels, noise_floor_V
    from patchgen.render.bench_sheet import LOW_SHARE, levels_section

    net, plant = patch
    preds = predict(net, plant, BENCH, GP6, runs_hold=4)
    pred = BenchPrediction(tuple(preds), (), None, 4)
    hold = simulate(net, plant, BENCH, GP6, load_scenario("hold-120s"), runs=4, keep_history=False)
    offset = simulate(net, plant, BENCH, GP6, load_scenario("offset-10deg"), runs=1, keep_history=False)
    levels = amplifier_levels(net, GP6, pred.peaks_V())
    assert [lv.amplifier for lv in levels] == [a.id for a in net.amplifiers]
    floor = noise_floor_V(GP6)
    assert floor == math.hypot(GP6.imperfections.amplifier_noise_V_rms, GP6.imperfections.integrator_offset_V)
    for lv in levels:
        assert lv.peak_V >= max(r.amp_peak(lv.amplifier) for r in hold.runs + offset.runs)
        assert lv.peak_share == lv.peak_V / GP6.reference_V
        assert lv.snr_dB == pytest.approx(20 * math.log10(lv.peak_V / floor), rel=1e-12)
    actuator = next(lv for lv in levels if lv.quantity == "actuator")
    assert 0.1 < actuator.peak_share < 0.15 and actuator.peak_V == offset.runs[0].amp_peak(actuator.amplifier)
    sec = levels_section(BenchPrediction(tuple(preds), (), None, 4, levels), net)
    marked = {row[0] for row in sec.rows if row[-1] == "low"}
    assert marked == {lv.amplifier for lv in levels if lv.peak_share < LOW_SHARE}
