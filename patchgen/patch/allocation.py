"""Allocation: put a realization's blocks on the machine's amplifiers and pots, every sign tracked.

Every amplifier inverts. A block's amplifier output is P * (its signal) with a polarity P
chosen here; an input term c_j v_j must then arrive as -P sign(c_j) v_j. A term whose signal
is available only at the other polarity is served either by a shared inverter of that signal
or by one pre-summer per consuming block that collects all its mismatched terms (one that would
carry a single term with a gain above 1 becomes a unit inverter, the gain on the block's input, so
that no partial sum amplifies its source toward the rails). The choice
of polarities and inverters that needs the fewest amplifiers wins (ties: fewer inverters,
then the first in a fixed order; patchgen.patch.polarity), so the result is deterministic.

Coefficient magnitudes go on the smallest input weight w (the profile's, e.g. x1 and x10) with
|c| <= w * pot_max, through a pot set to |c|/w; a coefficient equal to a weight needs no pot; one
above the largest weight is split across inputs or carried by a gain stage
(patchgen.patch.large_gains), an error only when neither fits.

A machine whose coefficients carry their sign (``signed_coefficients``: the LUCIDAC's coefficient
matrix) needs no polarity search: every block is at polarity +1 and an input is marked
``negated`` where its coefficient's sign asks for it, so no inverter or pre-summer is placed.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, replace

from patchgen.inputs.errors import ResourceError
from patchgen.patch import large_gains, polarity, time_scales
from patchgen.patch.jacks import jacks_test, weight_for
from patchgen.patch.netlist import AmpInput, Amplifier, ControlOutput, Mode, Netlist, Pot, SensorInput, Signal
from patchgen.patch.realization import Block, Realization, Term
from patchgen.profiles.machine import MachineProfile, the_machine

ROLE = {"sum": "summer", "integrate": "integrator", "differentiate": "differentiator", "lag": "lag"}
SLOT_ROLE = {"summer": "summer", "inverter": "inverter", "integrator": "integrator",
             "differentiator": "differentiator", "lag": "integrator"}


@dataclass(frozen=True)
class _Stage:
    """An amplifier to be placed: a block, a pre-summer for a block, or an inverter of a signal."""

    key: str  # block name, "pre:<block>" or "inv:<signal>"
    role: str
    terms: tuple[tuple[str, int, float], ...]  # (source key, source polarity needed, |coefficient|)
    out_signal: str
    out_polarity: int
    block: Block | None


_JACKS = "inputs, has"  # what a shortfall of input jacks says (see _emit)

# a coefficient this small beside its block's largest is rounding noise of the design's linear
# algebra (double precision carries about 16 digits; a few products lose a few), not a gain
ROUNDING_NOISE = 1e-12


def _quantise(setting: float, res: float) -> float:
    return round(round(setting / res) * res, 12)


def _plan_terms(real: Realization, machine: MachineProfile):
    """Apply the pot-resolution policy; returns kept terms per block and notes."""
    res, reading = machine.pot_resolution, machine.procedure.pot_reading
    notes: list[str] = []
    too_big: list[tuple[float, str]] = []  # (magnitude, what to say), the largest said first
    kept: dict[str, list[Term]] = {}
    for b in real.blocks:
        kept[b.name] = []
        largest = max((abs(t.coeff) for t in b.terms), default=0.0)
        for t in b.terms:
            mag = abs(t.coeff)
            if mag == 0:
                continue
            if mag <= ROUNDING_NOISE * largest:
                notes.append(f"{t.signal} -> {b.name}: design coefficient {t.coeff:.3g} is rounding noise "
                             f"({mag / largest:.1e} of the block's largest); left out")
                continue
            top = max(machine.input_weights)
            if mag > top * machine.pot_max + 1e-12:
                # .5g: a coefficient just over the top must not print as the top itself
                too_big.append((mag, f"coefficient {t.coeff:.5g} of {t.signal} into {b.name} exceeds {top:g}, the "
                                     f"most one x{top} input gives" + _rate_words(b, t, machine)))
            if mag < res / 2 or (mag < res and real.below_resolution != "round"):
                if real.below_resolution == "minimum":
                    notes.append(f"{t.signal} -> {b.name}: design coefficient {t.coeff:.3g} is below the {reading} "
                                 f"resolution {res:g}; set to the minimum {res:g}, as the thesis did")
                    kept[b.name].append(Term(t.signal, math.copysign(res, t.coeff), t.coeff))
                else:
                    notes.append(f"{t.signal} -> {b.name}: design coefficient {t.coeff:.3g} is below the {reading} "
                                 f"resolution {res:g}; left out")
                continue
            kept[b.name].append(t)
    # drop blocks nobody uses any more (e.g. an integrator whose only term was left out)
    used = {"u_c"}
    changed = True
    while changed:
        changed = False
        for name in sorted(used):
            for t in kept.get(name, []):
                if t.signal not in used and t.signal in kept:
                    used.add(t.signal)
                    changed = True
    blocks = [b for b in real.blocks if b.name in used]
    for b in real.blocks:
        if b.name not in used:
            notes.append(f"{b.name} is not needed once its coefficient is left out: no amplifier for it")
    return blocks, kept, notes, too_big


def allocate(real: Realization, machine: MachineProfile, source: str = "<spec>") -> Netlist:
    """Place the realization on the machine; a shortfall raises ResourceError (one line).

    A coefficient above the largest input weight is split across inputs, else carried by a gain
    stage (patchgen.patch.large_gains); only when neither fits is it the error. Each integrator
    is first put on the slowest mode that carries its coefficients (patchgen.patch.time_scales).
    """
    real = time_scales.assign(real, machine)
    blocks, kept, notes, over = _plan_terms(real, machine)
    too_big = [said for _, said in sorted(over, key=lambda o: -o[0])]
    if not too_big:
        return _place(real, blocks, kept, notes, machine, source)
    big = [t for ts in kept.values() for t in ts if large_gains.too_big(t, machine)]
    jacks = max(sum(a.input_count(w) for w in machine.input_weights) for a in machine.amplifiers)
    top = large_gains.top_gain(machine)
    if any(abs(t.coeff) > top * top and abs(t.coeff) > top * jacks for t in big):
        _check_lower_bound(blocks, kept, machine, source)  # short of amplifiers or pots: say that first
        # beyond every jack of an amplifier and beyond one gain stage: neither can carry it
        raise ResourceError(source, "machine", too_big[0] + f" ({len(too_big)} such coefficients), beyond what "
                            "the inputs of one amplifier or one gain stage reach")
    split = {b: large_gains.split_terms(ts, machine) for b, ts in kept.items()}
    how = [f"{t.signal}: coefficient {t.coeff:.4g} split across {math.ceil(abs(t.coeff) / top)} inputs of the "
           "same amplifier" for t in big]
    try:
        return _place(real, blocks, split, notes + how, machine, source)
    except ResourceError as exc:
        if _JACKS not in exc.message:  # short of amplifiers or pots already: a gain stage only adds to that
            raise
    stages, staged, stage_notes = large_gains.gain_stages(real, kept, machine)
    if any(large_gains.too_big(t, machine) for st in stages for t in st.terms):
        raise ResourceError(source, "machine", too_big[0] + f" ({len(too_big)} such coefficients), beyond what a "
                            "second input or one gain stage reaches")
    try:
        return _place(replace(real, blocks=tuple(stages) + real.blocks), stages + blocks, staged, notes + stage_notes,
                      machine, source)
    except ResourceError:
        raise ResourceError(source, "machine", too_big[0] + f" ({len(too_big)} such coefficients), and neither a "
                            "second input nor a gain stage fits the machine") from None


def _place(real: Realization, blocks: list[Block], kept: dict[str, list[Term]], notes: list[str],
           machine: MachineProfile, source: str) -> Netlist:
    """Polarities, inverters and pre-summers for the blocks' terms, then the amplifiers and pots."""
    _check_lower_bound(blocks, kept, machine, source)
    if machine.signed_coefficients:  # each input carries its sign: every block at +1, no inverters
        P, inverted = {b.name: 1 for b in blocks}, set()
    else:
        P, inverted, pre = polarity.search(blocks, kept, machine)
        inverted = _unit_inverters(blocks, kept, P, inverted, pre, machine)
    stages: list[_Stage] = []
    wanted: dict[tuple[str, str, float], float] = {}
    for b in blocks:
        direct, staged = [], []
        for t in kept[b.name]:
            need = -P[b.name] * (1 if t.coeff > 0 else -1)
            have = P.get(t.signal, 1)
            if have == need or machine.signed_coefficients:
                direct.append((t.signal, have, t.coeff))
            elif t.signal in inverted:
                g = real.inverter_gains.get(t.signal, 1.0)  # a sensor's inverter may amplify it
                wanted[(b.name, t.signal, t.coeff / g)] = t.wanted / g
                direct.append((f"inv:{t.signal}", -have, t.coeff / g))
            else:
                staged.append((t.signal, have, t.coeff))
            wanted[(b.name, t.signal, t.coeff)] = t.wanted
        if staged:
            # pre-summer output = -beta sum |c| (have v) = -P beta sum c v: enters the block 1 / beta times
            # (weight 1, no pot, when beta is 1: patchgen.patch.snr_scaling chooses beta)
            beta = b.partial_scale
            if beta != 1.0:
                for sig, _, c in staged:
                    wanted[(b.name, sig, c * beta)] = wanted[(b.name, sig, c)] * beta
                staged = [(sig, have, c * beta) for sig, have, c in staged]
            stages.append(_Stage(f"pre:{b.name}", "summer", tuple(staged), b.name, -P[b.name], None))
            direct.append((f"pre:{b.name}", None, None if beta == 1.0 else 1.0 / beta))
        stages.append(_Stage(b.name, ROLE[b.kind], tuple(direct), b.name, P[b.name], b))
    for sig in sorted(inverted):
        stages.insert(0, _Stage(f"inv:{sig}", "inverter", ((sig, None, real.inverter_gains.get(sig, 1.0)),), sig,
                                -P.get(sig, 1), None))
    _check_resources(stages, machine, source)
    return _emit(real, machine, stages, P, notes, wanted, source)


