"""Recommend a patch: every way of getting the unmeasured states that the machine can hold, with
the spec's actuator model and with the bench's, each designed, allocated and run on the bench in
every scenario, ranked by what the bench would do.

Candidates (same plant, weights and integral states as the spec): the raw differentiator of the
thesis (the machine's default roll-off), a filtered differentiator and a reduced-order observer
(their speed from the bench noise, patchgen.design.corner), and the Kalman estimator (the spec's
settings when it has them); and, when the spec's design model of the actuator is not the bench's
(the thesis's section 5.3 assumed a pure gain where the bench has a 0.2 s lag), each of these
again designed with the bench's actuator. A candidate that does not fit keeps its error.

Each candidate is judged by patchgen.studies.ranking: its wired loop's linear verdict on the bench
(patchgen.bench.diagnosis), then a sequential Monte Carlo over every scenario (rounds of
ranking.ROUND_RUNS runs per scenario, stopped once every scenario's held fraction is clearly
above ranking.TARGET or one is clearly below it, by its Wilson interval, else at ``runs``).

Ranking, best first: simulated; a wired loop stable on the bench (a marginal or unstable one ranks
below every stable one and is never chosen); holds, undecided, fails; for those that do not
clearly hold, the weakest scenario's held fraction; then the wired loop's gain margin on the
bench (the nearer limit, dB) and phase margin; then hardware (units, amplifiers, pots); then the
candidate order. Figures are rounded before ranking so the order is deterministic.

When the bench states ranges for its parameters (its ``[uncertainty]`` table), every run draws its
bench from them, so the held fractions are over the bench's uncertainty; each stable candidate is
also run at the corners of the ranges (every corner, or the worst searched for past three ranges)
and at each end of each range in its weakest scenario (ties: the longest; CORNER_RUNS seeds each,
patchgen.studies.bench_corners), which names its weakest parameter; the worst corner's held fraction
ranks right after the verdict, and a candidate is chosen only if it held in at least TARGET of the
runs at its worst corner. When none is chosen, one whose gains are
chosen over the corners joins them (patchgen.studies.robust, ``extra_candidates``) before any
variant of the spec: a search over weights costs a study per weight, worth it only when the spec's
own realisations do not hold at their worst corner.

When none of these is chosen, the spec's variants are tried (patchgen.studies.variants), each with
every candidate above, a tier at a time, nearest first, until one is chosen. Every candidate carries
its departures from the spec (patchgen.studies.departures), so the one chosen names them.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numba

from patchgen.bench.diagnosis import bench_margins, diagnose
from patchgen.bench.simulate import simulate
from patchgen.design.lqg import Design
from patchgen.design.model import plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.studies import robust, variants
from patchgen.studies.bench_corners import study
from patchgen.studies.candidate import Candidate, Recommendation
from patchgen.studies.compensator_candidates import compensator_specs
from patchgen.studies.departures import departures, realisation_whys, settled_spec
from patchgen.studies.design_memo import designed
from patchgen.studies.ranking import ROUND_RUNS, ScenarioOutcome, decision, outcome

CANDIDATES = (
    ("raw differentiator", "differentiator"),
    ("filtered differentiator", "filtered_differentiator"),
    ("reduced observer", "reduced_observer"),
    ("Kalman", "kalman"),
)

RUNS = 200  # the most noise seeds per candidate and scenario
DESIGNING = "designing and allocating every realisation"  # the first thing progress hears
CORNER_RUNS = 64  # seeds at each corner and each end of the bench's ranges
CANDIDATES_AT_ONCE = 1  # candidates simulated side by side, per core (_Runner)

def candidate_specs(spec: DesignSpec, bench: BenchProfile) -> list[tuple[str, str, DesignSpec]]:
    """The spec with each estimator kind (plant, weights, integrators unchanged), each wired as its
    states; then, when the spec's actuator model is not the bench's, each again with the bench's
    actuator."""
    actuators = [("", spec.actuator)]
    b = bench.actuator
    mine = spec.actuator
    if (mine.model, mine.K_U, mine.tau) != (b.model, b.K_U, b.tau):
        bench_act = mine.model_copy(update={"model": b.model, "K_U": b.K_U, "tau": b.tau,
                                            "dead_zone_V": b.dead_zone_V})
        tag = f"lag {b.tau:g} s" if b.model == "lag" else b.model
        actuators.append((f", designed with the bench actuator ({tag})", bench_act))
    out = []
    for suffix, act in actuators:
        for label, kind in CANDIDATES:
            e = spec.estimator
            upd: dict = {"kind": kind}
            if kind != e.kind or suffix:
                upd.update(rolloff_s=None, observer_pole=None)
            read = spec.sensors.read()
            if kind == "kalman" != e.kind and e.V and not isinstance(e.V[0], list) and len(e.V) != len(read):
                upd["V"] = [1.0] * len(read)  # the default's unit noise, one per signal the bench gives
            est = e.model_copy(update=upd)
            # wired as its states: the compensator as one system is compensator_specs' candidate
            patch = spec.patch.model_copy(update={"realization": "states", "order": "full"})
            out.append((label + suffix, kind, spec.model_copy(update={"estimator": est, "actuator": act,
                                                                       "patch": patch})))
    return out


def prepare(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile) -> list[Candidate]:
    """Design and allocate every candidate, with its wired loop's verdict and margins on the bench;
    errors are kept, not raised.

    Parameters
    ----------
    spec : DesignSpec
        The spec whose estimator (and actuator model) is varied.
    machine, bench : MachineProfile, BenchProfile
        The machine each candidate is allocated on, the bench it is judged on.

    Returns
    -------
    list of Candidate
        In candidate_specs order; one that does not design or fit keeps its one-line error.
    """
    specs = candidate_specs(spec, bench)
    specs += compensator_specs(specs, machine, bench)
    return [allocate(label, kind, sp, machine, bench) for label, kind, sp in specs]


def allocate(label: str, kind: str, sp: DesignSpec, machine: MachineProfile, bench: BenchProfile) -> Candidate:
    """One candidate designed and allocated (on slaved units if the machine allows and one is not
    enough), with its wired loop's verdict and margins on the bench; an error is kept."""
    try:
        d = designed(sp, machine, bench)
    except InputError as exc:
        return Candidate(label, kind, sp, None, None, exc.message)
    try:
        net = build_patch(d, machine, 1)
    except InputError as exc:
        if machine.max_units == 1:
            return Candidate(label, kind, sp, d, None, exc.message)
        try:  # slaved units, as the machine allows
            net = build_patch(d, machine, "auto")
            label = f"{label} ({net.units} slaved units)"
        except InputError as exc2:
            return Candidate(label, kind, sp, d, None, exc2.message)
    plant = d.plant
    loop = diagnose(net, plant, bench)[-1]
    return Candidate(label, kind, sp, d, net, None, _detail(d), loop.verdict, loop.line(),
                     bench_margins(net, plant, bench))


