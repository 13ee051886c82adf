"""A patch judged as patched: the wired law (the netlist read back, pots as dialled) closed around
the design model beside the design's own law, and how far the wired law is from the design's, cause
by cause.

The design's margins are those of its law; a patch wires another one. Thesis case 2 realised as one
compensator on three GP-6 units residualises its -76 +/- 76j pair: the wired law is 9 % off the
design's at 10 rad/s, 50 % at 30 and 76 % at 100, and the loop keeps 14.9 of the design's 52.8 deg
of phase margin. So every patch is reported with

- the loop as designed: the design model closed by the design's controller (its margins at the
  plant input, patchgen.design.margins.loop_margins, and its poles);
- the loop as patched: the same model closed by the wired law (patchgen.patch.readback);
- on the bench, when the caller adds it (patchgen.bench.diagnosis.as_patched_on_bench): the wired
  loop linearised with the bench's actuator, as the simulator's linear verdict has it;
- the wired law against the design's (patchgen.patch.law_error) over the loop's band, and the
  same split into its causes along the way from one to the other: the integral states' leaks the
  patch leaves out, the modes the realisation residualises or reduces away (a compensator patched
  as one system), the terms the allocator leaves out below the dial's resolution, and the dial.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from patchgen.design.controller import Controller
from patchgen.design.lqg import Design, loop_with_controller
from patchgen.design.margins import Margins, loop_margins
from patchgen.patch import compensator_fit
from patchgen.patch.law_error import LawError, difference, law_error, relative
from patchgen.patch.netlist import Netlist
from patchgen.patch.readback import si_controller
from patchgen.profiles.machine import MachineProfile

REPORT_W = (1.0, 3.0, 10.0, 30.0, 100.0)  # rad/s: where the sheet gives the wired law's error
BAND_SLACK = 2.0  # the loop's band: an octave below its slowest crossover to one above its fastest
MATCH_POINTS = 40  # frequencies over the band that tell which compensator law the wiring realises
SAME_POLE = 1e-3  # relative: a design pole this near one of the realised law's is patched
# 1/s: a closed-loop pole this near the origin that no loop gain moves (the force cannot reach it,
# or u does not see it) is a fixed mode, set beside the margins (as patchgen.bench.diagnosis's
# MARGINAL_TOL: thesis-ch5's pure integral of theta leaves the plant's conserved quantity there)
FIXED_TOL = 1e-7
FIXED_RTOL = 1e-8  # relative: |w'B| (or |C v|) this small beside |w| |B| is zero
FIXED_SHIFT = 1.0  # 1/s: where the margins' copy of the loop moves a fixed mode (any stable value)


@dataclass(frozen=True)
class LoopFigures:
    """One closed loop: what it is, whose law closes it, its margins and its poles (1/s)."""

    loop: str  # "design model", or the bench's name
    law: str  # "as designed (kalman)", "as patched"
    margins: Margins  # of what a loop gain or delay moves: the fixed modes left out
    poles: np.ndarray
    fixed: tuple[complex, ...] = ()  # closed-loop poles at the origin that no loop gain moves

    @property
    def rightmost(self) -> complex:
        """The pole with the largest real part (of a pair, the one with Im >= 0)."""
        p = self.poles[np.lexsort((-self.poles.imag, -self.poles.real))]
        return complex(p[0])

    def as_dict(self) -> dict:
        """Plain JSON-ready values (poles as [re, im] pairs, sorted)."""
        p = self.poles[np.lexsort((self.poles.imag, self.poles.real))]
        return {"loop": self.loop, "law": self.law, "margins": self.margins.as_dict(),
                "poles": [[float(z.real), float(z.imag)] for z in p],
                "fixed_poles": [[float(z.real), float(z.imag)] for z in self.fixed]}


@dataclass(frozen=True)
class Cause:
    """One step from the design's law to the wired one: what it is and the error it adds."""

    kind: str  # leaks | modes | left_out | dial
    what: str
    error: LawError


