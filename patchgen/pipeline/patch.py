"""patchgen patch as one function: the spec designed, scaled and allocated on its machine, the
patch judged as patched on the bench, and its bench prediction for the sheet."""

from __future__ import annotations

from concurrent.futures import Future
from dataclasses import dataclass, field

from patchgen.bench.diagnosis import as_patched_on_bench
from patchgen.design.lqg import Design, design_on
from patchgen.patch.as_patched import AsPatched
from patchgen.patch.netlist import Netlist
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.prediction import HOLD_RUNS, BenchPrediction
from patchgen.pipeline.prediction_worker import PredictionWorker
from patchgen.pipeline.scaling import ENVELOPE_RUNS, scaled_patch


@dataclass(frozen=True)
class PatchPlan:
    """Noise seeds of the sheet's long hold, and whether to predict the bench at all."""

    runs_hold: int = HOLD_RUNS
    predict: bool = True


@dataclass(frozen=True)
class PatchReport:
    """The design, its patch, the patch judged as patched (design model and bench), and its bench
    prediction (None when not asked for), computed by a worker of its own while the patch is
    made and rendered (patchgen.pipeline.prediction_worker)."""

    design: Design
    netlist: Netlist
    judged: AsPatched
    pending: Future[BenchPrediction] | None = field(repr=False, compare=False)

    @property
    def prediction(self) -> BenchPrediction | None:
        """The bench prediction, waited for when it is still being computed."""
        return None if self.pending is None else self.pending.result()

    def summary(self) -> dict:
        """The patch's amplifiers, notes, margins as patched and the bench prediction, as plain data
        (``--json`` adds the pot table and the files written, which render words)."""
        net = self.netlist
        return {"design": net.design, "machine": net.machine, "units": net.units,
                "amplifiers": [{"id": a.id, "role": a.role, "carries": a.carries.model_dump()}
                               for a in net.amplifiers],
                "notes": net.notes, "margins": self.judged.as_dict(),
                "prediction": None if self.prediction is None else self.prediction.summary()}


def run_patch(inputs: Inputs, plan: PatchPlan = PatchPlan()) -> PatchReport:
    """Design, scale and allocate the spec on its machine (each signal raised for signal-to-noise
    over the bench's envelope, patchgen.pipeline.scaling); judge the patch as patched; predict it.

    Parameters
    ----------
    inputs : Inputs
        The spec, machine and bench, resolved and checked.
    plan : PatchPlan
        The long hold's seeds, and whether to predict.

    Returns
    -------
    PatchReport
    """
    spec, machine, bench = inputs
    worker = PredictionWorker() if plan.predict else None  # its simulator starts while the patch is made
    try:
        d = design_on(spec, machine, bench)
        # the envelope simulated by the worker, whose simulator started with this command (without one, here)
        scaled = scaled_patch(d, machine, bench, runs_of=None if worker is None else
                              lambda n, rails=True, hold=ENVELOPE_RUNS: worker.envelope(d, n, machine, bench, rails,
                                                                                       hold).result())
        net, runs = scaled.netlist, scaled.runs
        judged = as_patched_on_bench(d, net, machine, bench)
    except BaseException:
        if worker is not None:
            worker.cancel()
        raise
    pending = None if worker is None else worker.predict(d, net, machine, bench, plan.runs_hold, runs)
    return PatchReport(d, net, judged, pending)
