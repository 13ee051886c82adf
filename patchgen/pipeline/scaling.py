"""The patch every command patches, simulates and checks: the spec's law scaled into volts by its
sensor constants, then (``[patch] scaling = "snr"``, the default, the law as its states) each
internal signal raised as far as the bench lets it (patchgen.patch.snr_scaling).

How far a signal may go is what the bench Monte Carlo of the standard scenarios shows it reaching
with the sensor-constant scales (the envelope): the runs the sheet's prediction makes
(patchgen.bench.prediction.standard_runs), with ENVELOPE_RUNS seeds of the long hold whatever a
command's own run count, so that every command builds the same patch from the same spec, machine
and bench. The scaling is linear, so a signal's peak moves with its scale; the prediction of the
scaled patch checks it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from patchgen.design.lqg import Design
from patchgen.inputs.errors import InputError
from patchgen.patch.build import build_patch
from patchgen.patch.differences import without_differentiators
from patchgen.patch.netlist import Netlist
from patchgen.patch.realization import realize
from patchgen.patch.snr_scaling import Scaling, block_peaks, snr_scales
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

ENVELOPE_RUNS = 8  # seeds of the long hold in the envelope (one run of the others): HEADROOM covers the rest

Runs = dict  # scenario name -> list of patchgen.bench.results.RunSummary


@dataclass(frozen=True)
class ScaledPatch:
    """The patch, its scaling (None: kept at the sensor constants), and the envelope's runs when
    they are runs of this very patch (its scales kept: they stand in for the prediction's)."""

    netlist: Netlist
    scaling: Scaling | None
    runs: Runs | None


def wants_scaling(d: Design) -> bool:
    """Whether the spec asks for signal-to-noise scaling of a law it places as its states."""
    p = d.spec.patch
    return p.scaling == "snr" and not (p.realization == "compensator" and d.controller is not None)


def envelope_runs(d: Design, net: Netlist, machine: MachineProfile, bench: BenchProfile) -> Runs:
    """The standard scenarios' runs the envelope is taken over (the simulator, loaded here)."""
    from patchgen.bench.prediction import standard_runs

    return standard_runs(net, d.plant, bench, machine, ENVELOPE_RUNS, bench_spread=bool(bench.uncertainty.ranges))


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
    net = build_patch(d, machine) if net is None else net
    if not wants_scaling(d):
        return ScaledPatch(net, None, None)
    runs = runs_of(net) if runs_of is not None else envelope_runs(d, net, machine, bench)
    peaks: dict[str, float] = {}
    for rs in runs.values():
        for r in rs:
            for a, v in r.amp_peaks_V:
                peaks[a] = max(peaks.get(a, 0.0), v)
    real = without_differentiators(realize(d, machine), machine)  # the blocks build_patch places
    scaling = snr_scales(real, block_peaks(real, {a.id: a.carries.quantity for a in net.amplifiers}, peaks), machine)
    if not scaling.changes:
        return ScaledPatch(net, scaling, runs)
    try:
        scaled = build_patch(d, machine, scales=scaling.factors)
    except InputError as exc:  # the scaled law needs what the machine lacks: keep the sensor constants
        note = f"not scaled for signal-to-noise: the scaled patch does not fit ({exc.message})"
        return ScaledPatch(net.model_copy(update={"notes": [*net.notes, note]}), None, runs)
    return ScaledPatch(scaled.model_copy(update={"notes": [*scaled.notes, *scaling.notes()]}), scaling, None)