def extra_candidates(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile, scenarios: Sequence[Scenario],
                     seed: int | None = None, progress: Callable[[int, int], None] | None = None) -> list[Candidate]:
    """When the bench states ranges: the candidate whose gains (and integral action) are chosen
    over the corners of the ranges (patchgen.studies.robust.search, ``progress`` its); none otherwise."""
    choice = robust.search(spec, machine, bench, scenarios, seed, progress)
    if choice is None:
        return []
    c = allocate(f"{robust.LABEL}, {spec.estimator.kind.replace('_', ' ')}", spec.estimator.kind, choice.spec,
                 machine, bench)
    same = (c.netlist is not None and c.netlist == choice.netlist
            and c.design.plant == plant_params(choice.spec))
    return [replace(c, robust_note=choice.detail(), searched=choice.studies if same else ())]


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


def _swing(res, machine: MachineProfile) -> float:
    """The largest amplifier output of a Monte Carlo: run 0's history and every run's u_c (the
    rails when any run overloaded)."""
    swing = max([0.0] + [float(abs(res.history[a]).max()) for a in res.amplifiers] if res.history else [0.0])
    swing = max([swing] + [r.max_abs_u_c_V for r in res.runs])
    if any(r.overloads for r in res.runs):
        swing = max(swing, machine.imperfections.saturation_V)
    return swing


