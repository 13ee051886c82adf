"""The one reading of a netlist: what feeds what, with which gain, in which order, with which sign.

Every consumer of a netlist (the simulator's circuit arrays, the read-back of the control law, the
SPICE deck, the sheet's sign table and the diagram's stages) reads it through :func:`read`, so a
patch means one thing everywhere. The reading checks what a netlist file could get wrong (unknown
sources and pots, an amplifier id used twice, a lag without a time constant, feed-through
amplifiers wired in a ring) and resolves each amplifier's element values once, with the
machine's defaults where the netlist leaves them out.

Every amplifier inverts: an input's gain is weight x pot setting (>= 0; negative for an input
marked ``negated`` on a machine with signed coefficients) and the inversion belongs to the role.
Integrators and lags hold their output in a capacitor (a state, no feed-through); summers,
inverters and differentiators pass their present input through.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

from patchgen.inputs.errors import InputError
from patchgen.patch.netlist import Netlist

STATEFUL = ("integrator", "lag")  # output is a state: evaluated first, no feed-through
FEED_THROUGH = ("summer", "inverter", "differentiator")


class AlgebraicLoopError(InputError):
    """Feed-through amplifiers wired in a loop with no integrator or lag in it."""


@dataclass(frozen=True)
class Feed:
    """One input of an amplifier: its source (sensor or amplifier id) and gain = weight x pot."""

    source: str
    gain: float


@dataclass(frozen=True)
class Stage:
    """One amplifier as wired, with its element values resolved.

    ``T_s`` is the integrator's time scale, ``tau_s`` the lag's time constant, ``T_d_s`` and
    ``rolloff_s`` the differentiator's gain time and roll-off; the others are None. ``ic_V`` is NaN
    for an integrator the netlist gives no IC: it starts settled on its input (a lag closed through
    a difference, patchgen.patch.differences), as a differentiator does.
    """

    id: str
    role: str
    feeds: tuple[Feed, ...]
    ic_V: float
    T_s: float | None = None
    tau_s: float | None = None
    T_d_s: float | None = None
    rolloff_s: float | None = None

    @property
    def stateful(self) -> bool:
        """True for integrators and lags: the output is a capacitor's state, not the present input."""
        return self.role in STATEFUL


@dataclass(frozen=True)
class Reading:
    """A netlist read once: its sensors, its amplifiers by id, their evaluation order, the output."""

    sensors: tuple[str, ...]
    amplifiers: dict[str, Stage]  # netlist order
    order: tuple[str, ...]  # stateful amplifiers (netlist order), then feed-through ones topologically
    output: str  # source of the control voltage u_c

    def fed_by(self) -> dict[str, list[str]]:
        """Source id -> the amplifiers it feeds, in netlist order (an amplifier once per input)."""
        out: dict[str, list[str]] = {}
        for a in self.amplifiers.values():
            for f in a.feeds:
                out.setdefault(f.source, []).append(a.id)
        return out

    def path_sign(self, amp_id: str) -> int | None:
        """Sign of u_c per volt entering ``amp_id``: one inversion per amplifier to the output.

        None when the amplifier reaches the output by no path or by more than one. Several inputs
        of one amplifier from the same source (a coefficient split across inputs) are one path.
        """
        feeds = self.fed_by()
        paths: list[int] = []

        def walk(node: str, depth: int, seen: frozenset[str]) -> None:
            if len(paths) > 1:
                return
            if node == self.output:
                paths.append(depth)
                return
            for nxt in dict.fromkeys(feeds.get(node, [])):
                if nxt not in seen:
                    walk(nxt, depth + 1, seen | {nxt})

        walk(amp_id, 1, frozenset({amp_id}))
        if len(paths) != 1:
            return None
        return -1 if paths[0] % 2 else 1

    def levels(self) -> dict[str, int]:
        """Stage of each sensor (0) and amplifier: the wiring diagram's columns (:func:`stage_levels`)."""
        return stage_levels(self.sensors, [(a.id, a.role, [f.source for f in a.feeds])
                                           for a in self.amplifiers.values()])


def stage_levels(sources: Iterable[str], amplifiers: Iterable[tuple[str, str, Iterable[str]]]) -> dict[str, int]:
    """Stage of each source and amplifier in a wiring diagram, as an analog computer is drawn.

    Parameters
    ----------
    sources : iterable of str
        Signals entering the diagram (sensors, or signals from another unit): stage 0.
    amplifiers : iterable of (id, role, source ids)
        In netlist order.

    Returns
    -------
    dict of str to int
        Integrators and lags (their outputs are states, fed back as a patch needs) at stage 1; a
        feed-through amplifier one after its latest source. A ring of feed-through amplifiers (which
        :func:`read` refuses) is broken in netlist order.
    """
    level: dict[str, int] = {s: 0 for s in sources}
    amps = [(aid, role, [s for s in srcs if s != aid]) for aid, role, srcs in amplifiers]
    level.update({aid: 1 for aid, role, _ in amps if role in STATEFUL})
    remaining = [a for a in amps if a[1] not in STATEFUL]
    while remaining:
        ready = [a for a in remaining if all(s in level for s in a[2])] or remaining[:1]
        for aid, _, srcs in ready:
            level[aid] = 1 + max([level[s] for s in srcs if s in level], default=0)
        remaining = [a for a in remaining if a[0] not in level]
    return level


