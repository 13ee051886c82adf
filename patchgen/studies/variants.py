"""Variants of a spec that recommend tries when none of the spec's own realisations holds on the
bench: the nearest patches that may hold, each change stated (patchgen.studies.departures).

The changes, each made only where it changes something:

- **an integral state the force cannot move dropped.** An integral whose pole at the origin is
  uncontrollable (the plant conserves a combination of its states and that integral: thesis-ch5's
  integral of theta) is designed with a tiny leak, but patched as a pure integrator: the wired loop
  keeps a pole on the axis (marginal on the bench) and the integrator drifts. A leak the patch could
  hold would need the integrator's own output fed back through a pot, at least the dial's smallest
  setting over the integrator's time scale (1e-3 1/s on the GP-6, a hundred times the spec's
  default), which the realisation does not wire; and since the force cannot move that mode, no leak
  makes the integral do any work. Dropping it (and its weight) is the honest variant.
- **coefficients below the dial left out** (``below_resolution = "omit"``) where the spec sets them
  to the dial's minimum or rounds them up to it.
- **theta weighted harder**, its weight times THETA_STEPS squared (a Bryson excursion divided by
  THETA_STEPS): a higher loop gain shrinks the limit cycle the bench's dead zone drives (the
  lesson of the shipped bench-recommended design), at the price of larger gains.
- **the command weighted harder** on a bench without a dead zone, first: R times THETA_STEPS
  squared (a Bryson force times THETA_STEPS). A stiff law asks a release more than the
  actuator's limit (a Quanser IP02 with Quanser's own weights asks 33 V of a 10 V amplifier from
  10 deg), and the law's summers leave the reference before its command reaches the limit; a
  softer law keeps them inside. Then theta weighted harder, as above.

The bench's actuator designed in is already one of the spec's own realisations (recommend's
candidate_specs), so every variant is tried with both actuator models too.

Nearest first: first each structural change alone, then together, with the spec's weights; then
at each step of THETA_STEPS the weights alone, then with one structural change, then with all.
Recommend stops at the first tier where a realisation holds.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from patchgen.design.lqg import Design
from patchgen.design.model import build_model
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.realization import realize
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

THETA_STEPS = (2.0, 4.0, 8.0)  # theta's excursion divided by these (its weight times their squares)
NULL_TOL = 1e-9  # relative: a singular value of [A B] this small leaves a mode the force cannot move
INTEGRALS = ("int_s", "int_theta")


@dataclass(frozen=True)
class Variant:
    """A changed spec: what changed in a few words, the spec, and why by field (as
    patchgen.studies.departures.departures takes it)."""

    name: str
    spec: DesignSpec
    whys: dict[str, str] = field(default_factory=dict)


def conserved_integrals(spec: DesignSpec) -> dict[str, str]:
    """The spec's integral states whose pole at the origin the force cannot move, each with the
    combination the plant then conserves (text: ``-0.0007336 theta - ... + int_theta``).

    The PBH test at s = 0 on the design model with that integral's leak taken out, as the patch's
    pure integrator has it: a left null vector of [A B] is a combination of the states that no
    force changes."""
    out = {}
    for name in INTEGRALS:
        if not getattr(spec.integrators, name):
            continue
        model = build_model(spec.model_copy(update={"integrators": spec.integrators.model_copy(
            update={f"{name}_leak": 0.0})}))
        keep = tuple(s for s in model.states if not s.startswith("int_") or s == name)
        A, B, _ = model.submodel(keep)
        u, sv, _ = np.linalg.svd(np.hstack([A, B]))
        if len(sv) == len(keep) and sv[-1] > NULL_TOL * sv[0]:
            continue
        w = u[:, -1] / u[keep.index(name), -1]
        parts = [("-" if c < 0 else "+", s if abs(abs(c) - 1) < 1e-12 else f"{abs(c):.4g} {s}")
                 for c, s in zip(w, keep) if abs(c) > 1e-9]
        out[name] = "-" * (parts[0][0] == "-") + parts[0][1] + "".join(f" {sg} {t}" for sg, t in parts[1:])
    return out


def below_dial(design: Design, machine: MachineProfile) -> bool:
    """Whether the patch of a design wired as its states dials a coefficient the spec's
    ``below_resolution`` raises to the dial's smallest setting (``minimum``: any below it;
    ``round``: from half of it up)."""
    policy = design.spec.patch.below_resolution
    if policy == "omit" or design.spec.patch.realization != "states":
        return False
    res = machine.pot_resolution
    low = 0.0 if policy == "minimum" else res / 2
    return any(low <= abs(t.coeff) < res and t.coeff != 0 for b in realize(design, machine).blocks for t in b.terms)


def drop_integral(spec: DesignSpec, name: str) -> DesignSpec:
    """The spec without one integral state: its flag off and its weight gone (a Q table's entry, a
    full Q's row and column, a Bryson excursion)."""
    w = spec.weights
    upd: dict = {}
    if isinstance(w.Q, dict):
        upd["Q"] = {k: v for k, v in w.Q.items() if k != name}
    elif w.Q is not None:
        i = spec.states().index(name)
        upd["Q"] = [[x for j, x in enumerate(row) if j != i] for r, row in enumerate(w.Q) if r != i]
    if w.bryson is not None:
        upd["bryson"] = {k: v for k, v in w.bryson.items() if k != name}
    return spec.model_copy(update={"integrators": spec.integrators.model_copy(update={name: False}),
                                   "weights": w.model_copy(update=upd)})


def tighten_theta(spec: DesignSpec, step: float) -> DesignSpec | None:
    """The spec with theta's excursion divided by ``step`` (its weight times step squared); None
    when theta carries no weight to tighten."""
    w = spec.weights
    if w.bryson is not None:
        if "theta" not in w.bryson:
            return None
        upd = {"bryson": {**w.bryson, "theta": _clean(w.bryson["theta"] / step)}}
    elif isinstance(w.Q, dict):
        if not w.Q.get("theta"):
            return None
        upd = {"Q": {**w.Q, "theta": _clean(w.Q["theta"] * step**2)}}
    else:
        i = spec.states().index("theta")
        if not w.Q[i][i]:
            return None
        upd = {"Q": [[_clean(x * step ** ((r == i) + (j == i))) for j, x in enumerate(row)]
                     for r, row in enumerate(w.Q)]}
    return spec.model_copy(update={"weights": w.model_copy(update=upd)})


def _clean(x: float) -> float:
    """Six significant digits, so the written spec reads cleanly."""
    return float(f"{x:.6g}")


def structural(spec: DesignSpec, machine: MachineProfile,
               below: bool) -> list[tuple[str, dict[str, str], Callable[[DesignSpec], DesignSpec]]]:
    """The structural changes that apply to ``spec``: (name, why by field, the change as a function
    of a spec); ``below`` says whether one of its patches dials a coefficient below the dial."""
    out = []
    res, T = machine.pot_resolution, machine.time_scale_s
    for name, text in conserved_integrals(spec).items():
        leak = getattr(spec.integrators, f"{name}_leak")
        why = (f"the force cannot move this integral's pole at 0 (the plant conserves {text}): designed with a "
               f"leak of {leak:g} 1/s but patched as a pure integrator, it leaves a pole of the wired loop on the "
               f"axis (marginal on the bench) and drifts; a leak the dial could set (at least {res / T:g} 1/s) is "
               "not wired, and no leak would let the force move that pole")
        whys = {f"integrators.{name}": why, f"weights.Q.{name}": "its weight goes with the state",
                f"weights.bryson.{name}": "its excursion goes with the state",
                "weights.Q": "the integral's row and column go with the state"}
        out.append((f"{name} dropped", whys, lambda sp, n=name: drop_integral(sp, n)))
    if below and spec.patch.below_resolution != "omit":
        how = "set to" if spec.patch.below_resolution == "minimum" else "rounded up to"
        why = (f"a coefficient below the dial's {res:g} left out, not {how} {res:g}: the dial cannot set the "
               "design's value, and the minimum is a gain the design did not ask for")
        out.append(("coefficients below the dial left out", {"patch.below_resolution": why},
                    lambda sp: sp.model_copy(update={"patch": sp.patch.model_copy(
                        update={"below_resolution": "omit"})})))
    return out


def tiers(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile, below: bool) -> list[list[Variant]]:
    """The variants of ``spec``, nearest first, in tiers (see the module docstring): recommend
    runs a tier's realisations together and stops after the first tier where one holds.

    Parameters
    ----------
    spec : DesignSpec
        The spec as given.
    machine, bench : MachineProfile, BenchProfile
        The machine (its dial) and the bench (its dead zone), for the reasons given.
    below : bool
        Whether one of the spec's own patches dials a coefficient below the dial (``below_dial``).

    Returns
    -------
    list of list of Variant
        Empty when no change applies.
    """
    changes = structural(spec, machine, below)
    dz = bench.actuator.dead_zone_V
    steps = [(1.0, spec, {}, "")]
    if dz == 0:
        steps += [(k, soften_command(spec, k), _command_whys(k, bench), f"command weighted x{k * k:g}")
                  for k in THETA_STEPS]
    for k in THETA_STEPS:
        weighted = tighten_theta(spec, k)
        if weighted is None:
            break
        steps.append((k, weighted, _weight_whys(k, dz), f"theta weighted x{k * k:g}"))
    out = []
    for step, weighted, weigh, label in steps:
        for size in range(1 if step == 1.0 else 0, len(changes) + 1):
            tier = [_variant(weighted, combo, label, weigh) for combo in itertools.combinations(changes, size)]
            if tier:
                out.append(tier)
    return out


def soften_command(spec: DesignSpec, step: float) -> DesignSpec:
    """The spec with the control weight times ``step`` squared (a Bryson force times ``step``)."""
    w = spec.weights
    if w.bryson is not None:
        upd = {"bryson": {**w.bryson, "u": _clean(w.bryson["u"] * step)}}
    elif w.R_V is not None:
        upd = {"R_V": _clean(w.R_V * step**2)}
    else:
        upd = {"R": _clean(w.R * step**2)}
    return spec.model_copy(update={"weights": w.model_copy(update=upd)})


def _command_whys(step: float, bench: BenchProfile) -> dict[str, str]:
    """Why the control weight went up, by the fields that carry it."""
    limit = (f"the amplifier's +/-{bench.actuator.V_limit:g} V" if bench.actuator.model == "dc_motor"
             else f"the actuator's {bench.actuator.force_limit_N:g} N")
    why = (f"the command weighted x{step * step:g}: a softer law asks less of {limit} and keeps the law's summers "
           "inside the machine's reference where a stiff one leaves it before the command reaches the limit")
    return {"weights.R": why, "weights.R_V": why, "weights.bryson.u": why}


def _weight_whys(step: float, dead_zone_V: float) -> dict[str, str]:
    """Why theta's weight went up, by the fields that carry it."""
    what = (f"shrinks the limit cycle the bench's dead zone (+/-{dead_zone_V:g} V) drives, so the cart stays inside "
            "the switches" if dead_zone_V > 0 else "deepens the lower gain margin against what the design model "
            "leaves out of the bench")
    why = f"theta weighted x{step * step:g} (its excursion /{step:g}): a higher loop gain {what}"
    return {"weights.Q.theta": why, "weights.bryson.theta": why, "weights.Q": why}


def _variant(spec: DesignSpec, combo: Sequence[tuple], label: str, weigh: dict[str, str]) -> Variant:
    """One tier's variant: the weighted spec with the structural changes of ``combo``."""
    whys = dict(weigh)
    names = []
    for name, why, change in combo:
        spec = change(spec)
        names.append(name)
        for k, v in why.items():
            whys[k] = f"{whys[k]}; {v}" if k in whys else v
    if label:
        names.append(label)
    return Variant(", ".join(names), spec, whys)
