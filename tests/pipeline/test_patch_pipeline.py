"""patchgen patch's pipeline function: the patch it returns is the stages' own, and its bench
prediction is the simulator's, scenario for scenario."""

from __future__ import annotations

from patchgen.bench.diagnosis import diagnose
from patchgen.bench.prediction import predict
from patchgen.design.lqg import design_on
from patchgen.patch.build import build_patch
from patchgen.pipeline.inputs import load_inputs
from patchgen.pipeline.patch import PatchPlan, run_patch
from patchgen.pipeline.scaling import scaled_patch


def test_the_report_is_the_stages_patch_and_prediction():
    inputs = load_inputs("bench-recommended")
    spec, machine, bench = inputs
    bare = run_patch(inputs, PatchPlan(predict=False))
    d = design_on(spec, machine, bench)
    net = scaled_patch(d, machine, bench).netlist
    assert net != build_patch(d, machine)  # scaled for signal-to-noise over the bench's envelope
    assert bare.netlist == net and bare.prediction is None
    assert bare.summary()["prediction"] is None and bare.summary()["margins"] == bare.judged.as_dict()
    report = run_patch(inputs, PatchPlan(runs_hold=3))
    pred = report.prediction
    assert report.netlist == net and pred.runs_hold == 3 and pred.corners is None  # uw-1991 states no ranges
    assert pred.predictions == tuple(predict(net, report.design.plant, bench, machine, runs_hold=3))
    assert [lp.verdict for lp in pred.loops] == [lp.verdict for lp in diagnose(net, report.design.plant, bench)]
    assert pred.holds == (pred.loops[-1].verdict == "stable" and all(p.fraction_held >= 0.95
                                                                      for p in pred.predictions))


def test_a_bench_with_ranges_is_predicted_at_its_corners_too():
    inputs = load_inputs("bench-recommended", "uw-1991-uncertain")
    pred = run_patch(inputs, PatchPlan(runs_hold=2)).prediction
    assert pred.corners is not None and pred.corners.scenario == "hold-120s"
    assert set(pred.corners.ranges) == set(inputs.bench.uncertainty.ranges) or pred.corners.at_nominal
    assert pred.summary()["bench_spread"] == pred.corners.as_dict()


def test_the_prediction_is_the_same_from_a_worker_process_and_a_thread():
    """The sheet's prediction made by a forked worker (a process of one thread, as the command line
    is) and by a thread (any other process) is the same prediction; with a thread of its own
    running, the worker is a thread."""
    import concurrent.futures
    import threading

    from patchgen.pipeline.prediction_worker import PredictionWorker

    inputs = load_inputs("bench-recommended")
    report = run_patch(inputs, PatchPlan(predict=False))
    args = (report.design, report.netlist, inputs.machine, inputs.bench, 4)
    forked = concurrent.futures.ProcessPoolExecutor  # what the worker starts from a one-thread process
    results = {}
    for label in ("alone", "with a thread"):
        stop = threading.Event()
        other = threading.Thread(target=stop.wait) if label == "with a thread" else None
        if other is not None:
            other.start()
        try:
            worker = PredictionWorker()
            results[label] = (isinstance(worker._pool, forked), worker.predict(*args).result().summary())
        finally:
            stop.set()
            if other is not None:
                other.join()
    assert results["with a thread"][0] is False
    assert results["alone"][0] is (threading.active_count() == 1 and __import__("sys").platform.startswith("linux"))
    assert results["alone"][1] == results["with a thread"][1]
    assert results["alone"][1]["runs_hold"] == 4 and len(results["alone"][1]["scenarios"]) == 4


def test_the_command_lines_process_forks_its_worker():
    """A process of one thread, as patchgen's command line is, on Linux: the worker is a process."""
    import subprocess
    import sys

    code = ("import concurrent.futures as c; from patchgen.pipeline.prediction_worker import PredictionWorker; "
            "w = PredictionWorker(); print(isinstance(w._pool, c.ProcessPoolExecutor)); w.cancel()")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == str(sys.platform.startswith("linux"))
