"""Which realisation of a compensator fits the machine: every order and form placed and compared.

For a design with a compensator (patchgen.design.compensator), the minimal law with the modes
faster than the machine's inputs reach residualised, then every lower order (balanced truncation
and balanced singular perturbation, the integral part kept), each in every form of
patchgen.patch.compensator_forms, is placed on 1, 2, ... slaved units. A realisation is compared by
units, pots and amplifiers, its coefficient range, the amplitude its states reach, and the loop's
margins on the design model with the pots as dialled (the netlist read back), its sensitivity to
the dial. At the full order the minimal law with its fast modes kept is tried as well
(:func:`whole_law`): a realisation that keeps KEEP_PM_SHARE of the design's phase margin as dialled
is chosen before any that keeps less (:func:`best`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from patchgen.design import compensator as comp
from patchgen.design.lqg import Design, loop_with_controller
from patchgen.design.margins import Margins, loop_margins
from patchgen.inputs.errors import InputError, ResourceError
from patchgen.patch import large_gains
from patchgen.patch.allocation import allocate
from patchgen.patch.compensator_forms import (
    AMPLITUDE,
    FORMS,
    STAGE_SUFFIX,
    FormSystem,
    coefficient_range,
    excursion_peaks,
    excursions,
    form_system,
    peaks,
    realize_compensator,
    scaling_plants,
)
from patchgen.patch.netlist import Netlist
from patchgen.patch.readback import si_controller, wired_law
from patchgen.patch.realization import Realization
from patchgen.profiles.machine import MachineProfile

METHODS = ("truncate", "residualise")
SHRINK_ROUNDS = 4  # placements of one law and form while scaling down the states that overload
UNSTABLE_LAW = "the loop with this law is unstable on the design model"  # a Fit's error: the law's own fault
# A realisation whose loop as dialled (the netlist read back, on the design model) keeps this share
# of the design's phase margin is chosen before every one that keeps less, whatever it costs in
# units, amplifiers and pots: thesis case 2 residualised keeps 28 % (14.9 of 52.8 deg).
KEEP_PM_SHARE = 0.8
FAST_KEPT = "fast modes kept"  # the method of whole_law's law


@dataclass(frozen=True)
class Fit:
    """One realisation tried: the law, its form, and where it landed (or why it did not)."""

    order: int
    method: str  # minimal, FAST_KEPT, truncate or residualise
    form: str
    law: comp.Compensator
    design_margins: Margins = field(compare=False)
    netlist: Netlist | None = None
    error: str | None = None
    coefficients: tuple[float, float] = (0.0, 0.0)  # smallest and largest magnitude
    peak_fraction: float = 0.0  # the largest amplifier's peak over the scaling excursions / reference
    dialled_margins: Margins | None = field(default=None, compare=False)
    staged: bool = False  # blocks with coefficients above one input summed at 1/g first (compensator_forms)
    real: Realization | None = field(default=None, compare=False, repr=False)  # the realisation placed

    @property
    def units(self) -> int | None:
        """Slaved units the patch needs (None when it does not fit)."""
        return None if self.netlist is None else self.netlist.units

    @property
    def pots(self) -> int | None:
        """Pots the patch uses."""
        return None if self.netlist is None else len(self.netlist.pots)

    @property
    def amplifiers(self) -> int | None:
        """Amplifiers the patch uses."""
        return None if self.netlist is None else len(self.netlist.amplifiers)

    @property
    def holds_dialled(self) -> bool:
        """The loop on the design model is stable with the pots as dialled."""
        return self.dialled_margins is not None and self.dialled_margins.stable

    def key(self) -> tuple:
        """Cheapest first: units, pots, amplifiers, then the dialled loop's phase margin (larger first)."""
        pm = self.dialled_margins.pm_deg if self.holds_dialled and self.dialled_margins.pm_deg else 0.0
        return (self.units, self.pots, self.amplifiers, -round(pm, 1), FORMS.index(self.form))

    def line(self) -> str:
        """One line for the table."""
        head = f"order {self.order} ({self.method}), {self.form}" + (", staged sums" if self.staged else "")
        if self.netlist is None:
            return f"{head}: {self.error}"
        m = self.dialled_margins
        marg = (f"dialled loop GM {_db(m.lower_gm_db)}/{_db(m.upper_gm_db)} dB, PM {m.pm_deg:.1f} deg"
                if m is not None and m.stable and m.pm_deg is not None else "dialled loop unstable")
        return (f"{head}: {self.units} unit(s), {self.amplifiers} amplifiers, {self.pots} pots, coefficients "
                f"{self.coefficients[0]:.3g}..{self.coefficients[1]:.3g}, largest amplifier "
                f"{self.peak_fraction:.2f} of the reference, {marg}")


def _db(x: float | None) -> str:
    return "inf" if x is None else f"{x:.1f}"


def pm_share(patched: Margins | None, designed: Margins | None) -> float | None:
    """The share of the design's phase margin a loop keeps.

    None when the design has none to keep (its loop unstable, or no gain crossover); 0 for a loop
    that is not stable; infinite for a stable one without a gain crossover (|L| never 1).
    """
    if designed is None or not designed.stable or not designed.pm_deg:
        return None
    if patched is None or not patched.stable:
        return 0.0
    return math.inf if patched.pm_deg is None else patched.pm_deg / designed.pm_deg


