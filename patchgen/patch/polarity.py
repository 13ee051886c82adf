"""The polarity search: block polarities and shared inverters that need the fewest amplifiers.

Every amplifier inverts, so a term c v into a block of polarity P must arrive as -P sign(c) v;
a signal at the other polarity needs a shared inverter or its block's pre-summer. The search
tries every polarity (itertools.product order) and, per polarity, every set of shared inverters
by size (itertools.combinations of the sorted candidates); the first cheapest that fits the
jacks wins, so the result is deterministic. Signal sets are integer bitmasks
(patchgen.patch.jacks.signal_bits), and the pre-summers of a choice are built only when its cost
can beat the best so far. Skipped without a change to the result: a polarity with a block that
fits for no choice of inverters, a number of inverters that leaves too many pre-summers, and every
set of inverters that starts with a choice no completion of which leaves few enough
(:func:`_inverter_sets`).
"""

from __future__ import annotations

import functools
import operator

from patchgen.patch.jacks import JackFit, signal_bits
from patchgen.patch.realization import Block, Term
from patchgen.profiles.machine import MachineProfile


def _mismatch_tables(blocks: list[Block], kept: dict[str, list[Term]], free: list[str], bit: dict[str, int]):
    """Per block and block polarity (index 0: -1, 1: +1): the bits of its terms mismatched whatever
    the free polarities are, and per free signal j the bits mismatched when P_j is -1 or +1."""
    slot = {name: j for j, name in enumerate(free)}
    tables = []
    for b in blocks:
        per_pol = []
        for pb in (-1, 1):
            fixed, by_free = 0, {}
            for t in kept[b.name]:
                need = -pb * (1 if t.coeff > 0 else -1)
                j = slot.get(t.signal)
                if j is None:  # sensors, u_c and dropped blocks are positive
                    if need != 1:
                        fixed |= bit[t.signal]
                else:
                    row = by_free.setdefault(j, [0, 0])
                    row[0 if need == 1 else 1] |= bit[t.signal]  # mismatched when P_j is -need
            per_pol.append((fixed, [(j, neg, pos) for j, (neg, pos) in by_free.items()]))
        tables.append((slot.get(b.name), per_pol))
    return tables


def _polarities(tables, fit: JackFit, n: int):
    """The free polarities (itertools.product order) with each block's mismatched signal bits,
    less every choice under which some block fits for no choice of shared inverters: a block is
    judged as soon as the polarities its mismatches depend on are set, and every choice that
    shares those is dropped with it (each would fail the same test)."""
    ready: list[list[int]] = [[] for _ in range(n + 1)]  # blocks judged once polarities 0..d-1 are set
    for i, (j_own, per_pol) in enumerate(tables):
        deps = {j for _, by_free in per_pol for j, _, _ in by_free} | ({j_own} - {None})
        ready[max(deps) + 1 if deps else 0].append(i)
    pols = [0] * n
    masks = [0] * len(tables)

    def walk(d: int):
        for i in ready[d]:
            j_own, per_pol = tables[i]
            fixed, by_free = per_pol[0 if j_own is not None and pols[j_own] < 0 else 1]
            m = fixed
            for j, neg, pos in by_free:
                m |= pos if pols[j] > 0 else neg
            if not fit.possible(i, m):
                return
            masks[i] = m
        if d == n:
            yield tuple(pols), list(masks)
            return
        for p in (-1, 1):
            pols[d] = p
            yield from walk(d + 1)

    return walk(0)


def _uncovered_at_least(mism: list[tuple[int, int]], k: int) -> int:
    """Pre-summers every choice of k shared inverters leaves: blocks with more than k mismatched signals."""
    return sum(1 for _, m in mism if m.bit_count() > k)


def _pre_allowed(best: tuple[int, int], k: int) -> int:
    """The most pre-summers beside k inverters whose cost (k + pre-summers, k) is below ``best``."""
    return best[0] - k - (0 if k < best[1] else 1)


def _inverter_sets(cand: list[int], ms: list[int], k: int, allowed: list[int]):
    """The sets of k of the candidate inverters ``cand`` (bits), as masks, in
    itertools.combinations order, less every set that leaves more than ``allowed[0]`` of the
    mismatched blocks ``ms`` with a pre-summer: a choice of the first few is dropped, with every set
    that starts with it, when too many blocks keep a signal none of the later candidates gives or
    more signals than are left to choose. The caller lowers ``allowed[0]`` as it finds cheaper sets."""
    n = len(cand)
    later = [0] * (n + 1)  # later[j]: the candidates from j on
    for j in range(n - 1, -1, -1):
        later[j] = later[j + 1] | cand[j]

    def walk(start: int, left: int, shared: int):
        if left == 0:
            yield shared
            return
        for j in range(start, n - left + 1):
            s = shared | cand[j]
            unreachable = ~(s | later[j + 1])
            if sum(1 for m in ms if m & unreachable or (m & ~s).bit_count() >= left) > allowed[0]:
                continue
            yield from walk(j + 1, left - 1, s)

    return walk(0, k, 0)


def search(blocks: list[Block], kept: dict[str, list[Term]], machine: MachineProfile | None = None):
    """Choose block polarities and shared inverters minimising amplifiers (with inputs that fit);
    returns (P, shared inverters, pre-summers: block -> the signals it stages)."""
    free = [b.name for b in blocks if b.name != "u_c"]
    bit = signal_bits(blocks, kept)
    fit = JackFit(blocks, kept, machine, bit)
    tables = _mismatch_tables(blocks, kept, free, bit)
    best = None  # ((amplifiers, inverters), polarities, shared bits, pre: block index -> bits)
    for pols, masks in _polarities(tables, fit, len(free)):
        mism = [(i, m) for i, m in enumerate(masks) if m]  # blocks with a mismatched term, in order
        union = functools.reduce(operator.or_, masks, 0)
        cand = [1 << n for n in range(union.bit_length()) if union >> n & 1]  # sorted names
        ms = [m for _, m in mism]
        for k in range(len(cand) + 1):
            if best is not None and k >= best[0][0]:
                break  # k inverters alone cost as much as the best: so does every larger k
            if best is not None and _uncovered_at_least(mism, k) > _pre_allowed(best[0], k):
                continue  # every choice of k inverters leaves too many pre-summers to beat the best
            allowed = [len(ms) if best is None else _pre_allowed(best[0], k)]
            for shared in _inverter_sets(cand, ms, k, allowed):
                # a block with a mismatched term no shared inverter serves gets a pre-summer
                # (a differentiator takes a single input: a pre-summer feeds it fine)
                left = ~shared
                cost = (k + sum(1 for m in ms if m & left), k)
                if best is not None and cost >= best[0]:
                    continue
                pre = {i: m & ~shared for i, m in mism if m & ~shared}
                if fit.fits(pre):
                    best = (cost, pols, shared, pre)
                    allowed[0] = _pre_allowed(cost, k)
    if best is None:  # nothing fits the jacks: keep the cheapest, the emitter names the shortfall
        return search(blocks, kept, None)
    _, pols, shared, pre = best
    names = {b: s for s, b in bit.items()}

    def signals(mask: int) -> set[str]:
        return {names[1 << n] for n in range(mask.bit_length()) if mask >> n & 1}

    P = dict(zip(free, pols))
    P["u_c"] = 1
    return P, signals(shared), {blocks[i].name: signals(m) for i, m in pre.items()}
