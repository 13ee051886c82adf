"""Recommend a patch: every way of getting the unmeasured states that the machine can hold,
each designed, allocated and simulated on the bench, ranked by what the bench would do.

Candidates (same plant, weights, actuator model and integral states as the spec; only the
estimator changes): the raw differentiator of the thesis (the machine's default roll-off), a
filtered differentiator and a reduced-order observer (their speed from the bench noise,
patchgen.design.corner), and the Kalman estimator (the spec's settings when it has them). A candidate
that does not fit the machine keeps its resource error in the table.

Ranking, best first: the fraction of Monte Carlo runs of the scenario in which the pendulum stays
up, the cart stays inside the limit switches and no amplifier leaves the rails (for the whole
scenario); then the loop's gain margin (the nearer of the two limits, dB), then its phase margin;
then the smallest worst amplifier swing; then the fixed candidate order. Figures are rounded
before ranking so the order is deterministic.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from patchgen.bench.diagnosis import diagnose
from patchgen.bench.simulate import RunSummary, simulate
from patchgen.design.lqg import Design, design_on
from patchgen.design.model import plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.build import build_patch
from patchgen.patch.netlist import Netlist
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

CANDIDATES = (
    ("raw differentiator", "differentiator"),
    ("filtered differentiator", "filtered_differentiator"),
    ("reduced observer", "reduced_observer"),
    ("Kalman", "kalman"),
)


RUNS = 200  # noise seeds per candidate: the held fraction in steps of half a percent

# Figures are rounded before ranking, so that noise in the last digits cannot reorder candidates.
FRACTION_DIGITS = 6  # fraction of runs held: below one run in a million
MARGIN_DIGITS = 1  # gain margin (dB) and phase margin (deg), as the table prints them
SWING_DIGITS = 2  # worst amplifier swing (V), as the table prints it
INFINITE_MARGIN = -1e9  # the rank figure of an infinite margin: ahead of every finite one


@dataclass(frozen=True)
class Candidate:
    """One realisation of the estimator: its design, its patch (when it fits the machine) and,
    once simulated, its bench figures."""

    label: str
    kind: str
    design: Design | None
    netlist: Netlist | None
    error: str | None  # why it was not simulated (design or resource error, one line)
    runs: int = 0
    fraction_ok: float | None = None  # held, inside the switches, no overload, whole scenario
    fraction_fallen: float | None = None
    fraction_tripped: float | None = None
    fraction_overloaded: float | None = None
    worst_swing_V: float | None = None  # largest |amplifier output| over the runs' peaks
    estimator_detail: str = ""
    results: tuple[RunSummary, ...] = field(default=(), repr=False, compare=False)  # the Monte Carlo's runs
    bench_loop: str | None = None  # the wired loop's linear verdict on the bench: stable, marginal, unstable

    @property
    def gm_db(self) -> float | None:
        """Distance to the nearer gain limit, dB (None when the loop is unstable)."""
        m = self.design.lqg_margins if self.design is not None else None
        if m is None or not m.stable:
            return None
        lims = [abs(x) for x in (m.lower_gm_db, m.upper_gm_db) if x is not None]
        return min(lims) if lims else math.inf

    @property
    def pm_deg(self) -> float | None:
        """Phase margin of the patched loop, deg (None when the loop is unstable)."""
        m = self.design.lqg_margins if self.design is not None else None
        return None if m is None or not m.stable else m.pm_deg

    @property
    def amplifiers(self) -> int | None:
        """Amplifiers the patch uses (None when it does not fit)."""
        return None if self.netlist is None else len(self.netlist.amplifiers)

    @property
    def pots(self) -> int | None:
        """Pots the patch uses (None when it does not fit)."""
        return None if self.netlist is None else len(self.netlist.pots)

    def rank_key(self, order: int) -> tuple:
        """Sort key, best first: simulated, a wired loop that is stable on the bench (a marginal or
        unstable one ranks below every stable one, whatever its runs did), runs held, fewer
        units, gain margin, phase margin, smaller swing, then ``order`` (the candidate's place in
        CANDIDATES)."""
        if self.fraction_ok is None:
            return (1, 1, 0.0, 0, 0.0, 0.0, 0.0, order)
        def r(x):  # larger margins first; none (unstable loop) after every margin
            if x is not None and math.isfinite(x):
                return -round(x, MARGIN_DIGITS)
            return INFINITE_MARGIN if x else 0.0

        units = self.netlist.units if self.netlist is not None else 1
        return (0, 0 if self.bench_loop == "stable" else 1, -round(self.fraction_ok, FRACTION_DIGITS), units,
                r(self.gm_db), r(self.pm_deg),
                round(self.worst_swing_V or 0.0, SWING_DIGITS), order)


@dataclass(frozen=True)
class Recommendation:
    """Every candidate, ranked, and the Monte Carlo they were ranked by."""

    spec: DesignSpec
    scenario: Scenario
    runs: int
    seed: int
    ranked: tuple[Candidate, ...]

    @property
    def best(self) -> Candidate | None:
        """The first-ranked candidate, if it was simulated and its wired loop is stable on the
        bench: a loop that is not is never chosen, whatever its runs did."""
        b = self.ranked[0] if self.ranked else None
        ok = b is not None and b.netlist is not None and b.fraction_ok is not None and b.bench_loop == "stable"
        return b if ok else None


def candidate_specs(spec: DesignSpec) -> list[tuple[str, str, DesignSpec]]:
    """The spec with each estimator kind (plant, weights, actuator, integrators unchanged)."""
    out = []
    for label, kind in CANDIDATES:
        e = spec.estimator
        upd: dict = {"kind": kind}
        if kind != e.kind:
            upd.update(rolloff_s=None, observer_pole=None)
        out.append((label, kind, spec.model_copy(update={"estimator": e.model_copy(update=upd)})))
    return out


def prepare(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile) -> list[Candidate]:
    """Design and allocate every candidate; errors are kept, not raised.

    Parameters
    ----------
    spec : DesignSpec
        The spec whose estimator is varied.
    machine, bench : MachineProfile, BenchProfile
        The machine each candidate is allocated on, the bench its estimator is shaped for.

    Returns
    -------
    list of Candidate
        In CANDIDATES order; one that does not design or fit keeps its one-line error.
    """
    out = []
    for label, kind, sp in candidate_specs(spec):
        try:
            d = design_on(sp, machine, bench)
        except InputError as exc:
            out.append(Candidate(label=label, kind=kind, design=None, netlist=None, error=exc.message))
            continue
        try:
            net = build_patch(d, machine, 1)
        except InputError as exc:
            if machine.max_units == 1:
                out.append(Candidate(label=label, kind=kind, design=d, netlist=None, error=exc.message))
                continue
            try:  # slaved units, as the machine allows
                net = build_patch(d, machine, "auto")
                label = f"{label} ({net.units} slaved units)"
            except InputError as exc2:
                out.append(Candidate(label=label, kind=kind, design=d, netlist=None, error=exc2.message))
                continue
        out.append(Candidate(label=label, kind=kind, design=d, netlist=net, error=None, estimator_detail=_detail(d)))
    return out


def _detail(d: Design) -> str:
    """The estimator's setting in a few words, for the table."""
    e = d.estimator
    if e is None:
        return ""
    how = " (from the bench noise)" if e.chosen_from_noise else ""
    if e.kind in ("differentiator", "filtered_differentiator"):
        return f"roll-off {e.rolloff_s:g} s{how}"
    if e.kind == "reduced_observer":
        return f"pole {e.observer.pole:g} rad/s{how}"
    return f"rho {e.rho:g}"


