"""From a static check's readings to the likeliest wiring fault.

The technician fills the ``measured_V`` column of static-check.csv (read by
patchgen.patch.readings). Each reading either agrees with its expected value within its
tolerance, or the patch differs from the netlist. The fault
model, one fault at a time, each a variation of the wiring that patchgen.patch.static_check.solve
evaluates under the same conditions:

- a pot at a wrong setting (the setting that explains the readings best, found on the dial);
- a cord on the wrong weight (x1 and x10 swapped);
- a cord from the wrong source (another sensor or amplifier output);
- a cord moved to another amplifier's input;
- a missing inversion (one input's sign flipped, as a cord taken from the signal's other polarity).

Each candidate is scored by chi-square, the sum over readings of ((measured - predicted) /
tolerance)^2. Candidates that explain every reading within its tolerance come first, the
structural faults (an inversion, a weight, a source, an amplifier) before a pot setting, since a
pot at the right wrong setting can mimic any change of one input's gain (a x10 cord on a x1 input
reads like its pot at a tenth); the rest follow by score. Faults the readings cannot tell apart
are reported together (``consistent``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize_scalar

from patchgen.patch.netlist import Netlist
from patchgen.patch.readings import reading_limit_V
from patchgen.patch.static_check import StaticCheck, Wire, solve, wires_of
from patchgen.profiles.machine import MachineProfile

TOP = 5  # faults reported
SCAN_POINTS = 101  # dial settings tried before a pot's best setting is refined
KIND_ORDER = ("inversion", "weight", "source", "amplifier", "pot_setting")  # among faults that explain everything


@dataclass(frozen=True)
class Fault:
    """One candidate fault: what it is, its chi-square against the readings, and how many of the
    readings it explains (within tolerance)."""

    kind: str  # pot_setting, weight, source, amplifier, inversion
    description: str
    score: float
    explained: int
    of: int

    @property
    def consistent(self) -> bool:
        """Every reading explained within its tolerance."""
        return self.explained == self.of


@dataclass(frozen=True)
class Verdict:
    """Whether the readings agree with the check and, if not, the likeliest faults, best first."""

    agree: bool
    mismatched: tuple[str, ...]  # "condition point" of each reading outside its tolerance
    faults: tuple[Fault, ...]


def predict(net: Netlist, check: StaticCheck, wires: list[Wire], rail: float | None = None) -> np.ndarray:
    """The readings a wiring would give under the check's conditions, in its reading order (outputs
    held at +/- ``rail``, the machine's saturation, when given)."""
    out = []
    solved = {c.name: solve(net, wires, c, rail) for c in check.conditions}
    for r in check.readings:
        amp = net.output.source if r.point == "u_c" else r.point
        out.append(solved[r.condition][amp])
    return np.array(out)


def diagnose_readings(net: Netlist, machine: MachineProfile, check: StaticCheck, measured: np.ndarray,
                      top: int = TOP) -> Verdict:
    """Compare the readings with the check and rank the single faults that explain them.

    Parameters
    ----------
    net : Netlist
        The patch as it should be.
    machine : MachineProfile
        Its weights and pot resolution (the candidates' range).
    check : StaticCheck
        The check the readings were taken under.
    measured : numpy.ndarray
        The measured voltages, in the check's reading order, each within
        patchgen.patch.readings.reading_limit_V (so that every chi-square is finite).
    top : int
        How many faults to report.

    Returns
    -------
    Verdict
        agree when every reading is within its tolerance; otherwise the likeliest faults.
    """
    limit = reading_limit_V(machine)
    if not np.all(np.abs(measured) <= limit):  # also false for nan: the chi-squares stay finite
        raise ValueError(f"readings must be finite and within +/-{limit:g} V (patchgen.patch.readings checks them)")
    expected = np.array([r.expected_V for r in check.readings])
    tol = np.array([r.tolerance_V for r in check.readings])
    off = np.abs(measured - expected) > tol
    mismatched = tuple(f"{r.condition} {r.point}" for r, o in zip(check.readings, off) if o)
    if not off.any():
        return Verdict(True, (), ())
    wires = wires_of(net)

    def chi2(ws: list[Wire]) -> tuple[float, int]:
        d = (measured - predict(net, check, ws, machine.imperfections.saturation_V)) / tol
        return float(np.sum(d * d)), int(np.sum(np.abs(d) <= 1.0))

    n = len(check.readings)
    cands: list[tuple[tuple, Fault]] = []

    def add(kind: str, text: str, ws: list[Wire]) -> None:
        score, explained = chi2(ws)
        fault = Fault(kind, text, score, explained, n)
        key = (0, KIND_ORDER.index(kind), score) if fault.consistent else (1, 0, score)
        cands.append((key + (len(cands),), fault))

    res = machine.pot_resolution
    for k, w in enumerate(wires):
        if w.pot:
            def at(setting, k=k, w=w):
                ws = list(wires)
                ws[k] = replace(w, gain=w.weight * setting)
                return chi2(ws)[0]
            # a coarse scan first (the readings clip at the rails, so the misfit need not have one
            # minimum over the dial), then Brent's method inside the best cell
            grid = np.linspace(0.0, machine.pot_max, SCAN_POINTS)
            i = int(np.argmin([at(x) for x in grid]))
            lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
            best = minimize_scalar(at, bounds=(lo, hi), method="bounded", options={"xatol": res / 4})
            setting = round(best.x / res) * res
            nominal = w.gain / w.weight
            if abs(setting - nominal) >= res:
                ws = list(wires)
                ws[k] = replace(w, gain=w.weight * setting)
                add("pot_setting", f"{w.pot} set to about {setting:.3f} instead of {nominal:.3f}", ws)
    for k, w in enumerate(wires):
        for other in machine.input_weights:
            if other != w.weight:
                ws = list(wires)
                ws[k] = replace(w, gain=w.gain * other / w.weight, weight=other)
                add("weight", f"{w.amplifier} {w.jack}: cord on a x{other} input instead of x{w.weight}"
                    + (f" (from {w.pot})" if w.pot else f" (from {w.source})"), ws)
    sources = [s.id for s in net.sensors] + [a.id for a in net.amplifiers]
    for k, w in enumerate(wires):
        for src in sources:
            if src != w.source and src != w.amplifier:
                ws = list(wires)
                ws[k] = replace(w, source=src)
                via = f"{w.pot} " if w.pot else ""
                add("source", f"{w.amplifier} {w.jack}: {via}fed from {src} instead of {w.source}", ws)
    for k, w in enumerate(wires):
        for a in net.amplifiers:
            if a.id != w.amplifier:
                ws = list(wires)
                ws[k] = replace(w, amplifier=a.id)
                add("amplifier", f"the cord for {w.amplifier} {w.jack} ({w.pot or w.source}) on an input of {a.id}",
                    ws)
    for k, w in enumerate(wires):
        ws = list(wires)
        ws[k] = replace(w, gain=-w.gain)
        add("inversion", f"{w.amplifier} {w.jack} ({w.pot or w.source}): sign reversed (a missing or extra "
            "inversion: the cord from the signal's other polarity)", ws)
    cands.sort(key=lambda kf: kf[0])
    ranked = [f for _, f in cands]
    consistent = sum(f.consistent for f in ranked)
    return Verdict(False, mismatched, tuple(ranked[:max(top, min(consistent, 2 * top))]))
