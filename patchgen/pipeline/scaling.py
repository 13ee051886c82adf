"""The patch every command patches, simulates and checks: the spec's law scaled into volts by its
sensor constants (the law as its states, or a compensator's realisation with its states at half
the reference over the design's excursions), then (``[patch] scaling = "snr"``, the default) each
internal signal raised as far as the bench lets it (patchgen.patch.snr_scaling).

How far a signal may go is what the bench Monte Carlo of the standard scenarios shows it reaching
at those scales (the envelope): the runs the sheet's prediction makes
(patchgen.bench.prediction.standard_runs), with ENVELOPE_RUNS seeds of the long hold whatever a
command's own run count, so that every command builds the same patch from the same spec, machine
and bench; taken with no rails when an amplifier clipped (a clip holds the others back). The
scaling is linear, so a signal's peak moves with its scale; the scaled patch is simulated on the
bench and kept only if its signals stay inside the reference and it is held as often (else
ROUNDS tries nearer the sensor constants), and those runs stand in for the prediction's.
"""

from __future__ import annotations

import importlib
import threading
from collections.abc import Callable
from dataclasses import dataclass

from patchgen.design.lqg import Design
from patchgen.inputs.errors import InputError
from patchgen.patch.build import build_patch, placed, scaled_placed
from patchgen.patch.netlist import Netlist
from patchgen.patch.snr_scaling import FIXED, HEADROOM, INVERTED, PARTIAL, BlockPeak, Scaling, block_peaks, snr_scales
from patchgen.patch.static_check import spare_pots
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

ENVELOPE_RUNS = 8  # seeds of the long hold in the envelope (one run of the others): HEADROOM covers the rest
ROUNDS = 3  # scalings tried: the programme's, then half of it and a quarter (ln), until the bench agrees
CHECK_RUNS = 1  # seeds of the long hold a scaled patch is checked on (one run of the others: a clip or a fall
# shows in the transients; the prediction runs the rest)

Runs = dict  # scenario name -> list of patchgen.bench.results.RunSummary


@dataclass(frozen=True)
class ScaledPatch:
    """The patch, its scaling (None: kept at the sensor constants), and the envelope's runs when
    they are runs of this very patch (its scales kept: they stand in for the prediction's)."""

    netlist: Netlist
    scaling: Scaling | None
    runs: Runs | None


def wants_scaling(d: Design) -> bool:
    """Whether the spec asks for signal-to-noise scaling (the law as its states, or as one
    compensator: its realisation's states and sums)."""
    return d.spec.patch.scaling == "snr"


def envelope_runs(d: Design, net: Netlist, machine: MachineProfile, bench: BenchProfile, rails: bool = True,
                  hold: int = ENVELOPE_RUNS) -> Runs:
    """The standard scenarios' runs the envelope is taken over, ``hold`` seeds of the long hold
    (the simulator, loaded here); with ``rails`` False, no amplifier clips."""
    from patchgen.bench.prediction import standard_runs

    return standard_runs(net, d.plant, bench, machine, hold, bench_spread=bool(bench.uncertainty.ranges),
                         rails=rails)


def scaled_patch(d: Design, machine: MachineProfile, bench: BenchProfile, net: Netlist | None = None,
                 runs_of: Callable[[Netlist], Runs] | None = None) -> ScaledPatch:
    """The spec's patch, scaled for signal-to-noise when it asks (see the module docstring).

    Parameters
    ----------
    d : Design
        The design.
    machine, bench : MachineProfile, BenchProfile
        The machine it is patched on and the bench the envelope is simulated on.
    net : Netlist, optional
        The patch at its sensor constants, when already built (``build_patch(d, machine)``).
    runs_of : callable, optional
        The envelope's runs of a patch (default: :func:`envelope_runs` here); a caller with a
        worker, or runs already made, gives its own.

    Returns
    -------
    ScaledPatch
    """
    if not wants_scaling(d):
        return ScaledPatch(build_patch(d, machine) if net is None else net, None, None)
    given = net
    net, real = placed(d, machine)  # the realisation placed: the law's blocks, or the compensator's chosen
    net = net if given is None else given
    run = runs_of if runs_of is not None else (lambda n, rails=True, hold=ENVELOPE_RUNS: envelope_runs(
        d, n, machine, bench, rails, hold))
    loading = threading.Thread(target=importlib.import_module, args=("scipy.optimize",), daemon=True)
    loading.start()  # the programme's solver loads while the envelope's runs are made (0.1 s)
    runs = run(net)
    loading.join()
    peaks = _peaks(runs)
    if not peaks:  # a pendulum that falls or runs to the switches: its signals are no envelope
        note = ("not scaled for signal-to-noise: no run on the bench held the pendulum, whose signals would be "
                "the envelope")
        return ScaledPatch(net.model_copy(update={"notes": [*net.notes, note]}), None, runs)
    on_bench = block_peaks(real, _quantities(net), peaks)
    # an amplifier clipped at its rails holds the others back, so their peaks say less than the
    # linear circuit's, which a scaling moves: the envelope is then the patch's with no rails
    clipped = any(v > machine.imperfections.saturation_V for v in peaks.values())
    linear = not clipped and all(r.held for rs in runs.values() for r in rs)
    if clipped and not (own := snr_scales(real, on_bench, machine, partial_sums(net), sensor_inverters(net))).changes:
        return ScaledPatch(net, own, runs)  # nothing moves on the bench's own peaks: nor with no rails, higher
    base = block_peaks(real, _quantities(net), _peaks(run(net, rails=False)) or peaks) if clipped else on_bench
    why_not = ""
    # a partial sum or an inverter scaled takes a pot more: without them if it does not fit, or if it
    # would take the last spare pot (the checks' test voltages come from one) to no overload's cure
    for parts, inverters in ((partial_sums(net), sensor_inverters(net)), (None, None)):
        chosen = snr_scales(real, base, machine, parts, inverters)
        if not chosen.changes:
            said = [f"not scaled for signal-to-noise: {why_not}"] if why_not else []
            return ScaledPatch(net.model_copy(update={"notes": [*net.notes, *said]}), chosen, runs)
        for k in range(ROUNDS):  # the programme's scales, then (ln) half of them, a quarter
            scaling = chosen if k == 0 else _backed_off(chosen, 0.5 ** k)
            try:
                scaled = scaled_placed(d, machine, net, real, scaling.factors)
            except InputError as exc:  # the scaled law needs what the machine lacks
                why_not = why_not or f"scaled, the patch does not fit ({exc.message})"
                break
            staged = [x for x, f in scaling.factors.items() if f != 1.0 and x.startswith((PARTIAL, INVERTED))]
            cures = any(base[x].most > HEADROOM * machine.reference_V for x in staged)
            if staged and not cures and spare_pots(net, machine) and not spare_pots(scaled, machine):
                why_not = "scaled, they would take the last spare pot, which the checks' test voltages come from"
                break
            if linear:  # no clip and no fall: the scaled circuit is the same circuit, its signals scaled
                return _kept(scaled, scaling, why_not, None)
            got = run(scaled, hold=CHECK_RUNS)
            reached = block_peaks(real, _quantities(scaled), _peaks(got))
            before = _held({name: rs[:CHECK_RUNS] for name, rs in runs.items()})
            if _within(reached, on_bench, machine) and all(_held(got).get(s, 0.0) >= v for s, v in before.items()):
                return _kept(scaled, scaling, why_not, got)
        else:
            why_not = why_not or (f"scaled, even to {0.5 ** (ROUNDS - 1):g} of its factors (ln), the patch passed "
                                  f"the reference or was held less often on the bench")
    note = f"not scaled for signal-to-noise: {why_not}"  # keep the sensor constants
    return ScaledPatch(net.model_copy(update={"notes": [*net.notes, note]}), None, runs)