@dataclass(frozen=True)
class AsPatched:
    """A patch judged as patched beside its design (module docstring)."""

    designed: LoopFigures
    patched: LoopFigures
    law: LawError  # the wired law against the design's, relative to the design's
    causes: tuple[Cause, ...]
    realization: str  # "compensator" (the law as one system) or "states"
    bench: LoopFigures | None = None

    @property
    def pm_share(self) -> float | None:
        """The share of the design's phase margin the patched loop keeps (compensator_fit.pm_share)."""
        return compensator_fit.pm_share(self.patched.margins, self.designed.margins)

    @property
    def keeps_margin(self) -> bool:
        """The patched loop keeps compensator_fit.KEEP_PM_SHARE of the design's phase margin (or there is none)."""
        share = self.pm_share
        return self.patched.margins.stable if share is None else share >= compensator_fit.KEEP_PM_SHARE

    @property
    def loops(self) -> tuple[LoopFigures, ...]:
        """As designed, as patched, then on the bench when there."""
        return (self.designed, self.patched) + ((self.bench,) if self.bench is not None else ())

    def with_bench(self, bench: LoopFigures) -> AsPatched:
        """The same, with the wired loop on the bench."""
        return replace(self, bench=bench)

    def as_dict(self) -> dict:
        """Plain JSON-ready values: every loop, the law's error and its causes."""
        share = self.pm_share
        return {"loops": [lp.as_dict() for lp in self.loops], "realization": self.realization,
                "pm_share": share if share is None or math.isfinite(share) else None,
                "keep_pm_share": compensator_fit.KEEP_PM_SHARE, "keeps_pm_share": self.keeps_margin,
                "law_error": self.law.as_dict(),
                "causes": [{"cause": c.kind, "what": c.what, **c.error.as_dict()} for c in self.causes]}


def as_patched(design: Design, net: Netlist, machine: MachineProfile) -> AsPatched:
    """The patch ``net`` of ``design`` judged on the design model (no bench).

    Parameters
    ----------
    design : Design
        The design the patch realises (it has a controller: every patchable design does).
    net : Netlist
        The patch, its pots as dialled.
    machine : MachineProfile
        One unit of the machine it is on (the compensator's laws are found with it).

    Returns
    -------
    AsPatched
        Loops as designed and as patched, the wired law's error against the design's and its causes.
    """
    model = design.model
    d0 = design.controller
    kind = design.estimator.kind if design.estimator is not None else "state feedback"
    designed = loop_figures("design model", f"as designed ({kind})", design, d0)
    wired = _in_model_order(si_controller(net), net, model.measured)
    patched = loop_figures("design model", "as patched", design, wired)
    band = loop_band(designed.margins)
    exact = _in_model_order(si_controller(exact_dial(net)), net, model.measured)
    d1 = without_leaks(d0)
    comp = design.spec.patch.realization == "compensator"
    realised = realised_law(design, machine, exact, band) if comp else None
    steps, end = [], d1
    if _leaks_text(design):
        steps.append(("leaks", _leaks_text(design), d0, d1))
    if realised is not None:
        end = realised.controller()
        steps.append(("modes", _modes_text(d1, realised), d1, end))
    reading = machine.procedure.pot_reading
    left = [n.split(":")[0] for n in net.notes if n.endswith("left out")]
    if left:
        steps.append(("left_out", f"terms below the {reading} resolution left out: " + ", ".join(left), end, exact))
    steps.append(("dial", _dial_text(net, reading), exact, wired))
    causes = tuple(Cause(k, what, law_error(b, a, d0, band, REPORT_W)) for k, what, a, b in steps)
    return AsPatched(designed, patched, law_error(wired, d0, d0, band, REPORT_W), causes,
                     "compensator" if comp else "states")


def loop_figures(loop: str, law: str, design: Design, ctl: Controller) -> LoopFigures:
    """The design model closed by ``ctl`` (SI, the model's measurements in order): its margins
    broken at the plant input and its closed-loop poles (:func:`figures`)."""
    return figures(loop, law, *loop_with_controller(design.model, ctl))