def evaluate(c: Candidate, bench: BenchProfile, machine: MachineProfile, scenarios: Sequence[Scenario],
             max_runs: int, seed: int | None, early_stop: bool = True,
             progress: Callable[[int], None] | None = None,
             phase: Callable[[str, int, int], None] | None = None) -> Candidate:
    """The sequential Monte Carlo of one allocated candidate on the bench, every scenario.

    Rounds of ROUND_RUNS runs per scenario (run i of a scenario always draws from its seed and i,
    so a round continues the runs before it) until the candidate clearly holds or clearly fails
    (patchgen.studies.ranking.decision), or every scenario has ``max_runs`` runs. When the bench
    states ranges, every run draws its bench from them, and a stable candidate is then run at the
    corners and ends of the ranges in its weakest scenario (``bench_study``).

    Parameters
    ----------
    c : Candidate
        An allocated candidate.
    bench, machine : BenchProfile, MachineProfile
        What it runs on.
    scenarios : sequence of Scenario
        Every scenario it is judged on.
    max_runs : int
        The most runs per scenario.
    seed : int, optional
        Every scenario's base seed (default: each scenario's own).
    early_stop : bool
        Stop at a clear decision; False runs ``max_runs`` of every scenario.
    progress : callable, optional
        Called with the runs done so far (over every scenario).
    phase : callable, optional
        ``phase(what, done, total)`` while the corners of the bench's ranges run (batches).

    Returns
    -------
    Candidate
        ``c`` with its outcomes.
    """
    plant = c.design.plant
    runs_of = {sc.name: [] for sc in scenarios}
    swing = {sc.name: 0.0 for sc in scenarios}
    done = 0
    outcomes: tuple[ScenarioOutcome, ...] = ()
    while True:
        jobs = [(sc, len(runs_of[sc.name]), min(ROUND_RUNS, max_runs - len(runs_of[sc.name]))) for sc in scenarios]
        jobs = [j for j in jobs if j[2] > 0]

        def one(job):
            sc, have, n = job
            return simulate(c.netlist, plant, bench, machine, sc, seed=seed, runs=n, first_run=have,
                            keep_history=have == 0, bench_spread=bool(bench.uncertainty.ranges))

        # a round's scenarios side by side, a thread each (the engine releases the GIL): a scenario's
        # runs depend on their seeds alone, so the figures are the same on any number of threads
        with ThreadPoolExecutor(max(1, min(len(jobs), numba.get_num_threads()))) as pool:
            for (sc, _, n), res in zip(jobs, pool.map(one, jobs)):
                runs_of[sc.name].extend(res.runs)
                swing[sc.name] = max(swing[sc.name], _swing(res, machine))
                done += n
                if progress is not None:
                    progress(done)
        outcomes = tuple(outcome(sc.name, runs_of[sc.name], swing[sc.name]) for sc in scenarios)
        full = all(len(v) >= max_runs for v in runs_of.values())
        if full or (early_stop and decision(outcomes) != "undecided"):
            break
    st = None
    if bench.uncertainty.ranges and c.bench_loop == "stable":
        held = {o.scenario: (o.fraction, o.interval[1]) for o in outcomes}  # ties: the longest scenario
        weak = min(scenarios, key=lambda sc: (*held[sc.name], -sc.duration_s))
        searched = [s.corners for s in c.searched if s.scenario == weak.name and CORNER_RUNS == robust.SEARCH_RUNS]
        where = (lambda d, t: phase(f"worst corner of the bench's ranges in {weak.name}", d, t)) if phase else None
        st = study(c.netlist, plant, bench, machine, weak, seed=seed, corner_runs=CORNER_RUNS, ends=True,
                   known=searched[0] if searched else (), progress=where)
    return replace(c, outcomes=outcomes, bench_study=st)


