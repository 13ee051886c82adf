"""Scaling for signal-to-noise: each internal signal's voltage chosen so that the signals use as
much of the machine's range as the bench lets them.

A signal scaled by sensor constants alone may live at a few per cent of the reference, where the
machine's amplifier noise, integrator offsets and the dial's step weigh many times more than they
would at full scale (bench-recommended's actuator-state integrator peaks at 5 % of the rails over
two minutes of balancing). Every signal a block produces can be carried at any voltage scale: a
block whose voltage is multiplied by alpha has its input coefficients multiplied by alpha (a
differentiator its T_d), and every coefficient that reads it divided by alpha, so the law is
unchanged. The sensors (the bench's) and u_c (the servo amplifier's input) keep theirs.

The choice, as in the analog-compilation literature (Achour et al., Jaunt, ASPLOS 2018; Legno,
ASPLOS 2020), is an optimisation, here a pair of linear programmes in y = ln alpha (exact, HiGHS):

1. maximise the smallest predicted peak of a free block's amplifiers, as a share of the reference
   (the worst signal-to-noise and signal-to-offset ratio: the noise and offsets are the same on
   every amplifier of a machine);
2. with that held, maximise the sum of ln alpha (every other signal as large as it may be);

a partial sum (a pre-summer of a block's terms of the other sign) and a sensor's inverter, stages
the allocation adds, have scales of their own too, each costing a pot where it was wired straight:
they move where the worst signal (stage 1) or an overload needs it, stage 2 prices them
(STAGE_COST), and one within HEADROOM that would gain less than STAGE_WORTH keeps its scale, as
does a block that would gain less than SCALE_WORTH;

subject to

- no amplifier's predicted peak (the bench Monte Carlo's envelope, supplied by the caller) past
  HEADROOM of the reference; a block already past it is brought down towards it as far as its
  coefficients allow (and left out of the first programme);
- no coefficient past the largest weighted input (a gain stage or another input would be needed)
  unless it was already, and then no larger than it was;
- no coefficient below the dial floor (a setting whose dial step is more than DIAL_SHARE of
  itself) unless it was already, and then no smaller than it was (the signal-to-quantisation
  ratio of the law is never made worse than the dial allows);
- a coefficient wired straight (exactly an input weight, no pot) stays exactly that (on a
  programmed machine every coefficient is a setting, but a sensor's unit coefficient into its one
  consumer: a front-panel input has no coefficient of its own);
- no block scaled down unless its peak is past HEADROOM.

Every scale 1 is feasible (the limits are relative to the coefficients as they are), so both
programmes always have a solution.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from patchgen.patch.large_gains import PREFIX
from patchgen.patch.realization import Realization, Term
from patchgen.profiles.machine import MachineProfile

HEADROOM = 0.8  # the largest share of the reference a predicted peak may reach: room for runs the envelope missed
DIAL_SHARE = 0.01  # a pot whose dial step is more than this share of its setting limits the law it sets
FIXED = ("u_c",)  # blocks whose scale the bench fixes (the servo amplifier's input, 1 V per V)
PARTIAL = "partial "  # a block's partial sum, as the netlist names what its pre-summer carries
INVERTED = "inverted "  # a sensor's inverter (the netlist: an inverter carrying the sensor's quantity)
STAGE_COST = 1e-3  # stage 2's price of scaling a partial sum or an inverter (a pot more): only where the worst
# signal (stage 1) or an overload needs it
STAGE_WORTH = 2.0  # a stage within HEADROOM is scaled only if that raises it this much (6 dB): else not worth a pot
SCALE_WORTH = 1.25  # a block within HEADROOM is scaled only if that raises it this much (2 dB): else not worth
# re-dialling its pots, and moving the law's own errors (thesis-case2's compensator on the GP-6, every block
# 1.15 times: the op-amps' finite gain then moves the loop 1.07 % from the ideal, against 0.86 %)
INSIDE = 1e-6  # relative: every limit is kept this far inside, so a coefficient at a limit stays within it
STAGE_ONE_SLACK = 1e-9  # relative: stage 2 keeps stage 1's optimum to this (the solver's tolerance)


@dataclass(frozen=True)
class Scaling:
    """The factor each block's voltage is multiplied by (1: kept) and, for each block scaled,
    the limit that stopped it (in words, for the netlist's notes)."""

    factors: dict[str, float]
    why: dict[str, str]

    @property
    def changes(self) -> bool:
        """Whether any block's scale moved."""
        return any(f != 1.0 for f in self.factors.values())

    def notes(self) -> list[str]:
        """One line per block scaled: its factor and the limit it reached."""
        return [f"{_named(b)} carried at {f:.3g} times its sensor-constant scale for signal-to-noise: {self.why[b]}"
                for b, f in self.factors.items() if f != 1.0]


def _named(name: str) -> str:
    """A scaled signal as a note names it: a block, a block's partial sum, or a sensor's inverter."""
    if name.startswith(PARTIAL):
        return f"{name} (the sum of {name.removeprefix(PARTIAL)}'s terms of the other sign)"
    if name.startswith(INVERTED):
        return f"the inverter of {name.removeprefix(INVERTED)}"
    return name


@dataclass(frozen=True)
class BlockPeak:
    """The predicted largest |output| (V) of the amplifiers that carry one block's signal: the
    least of them (what its worst signal-to-noise ratio is) and the most (what may overload)."""

    least: float
    most: float


def dial_floor(machine: MachineProfile) -> float:
    """The smallest coefficient whose dial step is at most DIAL_SHARE of its setting (on a x1 input)."""
    return machine.pot_resolution / DIAL_SHARE


def dial_limits(setting: float, resolution: float) -> bool:
    """Whether a pot's dial step is more than DIAL_SHARE of its setting: the dial, not the design,
    then sets its coefficient to that precision (a setting of 0 is a term left out)."""
    return 0.0 < setting and resolution > DIAL_SHARE * setting


def snr_scales(real: Realization, peaks: Mapping[str, BlockPeak], machine: MachineProfile,
               partials: Mapping[str, frozenset[str]] | None = None,
               inverters: Mapping[str, frozenset[str]] | None = None,
               kept: frozenset[str] | set[str] = frozenset()) -> Scaling:
    """The factor each block's voltage is multiplied by (1: kept), see the module docstring.

    Parameters
    ----------
    real : Realization
        The law scaled by the sensor constants (patchgen.patch.realization.realize).
    peaks : mapping of str to BlockPeak
        Each block's predicted amplifier peaks (V) at its present scale; a block not given, or
        with a zero peak, keeps its scale (nothing predicts how large it gets).
    machine : MachineProfile
        Its reference, largest weighted input, input weights and dial step.
    partials : mapping of str to frozenset of str, optional
        For a block whose terms of the other sign a partial sum (a pre-summer) takes, the signals it
        takes; with its peak in ``peaks`` as "partial <block>", the partial sum gets a scale of its
        own (the block takes it at the inverse, on a pot): "partial <block>" in the factors.
    inverters : mapping of str to frozenset of str, optional
        For a sensor the allocation inverts, the blocks that take it through its inverter; with
        the inverter's peak in ``peaks`` as "inverted <sensor>", the inverter gets a gain of its own
        (its consumers take it at the inverse): "inverted <sensor>" in the factors.
    kept : set of str, optional
        Blocks kept at their scale (what a scaling that gained them too little leaves).

    Returns
    -------
    Scaling
        Block name (and "partial <block>", "inverted <sensor>") -> factor for every block the
        realisation has and every stage given a scale, and why each scaled one stopped.
    """
    from scipy.optimize import linprog  # 0.1 s of import, only where a scaling is chosen

    ref = machine.reference_V
    partials = {b: s for b, s in (partials or {}).items()
                if any(x.name == b for x in real.blocks) and peaks.get(PARTIAL + b, BlockPeak(0, 0)).least > 0}
    peaks = _partials_joined(peaks, partials)
    inverters = {s: b for s, b in (inverters or {}).items()
                 if s in real.sensors and peaks.get(INVERTED + s, BlockPeak(0, 0)).least > 0}
    free = [b.name for b in real.blocks
            if b.name not in FIXED and b.name not in kept and peaks.get(b.name, BlockPeak(0, 0)).least > 0]
    free += [PARTIAL + b for b in partials]  # a partial sum's own scale (its voltage over the sensor constants')
    free += [INVERTED + s for s in inverters]  # a sensor's inverter's gain
    out = {b.name: 1.0 for b in real.blocks} | {x: 1.0 for x in free}
    if not free:
        return Scaling(out, {})
    col = {name: i for i, name in enumerate(free)}
    n = len(free)  # variables: y_b for each free block and partial sum, then t
    rows, rhs, eq_rows, eq_rhs = [], [], [], []
    bounds = []

    def row(coef: dict[int, float]) -> np.ndarray:
        r = np.zeros(n + 1)
        for i, v in coef.items():
            r[i] += v
        return r

    gain = np.zeros(n + 1)  # stage 2's objective: up for a block within HEADROOM, down for one past it
    for name in free:
        p = peaks[name]
        top = math.log(HEADROOM * ref / p.most) + math.log1p(-INSIDE)
        if p.most <= HEADROOM * ref:
            bounds.append((0.0, max(0.0, top)))
            rows.append(row({col[name]: -1.0, n: 1.0}))  # t <= ln(least / ref) + y_b
            rhs.append(math.log(p.least / ref))
            gain[col[name]] = -STAGE_COST if name.startswith((PARTIAL, INVERTED)) else 1.0
        else:  # past HEADROOM already: down towards it as far as its coefficients allow, never up
            bounds.append((top, 0.0))
            gain[col[name]] = -1.0
    bounds.append((None, None))
    top_c, floor, weights = max(machine.input_weights) * machine.pot_max, dial_floor(machine), machine.input_weights
    consumers = _consumers(real)
    for taker, term in _coefficients(real, partials, inverters):
        c = abs(term.coeff)
        coef = {}
        if taker in col:
            coef[col[taker]] = 1.0
        if term.signal in col:
            coef[col[term.signal]] = coef.get(col[term.signal], 0.0) - 1.0
        coef = {i: v for i, v in coef.items() if v != 0.0}
        if c == 0.0 or not coef:
            continue
        if not _staged(taker, term) and _straight(term, c, weights, machine, consumers):
            eq_rows.append(row(coef))  # wired straight: stays a weight exactly
            eq_rhs.append(0.0)
            continue
        rows.append(row(coef))  # ln c + d <= ln max(top, c)
        rhs.append(max(0.0, math.log(top_c / c) + math.log1p(-INSIDE)) if c < top_c else 0.0)
        rows.append(-row(coef))  # ln c + d >= ln min(c, floor)
        rhs.append(-math.log(floor / c) if c > floor else 0.0)
    A, b_ub = np.array(rows), np.array(rhs)
    A_eq, b_eq = (np.array(eq_rows), np.array(eq_rhs)) if eq_rows else (None, None)
    if not gain[:n].any():
        return Scaling(out, {})
    if np.any(A[:, n] > 0):  # stage 1 (a signal within HEADROOM to raise): the worst share of the reference
        first = linprog(-row({n: 1.0}), A_ub=A, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")
        t_star = first.x[n]
        A = np.vstack([A, -row({n: 1.0})])
        b_ub = np.append(b_ub, -(t_star - STAGE_ONE_SLACK * max(1.0, abs(t_star))))
    second = linprog(-gain, A_ub=A if len(A) else None, b_ub=b_ub if len(A) else None, A_eq=A_eq, b_eq=b_eq,
                     bounds=bounds, method="highs")
    y = second.x[:n]
    for name, v in zip(free, y):
        out[name] = math.exp(v)
    small = {x for x in free if 1.0 < out[x] < (STAGE_WORTH if x.startswith((PARTIAL, INVERTED)) else SCALE_WORTH)
             and peaks[x].most <= HEADROOM * ref}
    if small:  # not worth re-dialling (or a pot more): those stay as they were, and the others are chosen again
        return snr_scales(real, peaks, machine, {b: s for b, s in partials.items() if PARTIAL + b not in small},
                          {s: b for s, b in inverters.items() if INVERTED + s not in small}, kept | small)
    return Scaling(out, {b: _why(b, real, partials, inverters, out, peaks, machine) for b in free if out[b] != 1.0})


def _partials_joined(peaks: Mapping[str, BlockPeak], partials: Mapping[str, frozenset[str]]) -> dict[str, BlockPeak]:
    """The peaks with each partial sum that keeps its block's scale (not among ``partials``) counted
    among its block's amplifiers: it moves with the block."""
    out = dict(peaks)
    for key, p in peaks.items():
        b = key.removeprefix(PARTIAL)
        if key.startswith(PARTIAL) and b not in partials and b in out:
            out[b] = BlockPeak(out[b].least, max(out[b].most, p.most))
    return out


def _coefficients(real: Realization, partials: Mapping[str, frozenset[str]],
                  inverters: Mapping[str, frozenset[str]]) -> list[tuple[str, Term]]:
    """Every coefficient a scaling moves, as (who takes it, the term): a block's own terms (those
    its partial sum takes are the partial sum's; a sensor it takes through an inverter, the
    inverter's), each block's entry of its partial sum (at 1), and each sensor's inverter's input
    (at 1). A differentiator's are not: its input is a sensor and its scale is its T_d, an external part."""
    out = []
    for b in real.blocks:
        if b.kind == "differentiate":
            continue
        for t in b.terms:
            taker = PARTIAL + b.name if t.signal in partials.get(b.name, ()) else b.name
            through = taker == b.name and b.name in inverters.get(t.signal, ())
            out.append((taker, replace(t, signal=INVERTED + t.signal) if through else t))
        if b.name in partials:
            out.append((b.name, Term(PARTIAL + b.name, 1.0)))
    out += [(INVERTED + s, Term(s, 1.0)) for s in inverters]
    return out


def _staged(taker: str, term: Term) -> bool:
    """Whether a coefficient enters or leaves a stage the allocation adds (a partial sum, an
    inverter): wired straight at 1 when unscaled, it takes a pot when scaled."""
    return term.signal.startswith(PARTIAL) or taker.startswith(INVERTED)


def _consumers(real: Realization) -> dict[str, int]:
    """How many blocks take each sensor."""
    out: dict[str, int] = {}
    for b in real.blocks:
        for sig in {t.signal for t in b.terms} & set(real.sensors):
            out[sig] = out.get(sig, 0) + 1
    return out


def _straight(term: Term, c: float, weights: tuple[float, ...] | list[float], machine: MachineProfile,
              consumers: Mapping[str, int]) -> bool:
    """Whether a coefficient of magnitude ``c`` is wired straight, and so must stay exactly what it is.

    On a patched machine, any coefficient that is an input weight (no pot). On a programmed one
    every coefficient is a setting, except a sensor's unit coefficient into its one consumer: a
    front-panel input enters that element with no coefficient of its own (patchgen.lucidac.plan).
    """
    if not any(math.isclose(c, w, rel_tol=1e-12) for w in weights):
        return False
    if not machine.programmed:
        return True
    return consumers.get(term.signal, 0) == 1 and math.isclose(c, 1.0, rel_tol=1e-12)


def _why(name: str, real: Realization, partials: Mapping[str, frozenset[str]],
         inverters: Mapping[str, frozenset[str]], factors: dict[str, float], peaks: Mapping[str, BlockPeak],
         machine: MachineProfile) -> str:
    """The limits block ``name`` reached at its factor, in words."""
    tight = 1e-5
    said = []
    if factors[name] * peaks[name].most >= HEADROOM * machine.reference_V * (1 - tight):
        said.append(f"its predicted peak at {100 * HEADROOM:g} % of the reference")
    top_c, floor = max(machine.input_weights) * machine.pot_max, dial_floor(machine)
    for taker, t in _coefficients(real, partials, inverters):
        if name not in (taker, t.signal) or taker == t.signal or t.coeff == 0.0:
            continue
        c = abs(t.coeff) * factors.get(taker, 1.0) / factors.get(t.signal, 1.0)
        where = f"{taker}'s coefficient on {t.signal}"
        if abs(t.coeff) < top_c and c >= top_c * (1 - tight):
            said.append(f"{where} at the largest weighted input ({top_c:g})")
        elif abs(t.coeff) > floor and c <= floor * (1 + tight):
            said.append(f"{where} at the dial floor ({floor:g})")
    return "; ".join(said) or "with the least scaled signal's share of the reference"


def block_of(quantity: str) -> str:
    """The block an amplifier's signal belongs to: its own, its partial sum's or its gain stage's
    (a gain stage scales with the signal it amplifies)."""
    q = quantity.removeprefix("partial ")
    head, sep, tail = q.rpartition(f"_{PREFIX}")
    return head if sep and tail.replace(".", "", 1).isdigit() else q


def block_peaks(real: Realization, amplifiers: Mapping[str, str], peaks_V: Mapping[str, float]) -> dict[str, BlockPeak]:
    """Each block's BlockPeak from its amplifiers' predicted peaks (``amplifiers``: id -> the
    quantity it carries, as the netlist says; ``peaks_V``: id -> V); a block's partial sum's as
    "partial <block>", a sensor's inverter's (the one amplifier that carries a sensor) as
    "inverted <sensor>": each has a scale of its own."""
    names = {b.name for b in real.blocks}
    got: dict[str, list[float]] = {}
    for a, quantity in amplifiers.items():
        b = block_of(quantity)
        if a not in peaks_V:
            continue
        if b in names:
            got.setdefault(PARTIAL + b if quantity.startswith(PARTIAL) else b, []).append(peaks_V[a])
        elif quantity in real.sensors:
            got.setdefault(INVERTED + quantity, []).append(peaks_V[a])
    return {b: BlockPeak(min(v), max(v)) for b, v in got.items()}


def rescaled(real: Realization, scales: Mapping[str, float]) -> Realization:
    """The realisation with each block's voltage multiplied by its factor (the law unchanged):
    its input coefficients times its factor (a differentiator's T_d instead), every coefficient
    on it divided by it; a block's partial sum's ("partial <block>") sets its partial_scale, a
    sensor's inverter's ("inverted <sensor>") its gain."""
    def alpha(signal: str) -> float:
        return scales.get(signal, 1.0)

    def term(t: Term, own: float) -> Term:
        k = own / alpha(t.signal)
        return Term(t.signal, t.coeff * k, None if t.design is None else t.design * k)

    blocks = []
    for b in real.blocks:
        a = alpha(b.name)
        if b.kind == "differentiate":
            blocks.append(replace(b, terms=tuple(term(t, 1.0) for t in b.terms), volts_per_unit=b.volts_per_unit * a,
                                  T_d_s=None if b.T_d_s is None else b.T_d_s * a))
        else:
            blocks.append(replace(b, terms=tuple(term(t, a) for t in b.terms), volts_per_unit=b.volts_per_unit * a,
                                  partial_scale=b.partial_scale * scales.get(PARTIAL + b.name, a) / a))
    gains = {s: real.inverter_gains.get(s, 1.0) * scales[INVERTED + s] for s in real.sensors if INVERTED + s in scales}
    return replace(real, blocks=tuple(blocks), inverter_gains={**real.inverter_gains, **gains})