def _kept(scaled: Netlist, scaling: Scaling, why_not: str, runs: Runs | None) -> ScaledPatch:
    """The scaled patch, its notes saying each signal's scale and why a stage kept its own."""
    notes = [*scaled.notes, *scaling.notes()]
    if why_not:
        notes.append(f"its partial sums and sensor inverters keep their scale: {why_not}")
    return ScaledPatch(scaled.model_copy(update={"notes": notes}), scaling, runs)


def _backed_off(chosen: Scaling, share: float) -> Scaling:
    """The programme's scaling taken ``share`` of the way (in ln): the bench held the full one less
    often, or one of its signals passed the reference (a nonlinearity the envelope could not see)."""
    factors = {x: f ** share for x, f in chosen.factors.items()}
    said = f"{share:g} of the way (ln) to the scale where {{}}: the full scale was held less often on the bench"
    return Scaling(factors, {x: said.format(w) for x, w in chosen.why.items()})


def _quantities(net: Netlist) -> dict[str, str]:
    return {a.id: a.carries.quantity for a in net.amplifiers}


def _peaks(runs: Runs) -> dict[str, float]:
    """Each amplifier's largest |output| over every run that held the pendulum (V): a run that
    falls, or runs to the switches, swings its signals as no patch is scaled for."""
    peaks: dict[str, float] = {}
    for rs in runs.values():
        for r in rs:
            if not r.held:
                continue
            for a, v in r.amp_peaks_V:
                peaks[a] = max(peaks.get(a, 0.0), v)
    return peaks


def _held(runs: Runs) -> dict[str, float]:
    """The fraction of runs held, by scenario."""
    return {k: sum(r.held for r in rs) / len(rs) for k, rs in runs.items() if rs}


def _within(reached: dict[str, BlockPeak], base: dict[str, BlockPeak], machine: MachineProfile) -> bool:
    """Whether every signal of the scaled patch stays inside the reference, or no further past it
    than at the sensor constants (u_c, which the bench fixes, aside: what it asks is the design's)."""
    return all(p.most <= max(machine.reference_V, base[k].most if k in base else 0.0) * (1 + 1e-9)
               for k, p in reached.items() if k not in FIXED)


def sensor_inverters(net: Netlist) -> dict[str, frozenset[str]]:
    """For each sensor the patch inverts, the blocks that take it through its inverter."""
    sensors = {s.id for s in net.sensors}
    inv = {a.id: a.inputs[0].source for a in net.amplifiers
           if a.role == "inverter" and len(a.inputs) == 1 and a.inputs[0].source in sensors}
    out: dict[str, set[str]] = {}
    for a in net.amplifiers:
        for i in a.inputs:
            if i.source in inv:
                out.setdefault(inv[i.source], set()).add(a.carries.quantity)
    return {s: frozenset(b) for s, b in out.items()}


def partial_sums(net: Netlist) -> dict[str, frozenset[str]]:
    """For each block with a partial sum (a pre-summer of the terms needing the other sign), the
    signals that partial sum takes, by the names the realisation gives them."""
    quantity = {a.id: a.carries.quantity for a in net.amplifiers}
    return {a.carries.quantity.removeprefix(PARTIAL): frozenset(quantity.get(i.source, i.source) for i in a.inputs)
            for a in net.amplifiers if a.carries.quantity.startswith(PARTIAL)}