def _unit_inverters(blocks: list[Block], kept: dict[str, list[Term]], P: dict[str, int], inverted: set[str],
                    pre: dict[str, set[str]], machine: MachineProfile) -> set[str]:
    """A pre-summer that would carry a single term with a gain above 1 becomes a unit inverter of
    that signal instead (the same amplifier count), with the gain on the block's own input: a
    partial sum must not amplify its source toward the rails (a lag's input, say, scaled by
    T/tau). Kept as a pre-summer when the block's jacks would not take the extra weighted input."""
    out = set(inverted)
    fits = jacks_test(blocks, kept, machine)
    for b, staged in sorted(pre.items()):
        terms = [t for t in kept[b] if t.signal in staged]
        if len(terms) != 1 or abs(terms[0].coeff) <= 1 or terms[0].signal in out:
            continue
        trial = out | {terms[0].signal}
        rest = {n: {s for s in m if s not in trial} for n, m in pre.items()}
        if fits({n: m for n, m in rest.items() if m}):
            out = trial
    return out


def _check_lower_bound(blocks: list[Block], kept: dict[str, list[Term]], machine: MachineProfile,
                       source: str) -> None:
    """Fail fast, before the polarity search, when even one amplifier per block is too many."""
    need_amp = len(blocks)
    need_int = sum(1 for b in blocks if SLOT_ROLE[ROLE[b.kind]] == "integrator")
    need_pot = sum(1 for b in blocks for t in kept[b.name] if _needs_pot(abs(t.coeff), machine))
    have_int = sum(1 for a in machine.amplifiers if "integrator" in a.roles)
    have_amp = len(machine.amplifiers)
    if need_int > have_int or need_amp > have_amp or need_pot > machine.pot_count:
        raise ResourceError(source, "machine",
                            f"the patch needs at least {need_amp} amplifiers ({need_int} integrators) and {need_pot} "
                            f"pots; {the_machine(machine.name)} has {have_amp} amplifiers ({have_int} integrators) and "
                            f"{machine.pot_count} pots")