def recommend(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile, scenarios: Sequence[Scenario],
              runs: int = RUNS, seed: int | None = None, early_stop: bool = True,
              progress: Callable[[str, int, int], None] | None = None) -> Recommendation:
    """Design, allocate and simulate every candidate on every scenario, and rank them; when none
    holds, the spec's variants too (patchgen.studies.variants), nearest first, until one does.

    Parameters
    ----------
    spec : DesignSpec
        The spec whose estimator (and actuator model) is varied.
    machine, bench : MachineProfile, BenchProfile
        The machine the patches are allocated on and the bench they are simulated on.
    scenarios : sequence of Scenario
        The scenarios every candidate must hold (the command's default: every shipped one).
    runs : int
        The most noise seeds per candidate and scenario.
    seed : int, optional
        Every scenario's base seed (default: each scenario's own).
    early_stop : bool
        End a candidate's Monte Carlo once it clearly holds or clearly fails.
    progress : callable, optional
        Called as ``progress(label, done, total)``: the candidate being simulated, the runs done
        and the most runs there can be over every candidate that fits so far (it may finish early;
        a tier of variants adds its own).

    Returns
    -------
    Recommendation
        The candidates ranked best first (see the module docstring), each with its departures
        from ``spec``.
    """
    if progress is not None:
        progress(DESIGNING, 0, 0)
    run = _Runner(bench, machine, scenarios, runs, seed, early_stop, progress)
    done = run([departed(c, spec, bench) for c in prepare(spec, machine, bench)])
    rec = _ranked(spec, scenarios, runs, seed, done, bench)
    if rec.best is None and bench.uncertainty.ranges:  # gains chosen over the corners, when none holds there
        robust_why = {"weights": f"{robust.LABEL}: {robust.WHY_GAINS}", "integrators.int_s": robust.LABEL}
        where = (lambda i, n: progress(f"{robust.LABEL}: weights over the corners, {i} of {n} ruled out or chosen",
                                       run.base, run.total)) if progress else None
        done += run([departed(c, spec, bench, robust_why)
                     for c in extra_candidates(spec, machine, bench, scenarios, seed, where)])
        rec = _ranked(spec, scenarios, runs, seed, done, bench)
    if rec.best is not None:
        return rec
    below = any(variants.below_dial(c.design, machine) for c in done if c.netlist is not None)
    seen = {_patch_key(c.netlist) for c in done if c.netlist is not None}
    tried, repeated, unfit = [], 0, 0
    for tier in variants.tiers(spec, machine, bench, below):
        fresh, r, u = _tier_candidates(tier, spec, machine, bench, seen)
        tried, repeated, unfit = tried + [v.name for v in tier], repeated + r, unfit + u
        done += run(fresh)
        rec = _ranked(spec, scenarios, runs, seed, done, bench, tuple(tried), repeated, unfit)
        if rec.best is not None:
            break
    return rec


def _tier_candidates(tier: list[variants.Variant], spec: DesignSpec, machine: MachineProfile, bench: BenchProfile,
                     seen: set[str]) -> tuple[list[Candidate], int, int]:
    """Every candidate of a tier's variants whose patch is not in ``seen`` (which it joins), named
    after its variant and with its departures; and how many gave a patch already run, or none."""
    fresh, repeated, unfit = [], 0, 0
    for v in tier:
        for c in prepare(v.spec, machine, bench):
            key = None if c.netlist is None else _patch_key(c.netlist)
            repeated += key in seen
            unfit += key is None
            if key is not None and key not in seen:
                seen.add(key)
                fresh.append(departed(replace(c, label=f"{c.label}; {v.name}", variant=v.name), spec, bench, v.whys))
    return fresh, repeated, unfit


