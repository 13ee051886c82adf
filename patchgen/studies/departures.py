"""What a realisation changes of the spec it was made from: each field whose value differs, the
spec's value, the realisation's, and why (a ``Departure``), so that the comparison, the sheet and
recommended.toml can name every one.

The departures are found by comparing the two specs field by field, not by trusting whoever made
the change to list it: the spec a realisation writes (``settled_spec``: settings the design chose
fixed, the units it needs) against the spec given. A field the spec leaves open (unset, or
"auto") and the realisation fixes is what the spec asked for, not a departure. Labels (name,
description, source) are not compared.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from patchgen.design.lqg import Design
from patchgen.inputs.spec import DesignSpec
from patchgen.profiles.bench import BenchProfile

LABELS = ("name", "description", "source")  # what a spec is called, not what it designs
OPEN = (None, "auto")  # a spec value that leaves the choice to patchgen


@dataclass(frozen=True)
class Departure:
    """One field of the spec the realisation changes: its dotted name, the spec's value and the
    realisation's (None: not set) and why."""

    field: str
    was: object
    now: object
    why: str

    def as_dict(self) -> dict:
        """Plain JSON-ready values: field, from, to, why."""
        return {"field": self.field, "from": self.was, "to": self.now, "why": self.why}

    def change(self) -> str:
        """The change in a few words: ``integrators.int_theta true -> false``."""
        return f"{self.field} {value_text(self.was)} -> {value_text(self.now)}"

    def line(self) -> str:
        """The change and why, one line."""
        return f"{self.change()}: {self.why}"


def grouped(deps: tuple[Departure, ...]) -> list[str]:
    """The departures as lines, those in a row with one reason on one line: ``a 1 -> 2, b 3 -> 4: why``."""
    lines: list[tuple[list[str], str]] = []
    for d in deps:
        if lines and lines[-1][1] == d.why:
            lines[-1][0].append(d.change())
        else:
            lines.append(([d.change()], d.why))
    return [f"{', '.join(changes)}: {why}" for changes, why in lines]


def value_text(v: object) -> str:
    """A spec value as the TOML file writes it ("not set" for none)."""
    if v is None:
        return "not set"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:g}" if math.isfinite(v) else str(v)
    if isinstance(v, list):
        return "[" + ", ".join(value_text(x) for x in v) + "]"
    return f'"{v}"' if isinstance(v, str) else str(v)


def flat(spec: DesignSpec) -> dict[str, object]:
    """Every field of a spec by dotted name (a table's keys, such as Q's states, each a field of its
    own; a list one value); unset fields None, labels left out."""
    out: dict[str, object] = {}

    def walk(prefix: str, value: object) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{prefix}.{k}" if prefix else k, v)
        else:
            out[prefix] = value

    walk("", {k: v for k, v in spec.model_dump(mode="python").items() if k not in LABELS})
    return out


def settled_spec(sp: DesignSpec, design: Design | None, units: int | None) -> DesignSpec:
    """The spec a realisation writes: ``sp`` with the estimator settings its design chose fixed
    (roll-off, observer pole, Kalman rho) and the slaved units its patch takes, so that patching it
    gives the same patch again (without a design or a patch, ``sp`` as it is)."""
    e = None if design is None else design.estimator
    upd: dict = {}
    if e is not None and e.kind in ("differentiator", "filtered_differentiator"):
        upd["rolloff_s"] = e.rolloff_s
    elif e is not None and e.kind == "reduced_observer":
        upd["observer_pole"] = e.observer.pole
    elif e is not None and e.kind == "kalman" and e.rho is not None:
        upd["rho"] = e.rho
    patch = sp.patch if units is None else sp.patch.model_copy(update={"units": units})
    return sp.model_copy(update={"estimator": sp.estimator.model_copy(update=upd), "patch": patch})


def departures(base: DesignSpec, settled: DesignSpec, whys: dict[str, str]) -> tuple[Departure, ...]:
    """Every field ``settled`` changes of ``base``, in the spec's field order.

    Parameters
    ----------
    base : DesignSpec
        The spec as given.
    settled : DesignSpec
        A realisation's spec, as ``settled_spec`` writes it.
    whys : dict
        Why, by field or by the table holding it (``"actuator"``, ``"weights.Q"``): the longest
        name that is the field or holds it gives the reason.

    Returns
    -------
    tuple of Departure
        Nothing for a field the spec leaves open (unset or "auto"); a field no entry of ``whys``
        covers is a ValueError (every departure is explained).
    """
    a, b = flat(base), flat(settled)
    out = []
    for f in list(a) + [f for f in b if f not in a]:
        was, now = a.get(f), b.get(f)
        if was == now or (f in a and (was is None or was == "auto")):
            continue  # the same, or left open by the spec
        owners = [k for k in whys if f == k or f.startswith(k + ".")]
        if not owners:
            raise ValueError(f"{f} departs from the spec ({value_text(was)} -> {value_text(now)}) with no reason given")
        out.append(Departure(f, was, now, whys[max(owners, key=len)]))
    return tuple(out)


def realisation_whys(sp: DesignSpec, design: Design | None, bench: BenchProfile, units: int | None) -> dict[str, str]:
    """Why a realisation of recommend's (patchgen.studies.recommend.candidate_specs), with spec
    ``sp`` and ``design`` (None: it did not design), changes the fields it changes: its estimator,
    the bench's actuator, the compensator as one system, the units its patch takes."""
    b = bench.actuator
    act = f"{b.model} {b.tau:g} s" if b.model != "gain" else "a gain"
    e = None if design is None else design.estimator
    kind = sp.estimator.kind
    unused = f"not used by the {kind.replace('_', ' ')}"
    noise = "chosen from the bench noise (patchgen.design.corner) for this realisation"
    roll = (noise if e is not None and e.chosen_from_noise else "the machine's default roll-off for the raw "
            "differentiator") if kind in ("differentiator", "filtered_differentiator") else unused
    return {
        "estimator.kind": "recommend tries every way of getting theta_dot that the machine can hold",
        "estimator.rolloff_s": roll,
        "estimator.observer_pole": noise if kind == "reduced_observer" else unused,
        "estimator.rho": "the LTR factor the Kalman design settled on",
        "estimator.V": "unit sensor noise, one per signal the bench gives (the spec's default, sized to what it reads)",
        "actuator": (f"the bench's actuator ({bench.id}: {act}, dead zone +/-{b.dead_zone_V:g} V) designed in: "
                     "the spec's design model is not what the patch meets"),
        "patch.realization": "recommend also tries the Kalman compensator patched as one system",
        "patch.order": "the order of the compensator patched as one system",
        "patch.units": f"the patch takes {units} slaved units",
    }
