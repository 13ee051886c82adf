"""A patch's files with its bench prediction on the sheet: the patch simulated in the standard
scenarios (patchgen.bench.prediction), as the sheet's 'Predicted on the bench' section.

The simulator (numba) is imported only when a prediction is made, so a patch without one stays
light.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import PurePath
from typing import TYPE_CHECKING

from patchgen.design.lqg import Design
from patchgen.design.model import plant_params
from patchgen.inputs.scenario import load_scenario
from patchgen.patch.as_patched import AsPatched
from patchgen.patch.netlist import Netlist
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.profiles.uncertainty import UNITS
from patchgen.render.patchfiles import patch_files
from patchgen.render.sheet import SheetSection

if TYPE_CHECKING:  # pragma: no cover - the simulator loads numba, only when a prediction is made
    from patchgen.bench.simulate import RunSummary
    from patchgen.studies.bench_corners import BenchStudy

PREDICTION_TARGET = 0.95  # a scenario held in fewer of its runs than this is a predicted failure
HOLD_RUNS = 20  # noise seeds of the sheet's 120 s hold unless asked otherwise (patchgen patch --runs)
HOLD_SCENARIO = "hold-120s"  # the scenario run at the corners of the bench's ranges


def bench_section(d: Design, machine: MachineProfile, bench: BenchProfile, net: Netlist,
                  runs_hold: int = HOLD_RUNS, done: dict[str, list[RunSummary]] | None = None,
                  corners: BenchStudy | None = None) -> SheetSection:
    """'Predicted on the bench': the patch in the standard scenarios, with the bench's figures.

    Parameters
    ----------
    d : Design
        The design the patch realises (its spec gives the plant and the track).
    machine, bench : MachineProfile, BenchProfile
        The machine the patch is on and the bench it is simulated against.
    net : Netlist
        The patch.
    runs_hold : int
        Noise seeds of the long hold.
    done : dict, optional
        Runs already simulated, by scenario name (see patchgen.bench.prediction.predict).
    corners : BenchStudy, optional
        The patch at the corners of the bench's ranges, when already run; when the bench states
        ranges and none is given, the hold is run at every corner (``runs_hold`` seeds each).

    Returns
    -------
    SheetSection
        One row per scenario and a note naming the bench's figures and the linearised loop.
    """
    from patchgen.bench.diagnosis import diagnose
    from patchgen.bench.prediction import diagnosis_note, predict, prediction_rows  # the simulator: numba
    from patchgen.studies.bench_corners import study

    plant = plant_params(d.spec)
    spread = bool(bench.uncertainty.ranges)
    preds = predict(net, plant, bench, machine, runs_hold=runs_hold, done=done, bench_spread=spread)
    if spread and corners is None:
        corners = study(net, plant, bench, machine, load_scenario(HOLD_SCENARIO), corner_runs=runs_hold)
    header, rows = prediction_rows(preds)
    dist = bench.disturbance
    note = (f"From this netlist on the {bench_named(bench)}: actuator {bench.actuator.model} {bench.actuator.tau:g} s, "
            f"dead zone +/-{bench.actuator.dead_zone_V:g} V, {bench.actuator.force_limit_N:g} N; sensor noise; random "
            f"forces {dist.cart_force_N_rms:g} N rms on the cart and {dist.tip_force_N_rms:g} "
            f"N rms at the tip (to {dist.bandwidth_Hz:g} Hz); drift "
            f"{_drift_text(net, machine)} ({machine.imperfections.drift_source}); "
            f"rails +/-{machine.imperfections.saturation_V:g} V; switches at +/-{d.spec.plant.d / 2:g} m. "
            + diagnosis_note(net, plant, bench) + (" " + ranges_note(corners) if spread else ""))
    return SheetSection("Predicted on the bench", header, rows, note,
                        banner=failure_banner(bench.id, diagnose(net, plant, bench)[-1], preds))


def _drift_text(net, machine) -> str:
    """The integrators' drift rate, one per integrator mode the patch uses when it uses more than
    the machine's one (a faster mode drifts faster)."""
    modes = sorted({(a.mode.k0_per_s, a.mode.name) for a in net.amplifiers if a.mode is not None})
    if len(machine.integrator_modes) == 1 or not modes:
        return f"{1000 * machine.integrator_drift_V_per_s():.1f} mV/s"
    return ", ".join(f"{1000 * machine.integrator_drift_V_per_s(1.0 / k0):.1f} mV/s in {name}" for k0, name in modes)