class _Runner:
    """Simulates candidates, a few side by side (CANDIDATES_AT_ONCE a core), reporting progress
    over every candidate run so far (a call's candidates add their most runs to the total).

    A candidate's figures depend on its seeds alone, so they are the same however many run at
    once; running two keeps both cores busy while one candidate's round waits on its longest
    scenario, which runs alone."""

    def __init__(self, bench: BenchProfile, machine: MachineProfile, scenarios: Sequence[Scenario], runs: int,
                 seed: int | None, early_stop: bool, progress: Callable[[str, int, int], None] | None):
        self.args = (bench, machine, scenarios, runs, seed, early_stop)
        self.progress, self.per, self.base, self.total = progress, runs * len(scenarios), 0, 0
        self.lock = threading.Lock()

    def __call__(self, cands: list[Candidate]) -> list[Candidate]:
        bench, machine, scenarios, runs, seed, early_stop = self.args
        progress, per, base = self.progress, self.per, self.base
        total = self.total = base + per * sum(c.netlist is not None for c in cands)
        done_of: dict[int, int] = {}  # runs done of each candidate under way or finished

        def report(i: int, label: str, n: int) -> None:
            with self.lock:
                done_of[i] = n
                progress(label, base + sum(done_of.values()), total)

        def one(i: int, c: Candidate) -> Candidate:
            cb = ph = None
            if progress is not None:
                cb = lambda n: report(i, c.label, n)  # noqa: E731
                # the candidate's Monte Carlo is over when its corners run
                ph = lambda what, d, t: report(i, f"{c.label}: {what}, batch {d} of {t}", per)  # noqa: E731
            out = evaluate(c, bench, machine, scenarios, runs, seed, early_stop, cb, ph)
            if progress is not None:
                report(i, c.label, per)
            return out

        todo = [(i, c) for i, c in enumerate(cands) if c.netlist is not None]
        workers = max(1, min(len(todo), CANDIDATES_AT_ONCE * numba.get_num_threads()))
        with ThreadPoolExecutor(workers) as pool:
            ran = dict(zip((i for i, _ in todo), pool.map(lambda ic: one(*ic), todo)))
        self.base += per * len(todo)
        return [ran.get(i, c) for i, c in enumerate(cands)]


def _ranked(spec: DesignSpec, scenarios: Sequence[Scenario], runs: int, seed: int | None, done: list[Candidate],
            bench: BenchProfile, tried: tuple[str, ...] = (), repeated: int = 0, unfit: int = 0) -> Recommendation:
    """The candidates ranked (ties: the order they were made in)."""
    order = {id(c): i for i, c in enumerate(done)}
    ranked = tuple(sorted(done, key=lambda c: c.rank_key(order[id(c)])))
    return Recommendation(spec, tuple(scenarios), runs, seed, ranked, dict(bench.uncertainty.ranges),
                          bench.uncertainty.distribution, variants=tried, repeated=repeated, unfit=unfit)


def _patch_key(net) -> str:
    """What a patch wires, without its names and notes: two candidates with one key run alike."""
    return net.model_dump_json(exclude={"design", "description", "notes"})


def departed(c: Candidate, base: DesignSpec, bench: BenchProfile, whys: dict[str, str] | None = None) -> Candidate:
    """``c`` with its departures from ``base`` (patchgen.studies.departures): the fields its
    written spec changes, each with why (``whys`` adds a variant's reasons)."""
    units = None if c.netlist is None else c.netlist.units
    why = realisation_whys(c.spec, c.design, bench, units) | (whys or {})
    return replace(c, departures=departures(base, settled_spec(c.spec, c.design, units), why))


def chosen_spec(rec: Recommendation) -> DesignSpec:
    """The chosen candidate as a spec every other command takes (``recommended.toml``): its spec
    as patchgen.studies.departures.settled_spec writes it (the settings chosen from the bench
    noise fixed, the slaved units it needs), so that patching it gives the chosen patch again."""
    b = rec.best
    if b is None:
        raise ValueError("no candidate was chosen")
    return settled_spec(b.spec, b.design, b.netlist.units).model_copy(update={
        "name": f"{rec.spec.name}-recommended",
        "description": f"{b.label}: chosen by patchgen recommend on the bench",
        "source": f"patchgen recommend {rec.spec.path}",
    })
