"""recommend ranks a compensator by its loop as patched: a candidate's margins are the wired loop's
(the netlist read back, pots as dialled) on the bench, not the design's."""

from dataclasses import replace

import pytest

from patchgen.bench.diagnosis import as_patched_on_bench
from patchgen.inputs.spec import load_spec
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.studies.ranking import ScenarioOutcome
from patchgen.studies.recommend import allocate

M, BENCH = load_machine("gp6"), load_bench("uw-1991")


def _candidate(max_units):
    sp = load_spec("thesis-case2")
    sp = sp.model_copy(update={"patch": sp.patch.model_copy(update={"max_units": max_units})})
    return allocate(f"Kalman, compensator, {max_units} units", "kalman", sp, M, BENCH)


@pytest.fixture(scope="module")
def candidates():
    return {n: _candidate(n) for n in (4, 3)}


def test_a_compensator_candidates_margins_are_its_loop_as_patched_on_the_bench(candidates):
    c = candidates[4]
    j = as_patched_on_bench(c.design, c.netlist, M, BENCH)
    assert c.netlist.units == 4 and c.margins.stable and j.bench.margins.stable
    assert c.pm_deg == pytest.approx(j.bench.margins.pm_deg, abs=1e-9)
    assert c.margins.lower_gm_db == pytest.approx(j.bench.margins.lower_gm_db, abs=1e-9)
    assert c.margins.upper_gm_db == pytest.approx(j.bench.margins.upper_gm_db, abs=1e-9)
    # not the design's: the design model has the 0.1 s actuator, the bench 0.2 s
    assert c.pm_deg == pytest.approx(29.12, abs=0.01) and c.design.lqg_margins.pm_deg == pytest.approx(52.78, abs=0.01)
    # held to three units, the residualised law's loop does not balance on the bench at all
    r = candidates[3]
    assert r.netlist.units == 3 and not r.margins.stable and r.pm_deg is None and r.bench_loop == "unstable"


def test_the_patch_that_keeps_its_margins_ranks_first(candidates):
    held = (ScenarioOutcome("hold-120s", 80, 80, 0, 0, 0, 1.0),)
    kept, lost = (candidates[n] for n in (4, 3))
    kept, lost = replace(kept, outcomes=held), replace(lost, outcomes=held)  # held as often: the loop tells
    ranked = sorted([lost, kept], key=lambda c: c.rank_key(0))
    assert ranked[0] is kept