def read(net: Netlist, default_rolloff_s: float | None = None) -> Reading:
    """Read a netlist; what it gets wrong is an InputError naming the netlist and the field.

    Parameters
    ----------
    net : Netlist
        The patch.
    default_rolloff_s : float, optional
        The machine's roll-off for a differentiator that names none (a pure differentiator can be
        neither patched nor simulated); without it such a differentiator's roll-off stays None.

    Returns
    -------
    Reading
        Sensors, amplifiers with their gains and element values, evaluation order, output.
    """
    src = f"netlist {net.design}"
    sensors = tuple(s.id for s in net.sensors)
    ids = [a.id for a in net.amplifiers]
    if len(set(ids)) != len(ids):
        raise InputError(src, "amplifiers", "an amplifier id is used twice")
    pots = {p.id: p for p in net.pots}
    known = set(sensors) | set(ids)
    stages: dict[str, Stage] = {}
    for i, a in enumerate(net.amplifiers):
        feeds = []
        for k, inp in enumerate(a.inputs):
            where = f"amplifiers[{i}].inputs[{k}]"
            if inp.source not in known:
                raise InputError(src, f"{where}.source", f"unknown source {inp.source!r}")
            if inp.pot is not None and inp.pot not in pots:
                raise InputError(src, f"{where}.pot", f"unknown pot {inp.pot!r}")
            sign = -1.0 if inp.negated else 1.0  # a signed coefficient (patchgen.patch.netlist.AmpInput)
            feeds.append(Feed(inp.source, sign * inp.weight * (pots[inp.pot].setting if inp.pot is not None else 1.0)))
        stages[a.id] = _stage(a, tuple(feeds), net.time_scale_s, default_rolloff_s, src, i)
    if net.output.source not in known:
        raise InputError(src, "output.source", f"unknown source {net.output.source!r}")
    return Reading(sensors, stages, _evaluation_order(stages, src), net.output.source)


def _stage(a, feeds: tuple[Feed, ...], time_scale_s: float, default_rolloff_s: float | None, src: str,
           i: int) -> Stage:
    """One amplifier's element values: an integrator's time scale is its mode's; a lag needs its
    tau; a differentiator's T_d defaults to the machine's time scale and its roll-off to the
    machine's default."""
    ic = a.ic_V or 0.0
    if a.role == "integrator":  # its mode's 1/k0, or the netlist's time scale (a schema-2 netlist)
        ic = math.nan if a.ic_V is None else ic  # no IC: it starts settled on its input
        return Stage(a.id, a.role, feeds, ic, T_s=1.0 / a.mode.k0_per_s if a.mode is not None else time_scale_s)
    if a.role == "lag":
        if not a.tau_s or a.tau_s <= 0:
            raise InputError(src, f"amplifiers[{i}].tau_s", "a lag amplifier needs tau_s > 0")
        return Stage(a.id, a.role, feeds, ic, tau_s=a.tau_s)
    if a.role == "differentiator":
        roll = a.rolloff_s if a.rolloff_s else default_rolloff_s
        return Stage(a.id, a.role, feeds, ic, T_d_s=a.T_d_s if a.T_d_s is not None else time_scale_s,
                     rolloff_s=roll)
    return Stage(a.id, a.role, feeds, ic)


def _evaluation_order(stages: dict[str, Stage], src: str) -> tuple[str, ...]:
    """State-output amplifiers first (netlist order), then feed-through ones topologically."""
    order = [aid for aid, a in stages.items() if a.stateful]
    deps = {aid: [f.source for f in a.feeds if f.source in stages and not stages[f.source].stateful]
            for aid, a in stages.items() if not a.stateful}
    done: set[str] = set()
    visiting: list[str] = []

    def visit(aid: str) -> None:
        if aid in done:
            return
        if aid in visiting:
            loop = visiting[visiting.index(aid):] + [aid]
            raise AlgebraicLoopError(
                src, "amplifiers",
                f"algebraic loop {' -> '.join(loop)}: feed-through amplifiers (summers, inverters, "
                "differentiators) wired in a ring with no integrator or lag in it")
        visiting.append(aid)
        for dep in deps[aid]:
            visit(dep)
        visiting.pop()
        done.add(aid)
        order.append(aid)

    for aid in deps:
        visit(aid)
    return tuple(order)
