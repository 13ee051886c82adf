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
from dataclasses import dataclass, field

from patchgen.bench.simulate import RunSummary, simulate
from patchgen.design.lqg import Design, design
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


@dataclass(frozen=True)
class Candidate:
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
        m = self.design.lqg_margins if self.design is not None else None
        return None if m is None or not m.stable else m.pm_deg

    @property
    def amplifiers(self) -> int | None:
        return None if self.netlist is None else len(self.netlist.amplifiers)

    @property
    def pots(self) -> int | None:
        return None if self.netlist is None else len(self.netlist.pots)

    def rank_key(self, order: int):
        if self.fraction_ok is None:
            return (1, 0.0, 0, 0.0, 0.0, 0.0, order)
        r = lambda x, n: -round(x, n) if x is not None and math.isfinite(x) else (-1e9 if x else 0.0)
        units = self.netlist.units if self.netlist is not None else 1
        return (0, -round(self.fraction_ok, 6), units, r(self.gm_db, 1), r(self.pm_deg, 1),
                round(self.worst_swing_V or 0.0, 2), order)


@dataclass(frozen=True)
class Recommendation:
    spec: DesignSpec
    scenario: Scenario
    runs: int
    seed: int
    ranked: tuple[Candidate, ...]

    @property
    def best(self) -> Candidate | None:
        b = self.ranked[0] if self.ranked else None
        return b if b is not None and b.netlist is not None and b.fraction_ok is not None else None


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


def prepare(spec: DesignSpec, machine: MachineProfile) -> list[Candidate]:
    """Design and allocate every candidate; errors are kept, not raised."""
    out = []
    for label, kind, sp in candidate_specs(spec):
        try:
            d = design(sp, default_rolloff_s=machine.imperfections.differentiator_rolloff_s)
        except InputError as exc:
            out.append(Candidate(label, kind, None, None, exc.message))
            continue
        try:
            net = build_patch(d, machine, 1)
        except InputError as exc:
            if machine.max_units == 1:
                out.append(Candidate(label, kind, d, None, exc.message))
                continue
            try:  # slaved units, as the machine allows
                net = build_patch(d, machine, "auto")
                label = f"{label} ({net.units} slaved units)"
            except InputError as exc2:
                out.append(Candidate(label, kind, d, None, exc2.message))
                continue
        out.append(Candidate(label, kind, d, net, None, estimator_detail=_detail(d)))
    return out


def _detail(d: Design) -> str:
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
    """Monte Carlo of one allocated candidate on the bench."""
    res = simulate(c.netlist, plant_params(c.design.spec), bench, machine, scenario, seed=seed, runs=runs,
                   keep_history=True, progress=progress)
    D = res.distribution
    ok = sum(1 for r in res.runs if r.held and not r.overloads) / len(res.runs)
    swing = max(float(abs(res.history[a]).max()) for a in res.amplifiers)
    swing = max([swing] + [r.max_abs_u_c_V for r in res.runs])
    if any(r.overloads for r in res.runs):
        swing = max(swing, machine.imperfections.saturation_V)
    return Candidate(c.label, c.kind, c.design, c.netlist, None, runs, ok, D.fraction_fallen,
                     D.fraction_tripped, D.fraction_overloaded, swing, c.estimator_detail, tuple(res.runs))


def recommend(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile, scenario: Scenario,
              runs: int = 200, seed: int | None = None,
              progress: Callable[[str, int], None] | None = None) -> Recommendation:
    """Design, allocate and simulate every candidate, and rank them."""
    cands = prepare(spec, machine)
    done = []
    for c in cands:
        if c.netlist is None:
            done.append(c)
            continue
        cb = (lambda n, lab=c.label: progress(lab, n)) if progress else None
        done.append(evaluate(c, bench, machine, scenario, runs, seed, cb))
    order = {c.label: i for i, c in enumerate(done)}
    ranked = tuple(sorted(done, key=lambda c: c.rank_key(order[c.label])))
    return Recommendation(spec, scenario, runs, scenario.seed if seed is None else seed, ranked)


def table_rows(rec: Recommendation) -> list[dict]:
    """One plain row per candidate, ranked (for the terminal, the sheet and --json)."""
    rows = []
    for i, c in enumerate(rec.ranked, 1):
        m = c.design.lqg_margins if c.design is not None else None
        rows.append({
            "rank": i if c.fraction_ok is not None else None,
            "realisation": c.label,
            "estimator": c.estimator_detail,
            "fraction_ok": c.fraction_ok,
            "fraction_fallen": c.fraction_fallen,
            "fraction_tripped": c.fraction_tripped,
            "fraction_overloaded": c.fraction_overloaded,
            "lower_gm_db": None if m is None or not m.stable else m.lower_gm_db,
            "upper_gm_db": None if m is None or not m.stable else m.upper_gm_db,
            "pm_deg": c.pm_deg,
            "loop_stable": None if m is None else m.stable,
            "worst_swing_V": c.worst_swing_V,
            "amplifiers": c.amplifiers,
            "pots": c.pots,
            "error": c.error,
        })
    return rows


def _f(x, fmt: str, none: str = "-") -> str:
    return none if x is None else (fmt.format(x) if math.isfinite(x) else "inf")


def table_markdown(rec: Recommendation, reference_V: float) -> str:
    """The comparison as a Markdown section body: why the first row was chosen."""
    head = ("| rank | realisation | estimator | held (of runs) | fallen | tripped | overloaded | "
            "GM lower / upper (dB) | PM (deg) | worst swing (V) | amps / pots |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in table_rows(rec):
        if r["error"]:
            lines.append(f"| - | {r['realisation']} | {r['estimator']} | not simulated: {r['error']} "
                         "| | | | | | | |")
            continue
        lines.append(
            f"| {r['rank']} | {r['realisation']} | {r['estimator']} | {r['fraction_ok']:.1%} | "
            f"{r['fraction_fallen']:.1%} | {r['fraction_tripped']:.1%} | {r['fraction_overloaded']:.1%} | "
            f"{_f(r['lower_gm_db'], '{:+.1f}', 'none')} / {_f(r['upper_gm_db'], '{:+.1f}', 'inf')} | "
            f"{_f(r['pm_deg'], '{:.1f}')} | {r['worst_swing_V']:.2f} of {reference_V:g} | "
            f"{r['amplifiers']} / {r['pots']} |")
    best = rec.best
    intro = (f"Each way of getting theta_dot (and the actuator state) that fits the machine was designed, "
             f"allocated and simulated on the bench ({rec.scenario.name}: {rec.scenario.description}), "
             f"{rec.runs} noise seeds from seed {rec.seed}, with the bench actuator, sensor noise and "
             "integrator drift. 'held' counts runs where the pendulum stayed up, the cart stayed inside "
             "the limit switches and no amplifier left the rails for the whole scenario. Ranked by that, "
             "then by the loop's gain margin (nearer limit), phase margin, and worst amplifier swing.\n\n")
    tail = f"\nChosen: **{best.label}**.\n" if best else "\nNo candidate could be simulated.\n"
    return intro + head + "\n".join(lines) + "\n" + tail
