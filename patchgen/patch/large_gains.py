"""Coefficients above the largest input weight: carried by more inputs or by a gain stage.

One input gives at most w_max x pot_max (10 on a GP-6). A larger coefficient c of a signal is
carried, in the allocator's order of preference:

1. **split across inputs**: the same signal into the same amplifier on n = ceil(|c| / w_max)
   inputs, n - 1 of them at the full weight without a pot and the rest through a pot. It costs
   input jacks and one pot, and nothing else: no amplifier is added, so no output noise and no
   further point that can overload (the block sums what it summed before).
2. **a gain stage**: one more amplifier, a summer that takes the signal with gain g = |c| / w_max
   (a pot on a weighted input), whose output feeds the block at the full weight without a pot.
   It costs an amplifier and a pot; its output noise reaches the block at w_max times; and its
   output is g times its source, so it leaves the reference when the source passes reference / g:
   the netlist's notes say at what value of the quantity. g is the smallest that carries c.

The allocator tries the split first and the gain stages when the split's inputs do not fit; only
when neither fits is the coefficient the one-line resource error.
"""

from __future__ import annotations

import math

from patchgen.patch.realization import Block, Realization, Term
from patchgen.profiles.machine import MachineProfile

PREFIX = "x"  # a gain stage's block is named for its signal and gain, e.g. theta_x1.42


def top_gain(machine: MachineProfile) -> float:
    """The largest coefficient one input carries: the largest weight through a pot at its maximum."""
    return max(machine.input_weights) * machine.pot_max


def too_big(term: Term, machine: MachineProfile) -> bool:
    """Whether a coefficient exceeds what one input carries."""
    return abs(term.coeff) > top_gain(machine) + 1e-12


def split_terms(terms: list[Term], machine: MachineProfile) -> list[Term]:
    """Each coefficient above the top gain as several terms of the same signal: full-weight ones
    without a pot, then the remainder (which takes a pot). The others unchanged, in order."""
    top = top_gain(machine)
    out: list[Term] = []
    for t in terms:
        if not too_big(t, machine):
            out.append(t)
            continue
        n = math.ceil(abs(t.coeff) / top - 1e-12)
        rest = abs(t.coeff) - (n - 1) * top
        sign = math.copysign(1.0, t.coeff)
        share = [top] * (n - 1) + [rest]
        for k, mag in enumerate(share):
            # the design's value goes with the term that carries the remainder (it takes the pot)
            design = None if t.design is None or k < n - 1 else t.design - sign * (n - 1) * top
            out.append(Term(t.signal, sign * mag, design))
    return out


def gain_stages(real: Realization, kept: dict[str, list[Term]],
                machine: MachineProfile) -> tuple[list[Block], dict[str, list[Term]], list[str]]:
    """Gain stages for every signal some block needs above the top gain: one stage per signal,
    with the gain its largest such coefficient needs; the consumers' terms rescaled onto it.

    Returns
    -------
    (list of Block, dict, list of str)
        The stages (to place before their consumers), the blocks' terms with the stages in, and a
        note per stage saying where its output leaves the reference.
    """
    top = top_gain(machine)
    need: dict[str, float] = {}
    for terms in kept.values():
        for t in terms:
            if too_big(t, machine):
                need[t.signal] = max(need.get(t.signal, 0.0), abs(t.coeff) / top)
    blocks = {b.name: b for b in real.blocks}
    stages, notes = [], []
    for sig, g in sorted(need.items()):
        name = f"{sig}_{PREFIX}{g:.3g}"
        vpu, unit = ((real.sensors[sig], real.unit(sig)) if sig in real.sensors
                     else (blocks[sig].volts_per_unit, blocks[sig].unit))
        stages.append(Block(name, "sum", (Term(sig, g),), vpu * g, unit,
                            f"{sig} times {g:.4g}: a gain stage for a coefficient above {top:g}"))
        ref = machine.reference_V
        notes.append(f"{name}: a gain stage of {g:.4g} on {sig}; it leaves +/-{ref:g} V when {sig} passes "
                     f"{ref / g:.3g} V ({ref / g / vpu:.3g} {unit}), before {sig} itself does")
    out = {}
    for b, terms in kept.items():
        new = []
        for t in terms:
            if too_big(t, machine):
                g = need[t.signal]
                stage = f"{t.signal}_{PREFIX}{g:.3g}"
                new.append(Term(stage, t.coeff / g, None if t.design is None else t.design / g))
            else:
                new.append(t)
        out[b] = new
    for s in stages:
        out[s.name] = list(s.terms)
    return stages, out, notes