def keeps_margin(fit: Fit, designed: Margins | None) -> bool:
    """The fit's dialled loop keeps KEEP_PM_SHARE of ``designed``'s phase margin (or there is none to keep)."""
    share = pm_share(fit.dialled_margins, designed)
    return fit.holds_dialled if share is None else share >= KEEP_PM_SHARE


def _fastest(machine: MachineProfile) -> float:
    """The fastest mode laws() patches unresidualised (rad/s): a gain stage into a full-weight input
    of the machine's fastest integrator mode (the top gain squared times its k0)."""
    return large_gains.top_gain(machine) ** 2 * max(m.k0_per_s for m in machine.integrator_modes)


def whole_law(design: Design, machine: MachineProfile) -> tuple[int, str, comp.Compensator] | None:
    """The minimal law with the modes :func:`laws` residualises kept (None when it residualises none).

    The cut at the top gain squared is on a mode's magnitude; a complex pair's own coefficients in
    modal form are its real and imaginary parts, each below it (thesis case 2's -76 +/- 76j pair,
    108 rad/s), and its couplings can be balanced across a gain stage on each side
    (patchgen.patch.compensator_forms). Whether the machine takes it, placing it tells.
    """
    whole = comp.compensator(design)
    if (np.abs(np.linalg.eigvals(whole.A)) <= _fastest(machine)).all():
        return None
    return whole.order, FAST_KEPT, whole


def laws(design: Design, machine: MachineProfile, method: str = "auto") -> list[tuple[int, str, comp.Compensator]]:
    """The minimal law (modes faster than a gain stage into a full-weight input of the fastest
    integrator mode reaches, the top gain squared times its k0, residualised) and each
    lower order down to the integral part alone: (order, method, law), highest order first."""
    full = comp.without_fast_modes(comp.compensator(design), _fastest(machine))
    out = [(full.order, "minimal", full)]
    methods = METHODS if method == "auto" else (method,)
    low = (0 if full.R is None else 1) + full.unstable
    for order in range(full.order - 1, max(low, 1) - 1, -1):
        for m in methods:
            out.append((order, m, comp.reduced(full, order, m)))
    return out


def dialled_margins(design: Design, net: Netlist) -> Margins:
    """The loop's margins on the design model with the law read back from the netlist (pots as dialled)."""
    A, B, C = loop_with_controller(design.model, si_controller(net))
    return loop_margins(A, B, C)


def amplifier_peaks(design: Design, net: Netlist) -> dict[str, float]:
    """Each amplifier's largest |output| (V) over the scaling excursions: the wired law closing each
    scaling plant (patchgen.patch.compensator_forms.scaling_plants)."""
    vpu = {s.id: s.volts_per_unit for s in net.sensors}
    law = wired_law(net)
    ks = np.diag([vpu[s] for s in law.inputs])
    KU = net.output.K_U_N_per_V
    outs = {a.id: wired_law(net, a.id) for a in net.amplifiers}
    peak = {a: 0.0 for a in outs}
    for Ap, Bp, Cp, names in scaling_plants(design):
        Acl = np.block([[Ap + Bp @ (KU * law.Dc) @ ks @ Cp, Bp @ (KU * law.Cc)], [law.Bc @ ks @ Cp, law.Ac]])
        rows = np.vstack([np.hstack([la.Dc @ ks @ Cp, la.Cc]) for la in outs.values()])
        p = excursion_peaks(Acl, rows, excursions(design, names))
        peak = {a: max(peak[a], float(v)) for a, v in zip(outs, p)}
    return peak


def _block_of(quantity: str) -> str:
    """The compensator block an amplifier serves: its own, its partial sum's or its gain stage's."""
    q = quantity.removeprefix("partial ")
    return q.split(f"_{large_gains.PREFIX}")[0].removesuffix(STAGE_SUFFIX)


def try_fit(design: Design, order: int, method: str, law: comp.Compensator, form: str, machine: MachineProfile,
            units: list[int], dm: Margins | None = None) -> Fit:
    """Place one law in one form on the fewest of ``units`` slaved units that takes it; a state whose
    amplifiers (its own, its partial sum, its gain stage) pass AMPLITUDE of the reference over the
    scaling excursions is scaled down and placed again (SHRINK_ROUNDS at most). When no count of
    units takes it, or an amplifier still passes the reference (a partial sum of u_c, say, whose
    terms cancel only in u_c), the blocks with coefficients above one input's reach are staged
    (patchgen.patch.compensator_forms.staged_blocks) and placed again; the staged patch is taken
    when it fits within the reference, or comes nearer to it. ``dm``: the law's margins on the
    design model when the caller has them (:func:`fits` tries each law in every form)."""
    dm = comp.margins(design, law) if dm is None else dm
    if not dm.stable:
        return Fit(order, method, form, law, dm, error=UNSTABLE_LAW)
    fs = form_system(law, form)
    pk = peaks(design, law, fs)  # the form's scaling excursions: the same however its states are shrunk or staged
    placed: dict[str, _Placed] = {}  # a staging that changes no block places the plain realisation again
    plain = _place_scaled(design, order, method, law, fs, pk, machine, units, dm, False, placed)
    if plain.netlist is not None and plain.peak_fraction <= 1.0:
        return plain
    again = _place_scaled(design, order, method, law, fs, pk, machine, units, dm, True, placed)
    if again.netlist is None or (plain.netlist is not None and again.peak_fraction >= plain.peak_fraction):
        return plain
    return again