def evaluate(c: Candidate, bench: BenchProfile, machine: MachineProfile, scenario: Scenario, runs: int,
             seed: int | None, progress: Callable[[int], None] | None = None) -> Candidate:
    """Monte Carlo of one allocated candidate on the bench.

    Returns
    -------
    Candidate
        ``c`` with its bench figures: runs held (no overload), fallen, tripped, overloaded,
        worst swing (the rails when any run overloaded) and the runs themselves.
    """
    plant = plant_params(c.design.spec)
    res = simulate(c.netlist, plant, bench, machine, scenario, seed=seed, runs=runs,
                   keep_history=True, progress=progress)
    D = res.distribution
    ok = sum(1 for r in res.runs if r.held and not r.overloads) / len(res.runs)
    swing = max(float(abs(res.history[a]).max()) for a in res.amplifiers)
    swing = max([swing] + [r.max_abs_u_c_V for r in res.runs])
    if any(r.overloads for r in res.runs):
        swing = max(swing, machine.imperfections.saturation_V)
    return replace(c, error=None, runs=runs, fraction_ok=ok, fraction_fallen=D.fraction_fallen,
                   fraction_tripped=D.fraction_tripped, fraction_overloaded=D.fraction_overloaded,
                   worst_swing_V=swing, results=tuple(res.runs),
                   bench_loop=diagnose(c.netlist, plant, bench)[-1].verdict)


def recommend(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile, scenario: Scenario,
              runs: int = RUNS, seed: int | None = None,
              progress: Callable[[str, int, int], None] | None = None) -> Recommendation:
    """Design, allocate and simulate every candidate, and rank them.

    Parameters
    ----------
    spec : DesignSpec
        The spec whose estimator is varied.
    machine, bench : MachineProfile, BenchProfile
        The machine the patches are allocated on and the bench they are simulated on.
    scenario : Scenario
        The Monte Carlo's scenario.
    runs : int
        Noise seeds per candidate.
    seed : int, optional
        Base seed (default: the scenario's).
    progress : callable, optional
        Called as ``progress(label, done, total)`` while the Monte Carlo runs: the candidate
        being simulated, the runs done and the runs to do over all candidates that fit.

    Returns
    -------
    Recommendation
        The candidates ranked best first (see the module's ranking).
    """
    cands = prepare(spec, machine, bench)
    total = runs * sum(c.netlist is not None for c in cands)
    done, base = [], 0
    for c in cands:
        if c.netlist is None:
            done.append(c)
            continue
        cb = (lambda n, lab=c.label, b=base: progress(lab, b + n, total)) if progress else None
        done.append(evaluate(c, bench, machine, scenario, runs, seed, cb))
        base += runs
    order = {c.label: i for i, c in enumerate(done)}
    ranked = tuple(sorted(done, key=lambda c: c.rank_key(order[c.label])))
    return Recommendation(spec, scenario, runs, scenario.seed if seed is None else seed, ranked)
