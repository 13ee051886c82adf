"""The sheet's 'Predicted on the bench' section, worded from the pipeline's BenchPrediction
(patchgen.pipeline.prediction): one row per scenario, the bench's figures, the linearised loop and
the ranges; and a patch's files with that section first on its sheet."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import PurePath
from typing import TYPE_CHECKING

from patchgen.design.lqg import Design
from patchgen.patch.as_patched import AsPatched
from patchgen.patch.netlist import Netlist
from patchgen.pipeline.patch import PatchReport
from patchgen.pipeline.prediction import BenchPrediction
from patchgen.plant.plant_model import CART, PlantModel
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.profiles.measured_plant import as_on_bench, measured_words
from patchgen.profiles.uncertainty import UNITS
from patchgen.render.patchfiles import patch_files
from patchgen.render.sheet import SheetSection

if TYPE_CHECKING:  # pragma: no cover - the simulator loads numba, only when a prediction is made
    from patchgen.bench.prediction import Prediction
    from patchgen.studies.bench_corners import BenchStudy


def bench_section(pred: BenchPrediction, d: Design, machine: MachineProfile, bench: BenchProfile,
                  net: Netlist) -> SheetSection:
    """'Predicted on the bench': the patch in the standard scenarios, with the bench's figures.

    Parameters
    ----------
    pred : BenchPrediction
        The prediction (patchgen.pipeline.prediction.predict_on_bench).
    d : Design
        The design the patch realises (its spec gives the track).
    machine, bench : MachineProfile, BenchProfile
        The machine the patch is on and the bench it was simulated against.
    net : Netlist
        The patch.

    Returns
    -------
    SheetSection
        One row per scenario and a note naming the bench's figures and the linearised loop.
    """
    header, rows = prediction_rows(pred.predictions, d.spec.plant_model)
    dist, pm = bench.disturbance, d.spec.plant_model
    if pm is CART:
        randoms = (f"random forces {dist.cart_force_N_rms:g} N rms on the cart and {dist.tip_force_N_rms:g} "
                   f"N rms at the tip")
        ends = f"switches at +/-{d.spec.plant.d / 2:g} m"
    else:
        randoms = (f"a random torque {dist.arm_torque_Nm_rms:g} N m rms on the arm and force "
                   f"{dist.tip_force_N_rms:g} N rms at the tip")
        limit = as_on_bench(d.plant, bench).alpha_limit
        ends = f"the cable's wind-up at +/-{math.degrees(limit):g} deg" if math.isfinite(limit) else "no cable limit"
    note = (f"From this netlist on the {bench_named(bench)}: actuator {bench.actuator.model} {bench.actuator.tau:g} s, "
            f"dead zone +/-{bench.actuator.dead_zone_V:g} V, {bench.actuator.force_limit_N:g} {pm.input_unit}; "
            f"sensor noise; {randoms} (to {dist.bandwidth_Hz:g} Hz); drift "
            f"{_drift_text(net, machine)} ({machine.imperfections.drift_source}); "
            f"rails +/-{machine.imperfections.saturation_V:g} V; {ends}"
            + "".join(f"; the plant as this bench has it, {w}" for w in measured_words(d.plant, bench)) + ". "
            + diagnosis_note(pred) + (" " + ranges_note(pred.corners) if pred.corners is not None else ""))
    return SheetSection("Predicted on the bench", header, rows, note, banner=failure_banner(bench.id, pred))


LOW_SHARE = 0.1  # an amplifier whose expected peak is under this share of the reference is marked low
LIMITED = "the actuator's limit"  # a command past the reference that the actuator saturates first


def levels_section(pred: BenchPrediction, net: Netlist) -> SheetSection:
    """'Signal levels on the bench': each amplifier's expected peak (the largest |output| over the
    prediction's runs) as a share of the reference, and its signal-to-noise ratio over the
    machine's noise floor; a signal under LOW_SHARE of the reference is marked."""
    overloaded = {a for p in pred.predictions for a in p.overloads.split(", ")}
    rows = [[lv.amplifier, lv.quantity, f"{100 * lv.peak_share:.1f} %",
             "-" if lv.snr_dB == float("inf") else f"{lv.snr_dB:.0f}",
             "low" if lv.peak_share < LOW_SHARE else "" if lv.peak_share <= 1 else
             "past the reference" if lv.amplifier in overloaded else LIMITED]
            for lv in pred.levels]
    note = (f"The largest |output| of each amplifier over every run above while the pendulum is up (a run "
            f"that falls: up to its fall), as a share of the reference "
            f"(+/-{net.reference_V:g} V), and over the machine's noise floor (its amplifier noise and "
            f"integrator offset together). A signal that uses little of its range carries the machine's "
            f"noise, offsets and the settings' step at that much more weight; 'low' marks one under "
            f"{100 * LOW_SHARE:g} %." + (" The command past the reference where the actuator saturates first is "
                                          "the actuator's limit, not an overload (it asks no less than the "
                                          "actuator gives)." if any(r[-1] == LIMITED for r in rows) else ""))
    return SheetSection("Signal levels on the bench", ["amplifier", "carries", "expected peak", "SNR (dB)", ""],
                        rows, note)


