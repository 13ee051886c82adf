"""Input jacks: the weight a coefficient goes on, and whether a choice of pre-summers leaves every
stage's weighted inputs within the roomiest amplifier of the machine.

Signals are bits of an integer (numbered by the caller), so the polarity search can ask the fit
of many choices cheaply; each block's answer for a staged set is remembered.
"""

from __future__ import annotations

from collections.abc import Callable

from patchgen.patch.realization import Block, Term
from patchgen.profiles.machine import MachineProfile


def weight_for(mag: float, machine: MachineProfile) -> int:
    """The smallest input weight that reaches |c| through a pot (the largest if none does)."""
    ws = sorted(machine.input_weights)
    return next((w for w in ws if mag <= w * machine.pot_max + 1e-12), ws[-1])


class JackFit:
    """Whether the stages fit for a choice of pre-summers given as block index -> staged signal bits."""

    def __init__(self, blocks: list[Block], kept: dict[str, list[Term]], machine: MachineProfile | None,
                 bit: dict[str, int]):
        self.free = machine is None
        if self.free:
            return
        ws = tuple(machine.input_weights)
        self.cap = tuple(max(a.input_count(w) for a in machine.amplifiers) for w in ws)
        self.lowest = ws.index(min(ws))
        self.by_signal: list[dict[int, list[int]]] = []  # per block: signal bit -> its terms' count per weight
        self.total: list[tuple[int, ...]] = []  # per block: its terms' count per weight
        for b in blocks:
            counts: dict[int, list[int]] = {}
            for t in kept[b.name]:
                counts.setdefault(bit[t.signal], [0] * len(ws))[ws.index(weight_for(abs(t.coeff), machine))] += 1
            self.by_signal.append(counts)
            self.total.append(tuple(sum(row[i] for row in counts.values()) for i in range(len(ws))))
        # blocks whose own terms do not fit: each needs a pre-summer taking some of them
        self.crowded = {i for i, tot in enumerate(self.total) if any(n > c for n, c in zip(tot, self.cap))}
        self._staged: dict[tuple[int, int], bool] = {}  # (block, staged bits) -> fits
        self._possible: dict[tuple[int, int], bool] = {}  # (block, mismatched bits) -> fits for some

    def fits(self, pre: dict[int, int]) -> bool:
        """Every stage's inputs fit: blocks without a pre-summer as they are, the others split."""
        if self.free:
            return True
        return self.crowded <= pre.keys() and all(self._staged_fits(i, staged) for i, staged in pre.items())

    def possible(self, i: int, mismatched: int) -> bool:
        """Whether block i fits for some choice of shared inverters among its mismatched signals
        (those not shared go to its pre-summer)."""
        if self.free:
            return True
        key = (i, mismatched)
        if key not in self._possible:
            sub, ok = mismatched, i not in self.crowded
            while sub and not ok:  # every nonempty submask
                ok = self._staged_fits(i, sub)
                sub = (sub - 1) & mismatched
            self._possible[key] = ok
        return self._possible[key]

    def _staged_fits(self, i: int, staged: int) -> bool:
        key = (i, staged)
        if key not in self._staged:
            main, moved = list(self.total[i]), [0] * len(self.cap)
            main[self.lowest] += 1  # the pre-summer's output into its block
            for sig, row in self.by_signal[i].items():
                if staged & sig:
                    for w, n in enumerate(row):
                        main[w] -= n
                        moved[w] += n
            self._staged[key] = all(m <= c and s <= c for m, s, c in zip(main, moved, self.cap))
        return self._staged[key]


def signal_bits(blocks: list[Block], kept: dict[str, list[Term]]) -> dict[str, int]:
    """Each signal a kept term reads, as one bit; numbered in name order, so that ascending bits
    are the sorted signal names."""
    names = sorted({t.signal for b in blocks for t in kept[b.name]})
    return {s: 1 << i for i, s in enumerate(names)}


def jacks_test(blocks: list[Block], kept: dict[str, list[Term]],
               machine: MachineProfile | None) -> Callable[[dict[str, set[str]]], bool]:
    """The fit test on names: block name -> the signals its pre-summer stages."""
    bit = signal_bits(blocks, kept)
    fit = JackFit(blocks, kept, machine, bit)
    index = {b.name: i for i, b in enumerate(blocks)}

    def fits(pre: dict[str, set[str]]) -> bool:
        return fit.fits({index[n]: sum(bit.get(s, 0) for s in set(sigs)) for n, sigs in pre.items()})

    return fits
