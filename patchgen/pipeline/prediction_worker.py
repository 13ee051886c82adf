"""The sheet's bench prediction in a process of its own, started before the patch is designed.

Starting the simulator is half a second of interpreter work (numba's import and its set-up, then
the kernels from its cache) that threads of one process can only take in turns. A worker process
forked at the start does it while this process designs, searches and judges the patch; it then
simulates while this one renders. The prediction is the same: the worker runs
patchgen.pipeline.prediction.predict_on_bench on the same inputs, and its result (or its error)
comes back through the future.

Forking is Linux's way (the worker starts from this process as it is, nothing imported twice),
and it is taken only from a process of one thread, as the command line is: forking copies the
calling thread alone, and a lock another thread held would stay held in the worker. Elsewhere
(another system, a program or notebook with threads of its own, or no process to be had) the
prediction runs in a thread of this process.
"""

from __future__ import annotations

import multiprocessing
import sys
import threading
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor

from patchgen.design.lqg import Design
from patchgen.patch.netlist import Netlist
from patchgen.pipeline.prediction import BenchPrediction, predict_on_bench
from patchgen.pipeline.scaling import ENVELOPE_RUNS, envelope_runs
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile


def _start_simulator() -> None:
    """Import the simulator and set numba up (its target, from the first cached kernel)."""
    import numpy as np

    import patchgen.bench.diagnosis  # noqa: F401
    import patchgen.bench.simulate  # noqa: F401
    import patchgen.studies.bench_corners  # noqa: F401
    from patchgen.plant.compiled import PLANT_VECTOR, plant_rhs

    plant_rhs(np.ones(len(PLANT_VECTOR)), 0.0, 0.0, 0.0, 0.0, 0.0)


class PredictionWorker:
    """A worker that starts the simulator now, may simulate a patch's envelope for its scaling
    (:meth:`envelope`), and predicts one patch later (:meth:`predict`)."""

    def __init__(self) -> None:
        self._pool: Executor
        if sys.platform.startswith("linux") and threading.active_count() == 1:
            try:
                self._pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork"),
                                                 initializer=_start_simulator)
                self._pool.submit(int)  # the process starts now, not at the first real task
                return
            except OSError:  # no process to be had: a thread will do
                pass
        self._pool = ThreadPoolExecutor(1, thread_name_prefix="bench-prediction")

    def envelope(self, d: Design, net: Netlist, machine: MachineProfile, bench: BenchProfile,
                 rails: bool = True, hold: int = ENVELOPE_RUNS) -> Future:
        """The runs a patch's signal-to-noise scaling is taken over (patchgen.pipeline.scaling.envelope_runs)."""
        return self._pool.submit(envelope_runs, d, net, machine, bench, rails, hold)

    def predict(self, d: Design, net: Netlist, machine: MachineProfile, bench: BenchProfile,
                runs_hold: int, done: dict | None = None) -> Future[BenchPrediction]:
        """The prediction of ``net`` (see predict_on_bench; ``done``: runs of it already made), to be
        waited for; the worker ends with it."""
        pending = self._pool.submit(predict_on_bench, d, net, machine, bench, runs_hold, done)
        self._pool.shutdown(wait=False)
        return pending

    def cancel(self) -> None:
        """No prediction after all: the worker ends."""
        self._pool.shutdown(wait=False, cancel_futures=True)