def _check_resources(stages: list[_Stage], machine: MachineProfile, source: str) -> None:
    need_int = sum(1 for s in stages if SLOT_ROLE[s.role] == "integrator")
    need_amp = len(stages)
    need_pot = sum(1 for s in stages for (_, _, c) in s.terms if c is not None and _needs_pot(abs(c), machine))
    have_int = sum(1 for a in machine.amplifiers if "integrator" in a.roles)
    have_amp = len(machine.amplifiers)
    short = need_int > have_int or need_amp > have_amp or need_pot > machine.pot_count
    if short:
        raise ResourceError(source, "machine",
                            f"the patch needs {need_amp} amplifiers ({need_int} integrators) and {need_pot} pots; "
                            f"{the_machine(machine.name)} has {have_amp} amplifiers ({have_int} integrators) and "
                            f"{machine.pot_count} pots")


def _needs_pot(mag: float, machine: MachineProfile) -> bool:
    return not any(math.isclose(mag, w, rel_tol=1e-12) for w in machine.input_weights)


def _assign_slots(stages: list[_Stage], machine: MachineProfile, source: str) -> dict[str, str]:
    """Most constrained first: integrators and lags on integrator slots, then the rest on slots
    that cannot integrate, keeping integrators free; among those, one whose input jacks take the
    stage's weights (an inverter with a gain needs a x10 input an inverter-only slot may lack)."""
    free = list(machine.amplifiers)
    out: dict[str, str] = {}
    order = sorted(stages, key=lambda s: (0 if SLOT_ROLE[s.role] == "integrator" else
                                          1 if s.role == "differentiator" else 2))
    for st in order:
        want = SLOT_ROLE[st.role]
        fits = [a for a in free if want in a.roles]
        need = Counter(min(machine.input_weights) if c is None else weight_for(abs(c), machine) for _, _, c in st.terms)
        fits.sort(key=lambda a: (any(a.input_count(w) < k for w, k in need.items()),
                                 "integrator" in a.roles and want != "integrator", len(a.roles)))
        if not fits:
            raise ResourceError(source, "machine", f"no free amplifier of {the_machine(machine.name)} can be a "
                                f"{want} for {st.key}")
        out[st.key] = fits[0].id
        free.remove(fits[0])
    return out