def figures(loop: str, law: str, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> LoopFigures:
    """A loop broken at its input, T = C (sI - A)^-1 B closed as u = -T u: its poles, and its
    margins (patchgen.design.margins.loop_margins) with every fixed mode at the origin moved to
    -FIXED_SHIFT first.

    A mode the input cannot reach (left eigenvector w, w'B = 0) or the output does not see
    (right eigenvector v, C v = 0) is an eigenvalue of A - k B C for every gain k; moving it by
    the rank-one A - s u w' (w'u = 1; or A - s v z', z'v = 1: Brauer's theorem) changes no other
    eigenvalue of any of them, nor T. A pole at the origin that no gain moves is marginal whatever
    the margins; it is named beside them rather than hiding them.
    """
    A2, fixed = A.copy(), []
    for _ in range(A.shape[0]):
        lam, W = np.linalg.eig((A2 - B @ C).T)
        lam_r, V = np.linalg.eig(A2 - B @ C)
        k = int(np.argmin(np.abs(lam)))
        if abs(lam[k]) > FIXED_TOL:
            break
        w, v = _real(W[:, k]), _real(V[:, int(np.argmin(np.abs(lam_r)))])
        if abs(w @ B[:, 0]) <= FIXED_RTOL * np.linalg.norm(w) * np.linalg.norm(B):
            A2 = A2 - FIXED_SHIFT * np.outer(w / (w @ w), w)
        elif abs(C[0] @ v) <= FIXED_RTOL * np.linalg.norm(v) * np.linalg.norm(C):
            A2 = A2 - FIXED_SHIFT * np.outer(v, v / (v @ v))
        else:
            break
        fixed.append(complex(lam[k]))
    return LoopFigures(loop, law, loop_margins(A2, B, C), np.linalg.eigvals(A - B @ C), tuple(fixed))


def _real(x: np.ndarray) -> np.ndarray:
    """An eigenvector of a real eigenvalue as a real vector (its phase taken out)."""
    return (x / x[int(np.argmax(np.abs(x)))]).real


def loop_band(m: Margins) -> tuple[float, float]:
    """The loop's band: BAND_SLACK below its slowest crossover (gain or phase) to BAND_SLACK above
    its fastest, where the margins are decided (0.1 to 100 rad/s for a loop with none)."""
    ws = [w for w in [*m.gain_crossovers, *m.phase_crossovers] if w > 0]
    return (min(ws) / BAND_SLACK, max(ws) * BAND_SLACK) if ws else (0.1, 100.0)


def exact_dial(net: Netlist) -> Netlist:
    """The netlist with every pot at its design coefficient (no dial step): the law the wiring
    carries before the dial rounds it; a term below the resolution set to the dial's minimum is
    at its design value here."""
    pots = [p.model_copy(update={"setting": abs(p.coefficient) / p.weight}) for p in net.pots]
    return net.model_copy(update={"pots": pots})


def without_leaks(ctl: Controller) -> Controller:
    """The controller with its integral states (named int_*) pure integrators, as a patch wires them."""
    idx = [i for i, s in enumerate(ctl.states) if s.startswith("int_")]
    Ac = ctl.Ac.copy()
    Ac[np.ix_(idx, idx)] = 0.0
    return Controller(ctl.states, Ac, ctl.Bc, ctl.Cc, ctl.Dc)


def realised_law(design: Design, machine: MachineProfile, exact: Controller, band: tuple[float, float]):
    """The compensator law (patchgen.patch.compensator_fit: every order, fast modes kept or not)
    whose response the wiring at its design coefficients follows most closely over the band."""
    cands = [law for _, _, law in compensator_fit.laws(design, machine)]
    whole = compensator_fit.whole_law(design, machine)
    cands = ([whole[2]] if whole else []) + cands
    w = np.geomspace(*band, MATCH_POINTS)

    def off(c) -> float:
        ctl = c.controller()
        return float(np.max(relative(difference(exact, ctl), ctl, w)))

    return min(cands, key=off)


def _in_model_order(ctl: Controller, net: Netlist, measured: tuple[str, ...]) -> Controller:
    """The controller's inputs reordered to the design model's measurements (by sensor quantity)."""
    quantity = {s.id: s.quantity for s in net.sensors}
    order = [quantity[s.id] for s in net.sensors]
    idx = [order.index(m) for m in measured]
    return Controller(ctl.states, ctl.Ac, ctl.Bc[:, idx], ctl.Cc, ctl.Dc[:, idx])


def _leaks_text(design: Design) -> str:
    """The integral states' leaks the patch leaves out, in words ("" when there are none)."""
    integ = design.spec.integrators
    leaks = [(n, getattr(integ, f"{n}_leak")) for n in ("int_s", "int_theta") if n in design.states]
    leaks = [(n, v) for n, v in leaks if v]
    if not leaks:
        return ""
    return "the integral states' leaks not patched (pure integrators): " + ", ".join(
        f"{n} {v:g} 1/s" for n, v in leaks)


def _modes_text(d1: Controller, law) -> str:
    """The law realised and the design's modes it does not carry, in words."""
    mine = np.linalg.eigvals(law.controller().Ac)
    theirs = np.linalg.eigvals(d1.Ac)
    gone = [p for p in theirs if p.imag >= 0 and abs(p) > 0
            and not np.any(np.abs(mine - p) <= SAME_POLE * abs(p))]
    lost = ("; the design's modes at " + ", ".join(_pole(p) for p in sorted(gone, key=abs)) + " rad/s not patched"
            if gone else "")
    return f"the law realised: {law.method}, {law.order} states" + (lost or ", every mode of the design's")


def _pole(p: complex) -> str:
    return f"{p.real:.4g}" + (f" ± {abs(p.imag):.4g}j" if abs(p.imag) > 1e-9 * abs(p) else "")


def _dial_text(net: Netlist, reading: str) -> str:
    """The pots' steps, in words (``reading``: what the machine reads a setting on, its own term):
    the pots set to its resolution and the terms below it set to its smallest step."""
    low = sum(1 for n in net.notes if "set to the minimum" in n)
    return (f"each of {len(net.pots)} pots set to the {reading} resolution {net.pot_resolution:g}"
            + (f", {low} below it at its smallest step" if low else ""))
