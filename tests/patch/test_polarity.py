"""The bitmask polarity search against the straightforward search it replaced (kept here as the
oracle): the same polarities, shared inverters and pre-summers, in the same order."""

from __future__ import annotations

import itertools

from hypothesis import given, settings
from hypothesis import strategies as st

from patchgen.patch.jacks import jacks_test, weight_for
from patchgen.patch.polarity import search
from patchgen.patch.realization import Block, Term
from patchgen.profiles.machine import load_machine

MACHINES = [None, load_machine("gp6"), load_machine("the-analog-thing")]
SENSORS = ["s", "theta", "s_dot"]


def _oracle_jacks_test(blocks, kept, machine):
    if machine is None:
        return lambda pre: True
    ws = tuple(machine.input_weights)
    cap = tuple(max(a.input_count(w) for a in machine.amplifiers) for w in ws)
    lowest = ws.index(min(ws))
    per_block = []
    for b in blocks:
        by_signal: dict[str, list[int]] = {}
        for t in kept[b.name]:
            by_signal.setdefault(t.signal, [0] * len(ws))[ws.index(weight_for(abs(t.coeff), machine))] += 1
        total = [sum(row[i] for row in by_signal.values()) for i in range(len(ws))]
        per_block.append((b.name, by_signal, total))

    def fits(pre):
        for name, by_signal, total in per_block:
            main, staged = list(total), [0] * len(ws)
            if name in pre:
                main[lowest] += 1
                for sig in pre[name]:
                    for i, n in enumerate(by_signal.get(sig, ())):
                        main[i] -= n
                        staged[i] += n
            if any(m > c or st > c for m, st, c in zip(main, staged, cap)):
                return False
        return True

    return fits


def _oracle_search(blocks, kept, machine=None):
    free = [b.name for b in blocks if b.name != "u_c"]
    fits = _oracle_jacks_test(blocks, kept, machine)
    best = None
    for pols in itertools.product((-1, 1), repeat=len(free)):
        P = dict(zip(free, pols))
        P["u_c"] = 1
        mism: dict[str, set[str]] = {}
        for b in blocks:
            for t in kept[b.name]:
                have = P.get(t.signal, 1)
                need = -P[b.name] * (1 if t.coeff > 0 else -1)
                if have != need:
                    mism.setdefault(b.name, set()).add(t.signal)
        cand = sorted(set().union(*mism.values())) if mism else []
        for k in range(len(cand) + 1):
            if best is not None and k >= best[0][0]:
                break
            for inv in itertools.combinations(cand, k):
                shared = set(inv)
                pre = {b: m - shared for b, m in mism.items() if not m <= shared}
                cost = (k + len(pre), k)
                if best is not None and cost >= best[0]:
                    continue
                if fits(pre):
                    best = (cost, P, shared, pre)
    if best is None:
        return _oracle_search(blocks, kept, None)
    return best[1], best[2], best[3]


# magnitudes on either input weight, at a weight exactly (no pot) and above the largest
COEFFS = st.sampled_from([0.3, 1.0, 2.5, 10.0, 12.0]).flatmap(lambda m: st.sampled_from([m, -m, 0.0]))


@st.composite
def structures(draw):
    """A few blocks (u_c among them, anywhere), each reading sensors and blocks (itself too)."""
    n = draw(st.integers(1, 5))
    names = [f"x{i}" for i in range(n - 1)]
    names.insert(draw(st.integers(0, n - 1)), "u_c")
    sources = SENSORS + names + ["gone"]  # "gone": a block left out, positive like a sensor
    blocks, kept = [], {}
    for name in names:
        terms = draw(st.lists(st.tuples(st.sampled_from(sources), COEFFS), max_size=7))
        kept[name] = [Term(s, c) for s, c in terms]
        blocks.append(Block(name, "sum", tuple(kept[name]), 1.0, "V", name))
    return blocks, kept


def _ordered(result):
    P, shared, pre = result
    return list(P.items()), sorted(shared), [(b, sorted(m)) for b, m in pre.items()]


@settings(max_examples=400, deadline=None)
@given(structures(), st.sampled_from(MACHINES))
def test_search_matches_the_straightforward_search(structure, machine):
    blocks, kept = structure
    assert _ordered(search(blocks, kept, machine)) == _ordered(_oracle_search(blocks, kept, machine))


@settings(max_examples=200, deadline=None)
@given(structures(), st.sampled_from(MACHINES[1:]), st.data())
def test_jacks_test_matches_the_straightforward_test(structure, machine, data):
    blocks, kept = structure
    signals = sorted({t.signal for ts in kept.values() for t in ts} | {"elsewhere"})
    pre = data.draw(st.dictionaries(st.sampled_from([b.name for b in blocks]),
                                    st.sets(st.sampled_from(signals))))
    assert jacks_test(blocks, kept, machine)(pre) == _oracle_jacks_test(blocks, kept, machine)(pre)