def _emit(real: Realization, machine: MachineProfile, stages: list[_Stage], P: dict[str, int],
          notes: list[str], wanted: dict[tuple[str, str, float], float], source: str) -> Netlist:
    slot = _assign_slots(stages, machine, source)
    res = machine.pot_resolution
    sensors = [SensorInput(id=s, label=real.label(s), quantity=s, unit=real.unit(s), volts_per_unit=v)
               for s, v in real.sensors.items()]
    blocks = {b.name: b for b in real.blocks}

    def src_id(key: str) -> str:
        if key in real.sensors:
            return key
        return slot[key]

    amps: list[Amplifier] = []
    pots: list[Pot] = []
    # amplifiers listed in slot order for a stable netlist
    for st in sorted(stages, key=lambda s: [a.id for a in machine.amplifiers].index(slot[s.key])):
        inputs: list[AmpInput] = []
        used = {w: 0 for w in machine.input_weights}
        for (sk, _, c) in st.terms:
            if c is None:  # pre-summer into its block
                w, setting = min(machine.input_weights), None
            else:
                mag = abs(c)
                w = weight_for(mag, machine)
                setting = None if not _needs_pot(mag, machine) else mag / w
            jack = f"x{w}{_jack_letter(used[w])}"
            used[w] += 1
            slot_def = next(a for a in machine.amplifiers if a.id == slot[st.key])
            if used[w] > (have := slot_def.input_count(w)):
                raise ResourceError(source, "machine", f"amplifier {slot[st.key]} ({st.key}) of "
                                    f"{the_machine(machine.name)} needs {used[w]} x{w} inputs, has {have}")
            pot_id = None
            if setting is not None:
                pot_id = _next_pot(pots, slot[st.key], machine)
                q = _quantise(setting, res)
                # realised signed coefficient from the wiring: the stage inverts; its output is
                # out_pol * signal; the source arrives with polarity `have`
                sign_c = 1 if c > 0 else -1
                realized = sign_c * q * w
                design = wanted.get((st.out_signal, sk.split(":")[-1], c), c)
                pots.append(Pot(id=pot_id, setting=q, source=src_id(sk), amplifier=slot[st.key], jack=jack,
                                weight=w, signal=_signal_name(sk, P), coefficient=design, realized=realized,
                                note=_pot_note(design, c, machine.procedure.pot_reading)))
            # on a machine with signed coefficients every block is at +1: an input whose term is
            # positive is negated, so the inverting element gives +c v (summer -(-w k v), integrator too)
            negated = machine.signed_coefficients and c is not None and c > 0
            inputs.append(AmpInput(source=src_id(sk), pot=pot_id, weight=w, jack=jack, negated=negated))
        b = st.block
        quantity = st.out_signal
        if b is not None:
            vpu, unit = b.volts_per_unit, b.unit
        elif st.out_signal in blocks:  # an inverter of a block, or a partial sum (times its partial_scale)
            whole = blocks[st.out_signal]
            part = whole.partial_scale if st.key.startswith("pre:") else 1.0
            vpu, unit = whole.volts_per_unit * part, whole.unit
        else:  # a sensor's inverter, at its gain
            vpu, unit = real.sensors[st.out_signal] * real.inverter_gains.get(st.out_signal, 1.0), real.unit(
                st.out_signal)
        purpose = (b.purpose if b is not None else
                   f"partial sum for {st.out_signal} (terms needing the other sign)" if st.key.startswith("pre:")
                   else f"inverts {st.out_signal}")
        amps.append(Amplifier(id=slot[st.key], role=st.role, inputs=inputs,
                              carries=Signal(quantity=quantity if not st.key.startswith("pre:") else
                                             f"partial {quantity}",
                                             polarity=st.out_polarity, volts_per_unit=vpu, unit=unit),
                              ic_V=None if b is not None and b.settles else
                              0.0 if st.role in ("integrator", "lag") else None,
                              mode=_mode(b, machine) if st.role == "integrator" else None,
                              T_d_s=b.T_d_s if b is not None else None,
                              rolloff_s=b.rolloff_s if b is not None else None,
                              tau_s=b.tau_s if b is not None else None, purpose=purpose))
    ints = [a.id for a in amps if a.role in ("integrator", "lag")]
    operation = machine.procedure.steps("operation", machine=machine.name, units=machine.units, resolution=res,
                                        reference_V=machine.reference_V, integrators=tuple(ints), signs=False,
                                        plant=real.plant)
    return Netlist(design=real.design_name, machine=machine.id, machine_name=machine.name,
                   reference_V=machine.reference_V, time_scale_s=machine.time_scale_s,
                   pot_resolution=res, sensors=sensors, amplifiers=amps, pots=pots,
                   output=ControlOutput(source=slot["u_c"], K_U_N_per_V=real.K_U),
                   operation=operation, notes=list(real.notes) + notes)


