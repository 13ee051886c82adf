"""A filtered differentiator from an integrator, for a machine with no differentiator element.

A differentiate block (rolloff s + 1) r = T_d s x is the same law as

    r = (T_d / rolloff) (x - z),   rolloff z' = x - z

with z a lag of x (time constant rolloff): x minus its lag, amplified. The difference d = x - z is
the rate at a smaller scale, r / G with G = T_d / rolloff, so the block keeps its name and its
signal, carried at volts_per_unit / G, and every consumer takes it with G times its coefficient.
The lag closes through the difference: z' = d / rolloff, one integrator and no feedback of its own.

A sensor x that feeds the difference is taken by its other consumers as d + z (which is x), so
the sensor reaches the machine once, at unit coefficient: a programmed machine's front-panel input
enters one element with no coefficient of its own (the LUCIDAC: lucipy Routing.front_input).

A raw differentiator (no roll-off) is given the machine's ``differentiator_rolloff_s``, the roll-off
a patched differentiator has on the bench simulator too; the netlist's notes say so.
"""

from __future__ import annotations

from dataclasses import replace

from patchgen.patch.realization import Block, Realization, Term
from patchgen.profiles.machine import MachineProfile


def has_differentiator(machine: MachineProfile) -> bool:
    """True when some amplifier of the machine can be patched as a differentiator."""
    return any("differentiator" in a.roles for a in machine.amplifiers)


def without_differentiators(real: Realization, machine: MachineProfile) -> Realization:
    """The realisation with every differentiate block built from a lag, on a machine without the
    role; unchanged (the same object) on a machine that has it or when there is none."""
    diffs = [b for b in real.blocks if b.kind == "differentiate"]
    if has_differentiator(machine) or not diffs:
        return real
    T = machine.time_scale_s
    blocks = list(real.blocks)
    notes = list(real.notes)
    for r in diffs:
        roll = r.rolloff_s or machine.imperfections.differentiator_rolloff_s
        if not r.rolloff_s:
            notes.append(f"{r.name}: {machine.name} has no differentiator; the raw differentiator is given the "
                         f"profile's roll-off {roll:g} s (differentiator_rolloff_s)")
        gain = r.T_d_s / roll
        lag = f"{r.name}_lag"
        src = r.terms[0].signal
        vpu = real.sensors[src] if src in real.sensors else real.block(src).volts_per_unit
        z = Block(lag, "integrate", (Term(r.name, T / roll),), vpu, real.unit(src) if src in real.sensors else r.unit,
                  f"lag of {src} ({roll:g} s) for {r.name}: z' = ({src} - z) / rolloff", settles=True)
        d = Block(r.name, "sum", r.terms + (Term(lag, -1.0),), r.volts_per_unit / gain, r.unit,
                  f"{r.purpose}; no differentiator element: {src} minus its lag, the rate / {gain:.4g}")
        notes.append(f"{r.name}: {src} minus its lag of {roll:g} s (an integrator) carries the rate at 1/{gain:.4g} "
                     f"of its scale; its consumers take it {gain:.4g} times")
        single = len(r.terms) == 1 and r.terms[0].coeff == 1.0 and src in real.sensors
        i = blocks.index(r)
        blocks[i:i + 1] = [z, d]
        blocks = [b if b.name in (lag, r.name) else _rewired(b, r.name, gain, src if single else None, lag)
                  for b in blocks]
    return replace(real, blocks=tuple(blocks), notes=tuple(notes))


def _rewired(b: Block, rate: str, gain: float, sensor: str | None, lag: str) -> Block:
    """A consumer of the rate takes the difference ``gain`` times; a consumer of the sensor takes it
    as difference plus lag. Terms of one signal are merged, in the order they first appear."""
    out: dict[str, list[float | None]] = {}
    for t in b.terms:
        if t.signal == rate:
            parts = [(rate, t.coeff * gain, None if t.design is None else t.design * gain)]
        elif t.signal == sensor:
            parts = [(rate, t.coeff, t.design), (lag, t.coeff, t.design)]
        else:
            parts = [(t.signal, t.coeff, t.design)]
        for sig, c, des in parts:
            acc = out.setdefault(sig, [0.0, None])
            acc[0] += c
            if des is not None:
                acc[1] = (acc[1] or 0.0) + des
    if all(t.signal not in (rate, sensor) for t in b.terms):
        return b
    return replace(b, terms=tuple(Term(s, c, d) for s, (c, d) in out.items()))