def prediction_rows(preds: Sequence[Prediction], plant: PlantModel = CART) -> tuple[list[str], list[list[str]]]:
    """The predictions as a table for the patch sheet: (header, rows of text), in the plant's words."""
    header = ["scenario", "runs", "held", f"{plant.limit_event} (run 0)", "fallen (run 0)", "max |theta| (deg)",
              plant.position_heading(), "overloads"]
    rows = []
    for p in preds:
        rows.append([p.scenario, str(p.runs), f"{100 * p.fraction_held:.0f} %",
                     "no" if p.first_trip_s is None else f"at {p.first_trip_s:.2f} s",
                     "no" if p.first_fall_s is None else f"at {p.first_fall_s:.2f} s",
                     f"{p.max_theta_deg:.2f}", f"{p.max_s_m:.3f}", p.overloads])
    return header, rows


def diagnosis_note(pred: BenchPrediction) -> str:
    """The linearised loop's verdicts (see patchgen.bench.diagnosis) as one sentence for the sheet."""
    return "Linearised: " + "; ".join(lp.line() for lp in pred.loops) + "."


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
            f"them. At {st.how()}{rest}, the worst corner held "
            f"{w.held_text()}.")


def failure_banner(bench_id: str, pred: BenchPrediction) -> str:
    """One line for the top of the sheet when the prediction fails ("" when it holds): the wired
    loop's verdict on the bench when it is not stable, and the scenarios held in under 95 % of runs."""
    loop = pred.loops[-1]
    failing = [f"{p.scenario} {100 * p.fraction_held:.0f} %" for p in pred.failing]
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
                          pred: BenchPrediction, judged: AsPatched,
                          sections: Sequence[SheetSection] = ()) -> dict[str, str]:
    """Every file of a patch (patchgen.render.patchfiles.PATCH_FILES), the bench prediction first
    on the sheet, then ``sections``; the patch judged as patched on the bench
    (patchgen.bench.diagnosis.as_patched_on_bench) on its margins page."""
    return patch_files(d, machine, net, [bench_section(pred, d, machine, bench, net), *_levels(pred, net), *sections],
                       judged)


def patch_report_files(report: PatchReport, machine: MachineProfile, bench: BenchProfile) -> dict[str, str]:
    """Every file patchgen patch writes, from its report: the bench prediction on the sheet when
    the report has one."""
    d, net = report.design, report.netlist
    if report.pending is None:
        return patch_files(d, machine, net, judged=report.judged)
    # the sheet's bench section last: the prediction is computed while the rest is rendered
    return patch_files(d, machine, net, lambda: [bench_section(report.prediction, d, machine, bench, net),
                                                 *_levels(report.prediction, net)], report.judged)


def _levels(pred: BenchPrediction, net: Netlist) -> list[SheetSection]:
    """The signal levels' section, when the prediction has them."""
    return [levels_section(pred, net)] if pred.levels else []