def _jack_letter(n: int) -> str:
    """The n-th input jack of a weight: a ... z, then aa, ab ... (a programmed machine's element
    sums as many lanes as it is given)."""
    return chr(97 + n) if n < 26 else chr(96 + n // 26) + chr(97 + n % 26)


def _rate_words(b: Block, t: Term, machine: MachineProfile) -> str:
    """What an integrator's too-large coefficient means: the rate it needs against what the
    machine's fastest integrator mode reaches through one input (time_scales puts such a block there)."""
    if b.kind != "integrate":
        return ""
    m = machine.modes()[-1]
    return (f" (an integrator rate of {abs(t.coeff) * m.k0_per_s:.4g} 1/s; {the_machine(machine.name)}'s fastest mode, "
            f"{m.name}, k0 {m.k0_per_s:g} 1/s, reaches {large_gains.top_gain(machine) * m.k0_per_s:.4g} 1/s)")


def _mode(b: Block | None, machine: MachineProfile) -> Mode:
    """An integrator's mode as the netlist records it (the machine's slowest for a block without one)."""
    modes = machine.modes()
    m = next((m for m in modes if b is not None and m.name == b.mode), modes[0])
    return Mode(name=m.name, k0_per_s=m.k0_per_s, jumper=m.jumper)


def _next_pot(pots: list[Pot], amp_id: str, machine: MachineProfile) -> str:
    """P1, P2, ... on one machine; on slaved units a pot of the amplifier's own unit while it has
    one free (U1.P1 ...), else the first unit with a free pot."""
    if machine.units == 1:
        return f"P{len(pots) + 1}"
    per_unit = machine.pot_count // machine.units
    used = {u: sum(1 for p in pots if p.id.startswith(f"U{u}.")) for u in range(1, machine.units + 1)}
    own = int(amp_id.split(".")[0][1:])
    unit = own if used[own] < per_unit else next(u for u in used if used[u] < per_unit)
    return f"U{unit}.P{used[unit] + 1}"


def _signal_name(key: str, P: dict[str, int]) -> str:
    if key.startswith("inv:"):
        sig = key[4:]
        return f"{'-' if -P.get(sig, 1) < 0 else ''}{sig}"
    if key.startswith("pre:"):
        return f"partial {key[4:]}"
    pol = P.get(key, 1)
    return f"{'-' if pol < 0 else ''}{key}"


def _pot_note(design: float, used: float, reading: str) -> str:
    if design != used:
        return f"design {design:.3g} is below the {reading}: set to the minimum"
    return ""
