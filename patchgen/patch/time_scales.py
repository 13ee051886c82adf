"""Integrator time scales: each integrating block on the slowest of the machine's integrator
modes that carries its coefficients.

A realisation is scaled at the machine's time scale T0, its slowest mode's 1/k0
(patchgen.patch.realization): an integrate block's coefficient c_j means dv/dt = (1/T0) sum c_j
v_j. On a mode integrating at k0 the same block needs c_j / (k0 T0). The slowest mode whose
coefficients each fit one input (the largest weight at the pot's maximum) is chosen: it keeps
every setting largest, so the dial's step and the amplifier's offsets weigh least (a faster mode
shrinks every setting by the ratio of the rates, and drifts faster by it). THE ANALOG THING's
integrators run at 1000 1/s unless SLOW is patched to OUT (10 1/s): a pendulum's controller runs
in real time, so its integrators take SLOW unless a rate needs more. When no mode brings a
coefficient within one input, the fastest is kept: the allocator then splits the coefficient
across inputs or adds a gain stage, or refuses in one line (patchgen.patch.allocation).
"""

from __future__ import annotations

from dataclasses import replace

from patchgen.patch.large_gains import top_gain
from patchgen.patch.realization import Block, Realization, Term
from patchgen.profiles.machine import IntegratorMode, MachineProfile


def assign(real: Realization, machine: MachineProfile) -> Realization:
    """The realisation with every integrate block on a mode (named in ``Block.mode``), its
    coefficients rescaled to that mode's rate; a block already on a mode is kept as it is."""
    blocks = tuple(_on_mode(b, machine) if b.kind == "integrate" and b.mode is None else b for b in real.blocks)
    return replace(real, blocks=blocks)


def mode_for(coefficients: list[float], machine: MachineProfile) -> IntegratorMode:
    """The slowest mode on which every coefficient (at the machine's time scale) fits one input,
    else the fastest."""
    top = top_gain(machine)
    largest = max((abs(c) for c in coefficients), default=0.0)
    modes = machine.modes()
    return next((m for m in modes if largest * _factor(m, machine) <= top + 1e-12), modes[-1])


def _factor(mode: IntegratorMode, machine: MachineProfile) -> float:
    """What a coefficient at the machine's time scale is multiplied by on ``mode``: 1/(k0 T0),
    exactly 1 on the slowest mode (whose time scale T0 is)."""
    if mode.name == machine.modes()[0].name:
        return 1.0
    return 1.0 / (mode.k0_per_s * machine.time_scale_s)


def _on_mode(b: Block, machine: MachineProfile) -> Block:
    mode = mode_for([t.coeff for t in b.terms], machine)
    f = _factor(mode, machine)
    if f == 1.0:  # the slowest mode: the coefficients as realised
        return replace(b, mode=mode.name)
    terms = tuple(Term(t.signal, t.coeff * f, None if t.design is None else t.design * f) for t in b.terms)
    return replace(b, terms=terms, mode=mode.name)