@dataclass
class _Placed:
    """One realisation on the fewest units that take it: the patch (None, with the last unit
    count's error, when none does), its amplifiers' peaks, and its dialled margins once asked for."""

    netlist: Netlist | None
    error: str | None
    peaks: dict[str, float] = field(default_factory=dict)
    margins: Margins | None = None


def _place(design: Design, real, machine: MachineProfile, units: list[int]) -> _Placed:
    """Allocate ``real`` on the first of ``units`` slaved units that takes it, and its peaks."""
    err = None
    for n in units:
        try:
            net = allocate(real, machine.slaved(n), design.spec.path)
        except (ResourceError, InputError) as exc:
            err = exc.message
            continue
        net = net.model_copy(update={"units": n, "machine_name": machine.name})
        return _Placed(net, None, amplifier_peaks(design, net))
    return _Placed(None, err)


def _place_scaled(design: Design, order: int, method: str, law: comp.Compensator, fs: FormSystem,
                  pk: tuple[float, np.ndarray], machine: MachineProfile, units: list[int], dm: Margins,
                  staged: bool, placed: dict[str, _Placed]) -> Fit:
    """:func:`try_fit` for one choice of staging (``fs`` the law in its form, ``pk`` its peaks);
    ``placed``: the realisations already placed, by their repr (exact: floats print to the bit)."""
    form = fs.form
    shrink: dict[str, float] = {}
    for _ in range(SHRINK_ROUNDS):
        real = realize_compensator(design, law, form, machine, shrink, staged, (fs, pk))
        rng = coefficient_range(real, machine.pot_resolution)
        key = repr(real)
        if key not in placed:
            placed[key] = _place(design, real, machine, units)
        got = placed[key]
        if got.netlist is None:
            return Fit(order, method, form, law, dm, error=got.error, coefficients=rng, staged=staged)
        net, peaks = got.netlist, got.peaks
        limit = AMPLITUDE * machine.reference_V
        over = {}
        for a in net.amplifiers:
            b = _block_of(a.carries.quantity)
            if peaks[a.id] > limit and b != "u_c":
                over[b] = min(over.get(b, 1.0), limit / peaks[a.id])
        if not over:
            break
        for b, f in over.items():
            shrink[b] = shrink.get(b, 1.0) * f
    peak = max(peaks.values()) / machine.reference_V
    if got.margins is None:
        got.margins = dialled_margins(design, net)
    return Fit(order, method, form, law, dm, net, None, rng, peak, got.margins, staged, real)


def fits(design: Design, machine: MachineProfile, units: list[int], form: str = "auto",
         method: str = "auto", orders: list[int] | None = None, fast_kept: bool = False) -> list[Fit]:
    """Every law and form tried on ``units`` (in the order given), highest order first.

    Parameters
    ----------
    design : Design
        A design with a compensator.
    machine : MachineProfile
        One unit of the machine.
    units : list of int
        Slaved-unit counts to try, fewest first.
    form, method : str
        A form of FORMS and a reduction of METHODS, or "auto" for every one.
    orders : list of int, optional
        Only these orders (default: every order).
    fast_kept : bool
        :func:`whole_law` first, whatever ``orders`` (when there is one).

    Returns
    -------
    list of Fit
        In the order of :func:`laws`, each form within.
    """
    forms = FORMS if form == "auto" else (form,)
    wanted = [(o, m, law) for o, m, law in laws(design, machine, method) if orders is None or o in orders]
    whole = whole_law(design, machine) if fast_kept else None
    out = []
    for order, m, law in ([whole] if whole else []) + wanted:
        dm = comp.margins(design, law)  # the law's own: the same in every form
        out += [try_fit(design, order, m, law, f, machine, units, dm) for f in forms]
    return out


def best(candidates: list[Fit], designed: Margins | None = None) -> Fit | None:
    """Of the realisations that fit with a stable dialled loop and no amplifier past the reference
    over the scaling excursions: the cheapest (Fit.key) of those that keep KEEP_PM_SHARE of
    ``designed``'s phase margin (the design's loop), else the cheapest of the highest order."""
    ok = [f for f in candidates if f.netlist is not None and f.holds_dialled and f.peak_fraction <= 1.0]
    if not ok:
        return None
    keep = [f for f in ok if keeps_margin(f, designed)] if designed is not None else []
    if keep:
        return min(keep, key=Fit.key)
    top = max(f.order for f in ok)
    return min((f for f in ok if f.order == top), key=Fit.key)