def bench_named(bench: BenchProfile) -> str:
    """The bench profile as the sheet names it: its id and, for a profile fitted by patchgen identify,
    the recordings it came from (their folder once, then the files)."""
    if not bench.recordings:
        return f"{bench.id} bench"
    folders = {str(PurePath(r).parent) for r in bench.recordings}
    names = ", ".join(PurePath(r).name if len(folders) == 1 else r for r in bench.recordings)
    where = f" in {folders.pop()}" if len(folders) == 1 and folders != {"."} else ""
    return f"{bench.id} bench (identified from {len(bench.recordings)} recordings{where}: {names})"


def ranges_note(st: BenchStudy) -> str:
    """The ranges the prediction was made over, and the held fraction at their worst corner."""
    from patchgen.studies.bench_corners import MAX_CORNER_PARAMETERS

    ranges = ", ".join(f"{k} {lo:g} to {hi:g} {UNITS[k]}" for k, (lo, hi) in st.ranges.items())
    w = st.worst_corner
    rest = (f" (the corners take the {MAX_CORNER_PARAMETERS} widest ranges; at the profile's value: "
            + ", ".join(st.at_nominal) + ")") if st.at_nominal else ""
    return (f"Predicted over the bench's ranges ({st.distribution}: {ranges}): every run above drew its bench from "
            f"them. At every corner of the ranges in {st.scenario}{rest}, the worst corner held "
            f"{w.held_text()}.")


def failure_banner(bench_id: str, loop, preds) -> str:
    """One line for the top of the sheet when the prediction fails ("" when it holds): the wired
    loop's verdict on the bench when it is not stable, and the scenarios held in under 95 % of runs."""
    failing = [f"{p.scenario} {100 * p.fraction_held:.0f} %" for p in preds if p.fraction_held < PREDICTION_TARGET]
    if loop.verdict == "stable" and not failing:
        return ""
    w = loop.worst
    pole = f"{w.real:+.3g}" + (f" ± {abs(w.imag):.3g}j" if abs(w.imag) > 1e-9 else "")
    cause = f", conserving {loop.conserved_text}" if loop.verdict == "marginal" and loop.conserved else ""
    why = [] if loop.verdict == "stable" else [f"wired loop {loop.verdict} with the {loop.actuator} "
                                               f"(pole {pole} 1/s{cause})"]
    if failing:
        why.append("held in " + ", ".join(failing) + " of runs")
    return f"Predicted to fail on the {bench_id} bench: " + "; ".join(why) + ". See 'Predicted on the bench'."


def predicted_patch_files(d: Design, machine: MachineProfile, bench: BenchProfile, net: Netlist,
                          sections: Sequence[SheetSection] = (), runs_hold: int = HOLD_RUNS,
                          done: dict[str, list[RunSummary]] | None = None,
                          corners: BenchStudy | None = None, judged: AsPatched | None = None) -> dict[str, str]:
    """Every file of a patch (patchgen.render.patchfiles.PATCH_FILES), the bench prediction first
    on the sheet, then ``sections``; arguments as :func:`bench_section`, and the patch judged as
    patched (patchgen.bench.diagnosis.as_patched_on_bench, computed when not given)."""
    from patchgen.bench.diagnosis import as_patched_on_bench

    judged = judged if judged is not None else as_patched_on_bench(d, net, machine, bench)
    return patch_files(d, machine, net, [bench_section(d, machine, bench, net, runs_hold, done, corners), *sections],
                       judged)
