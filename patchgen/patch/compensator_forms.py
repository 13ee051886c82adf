"""A compensator (patchgen.design.compensator) as integrators on the machine, in one of its
state-space forms, each state's voltage scaled for the amplitudes the loop reaches.

Forms of the stable part (the integral part is always one integrator of R y):

- ``modal``: real modal form; each real pole an integrator with its own output fed back (one pot),
  a complex pair two integrators coupled as a rotation; the rate on a state's own feedback is the
  pole itself, whatever the scaling, so the form fits when every pole is within the inputs' reach;
- ``observer``: observer canonical form of the single output u: the characteristic polynomial's
  coefficients on the first state's output, a chain of unit couplings, u from the first state
  alone (no pot on the output side), but the coefficients are the polynomial's (sensitive to the
  dial for higher orders);
- ``balanced``: balanced coordinates; every state feeds every other (n^2 coefficients), shown for
  its insensitivity, rarely the cheapest.

Scaling: state i's voltage is sigma_i x_i. The loop (design model and this compensator) is run from
the scaling excursions (the largest initial angle and cart step of the shipped scenarios) and
sigma_i is chosen so that the state's peak is AMPLITUDE of the reference (over the design model's
loop and, when it models the actuator, the loop with the actuator a pure gain as well); then lowered, by at most
EXACT_SPAN, to the largest sigma that makes one of the state's input or output coefficients equal
to an input weight exactly (that term needs no pot). A state whose output coefficients would
then pass what a gain stage carries is scaled to balance its inputs and outputs instead (_scale).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from patchgen.design.compensator import Compensator
from patchgen.design.lqg import Design
from patchgen.patch import large_gains
from patchgen.patch.realization import Block, Realization, Term
from patchgen.profiles.machine import MachineProfile

FORMS = ("modal", "observer", "balanced")
AMPLITUDE = 0.5  # a state's peak over the scaling excursions, as a fraction of the reference
EXACT_SPAN = 4.0  # the most a state's voltage is lowered to make a coefficient an exact weight
SCALING_THETA0_RAD = math.radians(10.0)  # offset-10deg, the shipped scenario with the largest angle
SCALING_HORIZON_S = 10.0  # long enough for every scenario's transient to settle (shipped sims: 10 s)
SCALING_STEP_S = 0.005
EXCURSION_CHUNK = 250  # steps between excursion_peaks' divergence tests (a speed choice only)
STAGE_SUFFIX = "_in"  # a staged block's summer (staged_blocks)
ROUNDING = 1e-9  # relative: a form's entry this small beside its matrix's largest is a transformation's noise


@dataclass(frozen=True)
class FormSystem:
    """The stable part in one form's coordinates: x' = A x + B y, u = C x (+ D y, + the integral)."""

    form: str
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray


def form_system(c: Compensator, form: str) -> FormSystem:
    """The stable part of ``c`` in ``form`` coordinates (see the module docstring)."""
    A, B, C = c.A, c.B, c.C
    n = A.shape[0]
    if n == 0 or form == "balanced":
        return FormSystem(form, A, B, C)
    if form == "modal":
        T = _modal_basis(A, C)
    elif form == "observer":
        O = np.vstack([C @ np.linalg.matrix_power(A, k) for k in range(n)])
        a = np.poly(A)[1:]  # s^n + a1 s^(n-1) + ... + an
        Ao = np.zeros((n, n))
        Ao[:, 0] = -a
        Ao[:-1, 1:] = np.eye(n - 1)
        Co = np.zeros((1, n))
        Co[0, 0] = 1.0
        Oo = np.vstack([Co @ np.linalg.matrix_power(Ao, k) for k in range(n)])
        T = np.linalg.solve(O, Oo)  # x = T z
    else:
        raise ValueError(f"form must be one of {', '.join(FORMS)} (got {form!r})")
    Ti = np.linalg.inv(T)
    return FormSystem(form, *(_clean(M) for M in (Ti @ A @ T, Ti @ B, C @ T)))


def _clean(M: np.ndarray) -> np.ndarray:
    """Entries that are rounding beside the matrix's largest set to 0 (a transformation's noise)."""
    M = M.copy()
    M[np.abs(M) < ROUNDING * np.abs(M).max(initial=0.0)] = 0.0
    return M


def _modal_basis(A: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Real modal basis: real eigenvectors, and (Re v, Im v) for each complex pair, slowest first; a
    real mode's state is its share of u (output coefficient 1) unless u does not see it."""
    lam, V = np.linalg.eig(A)
    order = np.lexsort((lam.imag, np.abs(lam)))
    cols: list[np.ndarray] = []
    done = np.zeros(len(lam), dtype=bool)
    for i in order:
        if done[i]:
            continue
        done[i] = True
        v = V[:, i]
        if abs(lam[i].imag) <= 1e-9 * max(1.0, abs(lam[i])):
            v = v.real if np.abs(v.real).max() >= np.abs(v.imag).max() else v.imag
            cv = (C @ v)[0]
            cols.append(v / cv if abs(cv) > ROUNDING * np.abs(C).max() * np.abs(v).max() else v / np.abs(v).max())
        else:
            if lam[i].imag < 0:
                v = v.conj()
            j = next(k for k in order if not done[k] and abs(lam[k] - lam[i].conj()) < 1e-9 * abs(lam[i]))
            done[j] = True
            cols += [v.real, v.imag]
    return np.column_stack(cols)


def scaling_plants(design: Design) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]]:
    """The plants a patch is scaled over: the design model's (its actuator model included) and the
    plant of eq. 2.28 with the actuator a pure gain (the loop as an ideal bench closes it), each as
    (A, B, C of the measured signals, state names)."""
    model = design.model
    keep = [i for i, s in enumerate(model.states) if not s.startswith("int_")]
    out = [(model.A[np.ix_(keep, keep)], model.B[keep], model.C[:, keep], [model.states[i] for i in keep])]
    plant = design.spec.plant_model
    if len(keep) > len(plant.states):
        Ap, Bp = plant.linear(design.plant)
        Cp = np.zeros((len(model.measured), len(plant.states)))
        names = list(plant.state_names)
        for r, m in enumerate(model.measured):
            Cp[r, names.index(m)] = 1.0
        out.append((Ap, Bp, Cp, names))
    return out


def peaks(design: Design, c: Compensator, fs: FormSystem) -> tuple[float, np.ndarray]:
    """The largest |x_I| and each |x_i| of the form's states over the scaling excursions (SI).

    The closed loop of each scaling plant (:func:`scaling_plants`) and the compensator (integral
    state and stable part in the form's coordinates) from theta = SCALING_THETA0_RAD and,
    separately, from the position at the plant's step (PlantModel.step), sampled every
    SCALING_STEP_S for SCALING_HORIZON_S.
    """
    m = fs.A.shape[0]
    ni = 0 if c.R is None else 1
    peak = np.zeros(ni + m)
    for Ap, Bp, Cp, names in scaling_plants(design):
        n = Ap.shape[0]
        R = c.R if c.R is not None else np.zeros((0, Cp.shape[0]))
        Cc = np.hstack([np.ones((1, ni)), fs.C])
        Acl = np.block([
            [Ap + Bp @ c.D @ Cp, Bp @ Cc],
            [np.vstack([R @ Cp, fs.B @ Cp]), sla.block_diag(np.zeros((ni, ni)), fs.A)],
        ])
        Cout = np.hstack([np.zeros((ni + m, n)), np.eye(ni + m)])
        peak = np.maximum(peak, excursion_peaks(Acl, Cout, excursions(design, names)))
    return (float(peak[0]) if ni else 0.0), peak[ni:]


def excursions(design: Design, names: list[str]) -> list[tuple[int, float]]:
    """The releases a patch is scaled over, as (state index in ``names``, initial value): the
    pendulum from SCALING_THETA0_RAD, and the position from the plant's step (the cart's 0.2 m)."""
    plant = design.spec.plant_model
    return [(names.index(plant.angle), SCALING_THETA0_RAD), (names.index(plant.position), plant.step)]


def excursion_peaks(Acl: np.ndarray, Cout: np.ndarray, where: list[tuple[int, float]]) -> np.ndarray:
    """The largest |Cout x| of the closed loop x' = Acl x released from each (state, value) of
    ``where`` separately (``excursions``), sampled every SCALING_STEP_S for SCALING_HORIZON_S (a run
    that diverges, past 1e12 or not finite, is taken up to and including its first such sample)."""
    Phi = sla.expm(Acl * SCALING_STEP_S)
    steps = int(round(SCALING_HORIZON_S / SCALING_STEP_S))
    peak = np.zeros(Cout.shape[0])
    xs = np.empty((steps, Acl.shape[0]))
    dot = np.dot
    for i, value in where:
        x = np.zeros(Acl.shape[0])
        x[i] = value
        done = 0
        # in chunks: the divergence test once per chunk, not once per step; the steps a chunk takes
        # past its first diverged sample are dropped, and may overflow without a word. Each step is
        # np.dot into its row: the same BLAS gemv as Phi @ x, bit for bit, at half the call overhead
        with np.errstate(over="ignore", invalid="ignore"):
            while done < steps:
                chunk = xs[done:min(done + EXCURSION_CHUNK, steps)]
                for row in chunk:  # each a view of its row, as chunk[k] is
                    x = dot(Phi, x, row)
                bad = ~np.isfinite(chunk).all(axis=1) | (np.abs(chunk).max(axis=1) > 1e12)
                if bad.any():
                    done += int(np.argmax(bad)) + 1
                    break
                done += chunk.shape[0]
        peak = np.maximum(peak, np.abs(xs[:done] @ Cout.T).max(axis=0, initial=0.0))
    return peak


def _scale(peak: float, reference: float, into: list[float], outof: list[float], weights, rate: float,
           reach: float) -> float:
    """sigma for one state: peak at AMPLITUDE of the reference (divided by the gain stage its own
    rate ``rate`` needs beyond the largest weight, and lower if an input coefficient, which grows
    with sigma, would pass the largest weight), then lowered by at most EXACT_SPAN so that a
    coefficient proportional to sigma (``into``: the factor) or to 1/sigma (``outof``) is a weight.

    A mode that is both fast and strongly coupled (thesis case 2's -76 +/- 76j pair) has input and
    output coefficients whose product no sigma changes; with its inputs at the largest weight its
    outputs would pass ``reach``, what a gain stage carries (the top gain squared). Such a state is
    scaled where the two balance (their geometric mean), a gain stage's reach on each side, and
    not lowered past where its outputs reach ``reach``."""
    top = AMPLITUDE * reference / max(1.0, rate / max(weights)) / peak if peak > 0 else 1.0
    biggest, out = max(into, default=0.0), max(outof, default=0.0)
    floor = 0.0
    if biggest > 0:
        cap = max(weights) / biggest
        if out > reach * cap:
            cap, floor = math.sqrt(out / biggest), out / reach
        top = min(top, cap)
    cands = [w / f for f in into if f > 0 for w in weights] + [f / w for f in outof if f > 0 for w in weights]
    ok = [s for s in cands if max(top / EXACT_SPAN, floor) <= s <= top * (1 + 1e-12)]
    return max(ok) if ok else top


def realize_compensator(design: Design, c: Compensator, form: str, machine: MachineProfile,
                        shrink: dict[str, float] | None = None, staged: bool = False,
                        scaled: tuple[FormSystem, tuple[float, np.ndarray]] | None = None) -> Realization:
    """The compensator in ``form`` as integrate blocks and the u_c summer, in machine volts.

    Parameters
    ----------
    design : Design
        Gives the sensors, K_U and the plant for the scaling run.
    c : Compensator
        The law (minimal or reduced).
    form : str
        One of FORMS.
    machine : MachineProfile
        Its time scale, reference and input weights.
    shrink : dict, optional
        A factor (below 1) on a state's voltage, by block name: for a state whose partial sum or
        gain stage would leave the reference (patchgen.patch.compensator_fit).
    staged : bool
        Each block with a coefficient above what one input carries sums its terms at 1/g on a
        summer of its own, taken back at g (:func:`staged_blocks`).
    scaled : (FormSystem, (float, ndarray)), optional
        The law in ``form`` and its :func:`peaks`, when the caller has them (one form is placed
        again with its states shrunk or staged; the excursions stay the same).

    Returns
    -------
    Realization
        Blocks ``int`` (the integral part), ``c1``... (the stable part's states) and ``u_c``.
    """
    spec = design.spec
    ks = spec.sensors.constants()
    y = list(c.inputs)
    KU, T, ref = spec.actuator.K_U, machine.time_scale_s, machine.reference_V
    weights = [float(w) for w in machine.input_weights]
    reach = large_gains.top_gain(machine) ** 2
    if scaled is None:
        fs = form_system(c, form)
        scaled = fs, peaks(design, c, fs)
    fs, (pI, px) = scaled
    shrink = shrink or {}
    n = fs.A.shape[0]
    blocks: list[Block] = []
    sig: dict[str, float] = {}
    if c.R is not None:
        into = [abs(T * c.R[0, k]) / ks[m] for k, m in enumerate(y)]
        sig["int"] = _scale(pI, ref * shrink.get("int", 1.0), into, [1.0 / KU], weights, 0.0, reach)
    names = [f"c{i + 1}" for i in range(n)]
    for i, nm in enumerate(names):
        into = [abs(T * fs.B[i, k]) / ks[m] for k, m in enumerate(y)]
        rate = T * max(np.abs(fs.A[i]).max(), np.abs(fs.A[:, i]).max())
        sig[nm] = _scale(px[i], ref * shrink.get(nm, 1.0), into, [abs(fs.C[0, i]) / KU], weights, rate, reach)

    if form == "modal":  # a complex pair's two states share one scale: its rotation stays balanced
        for i in range(n):
            for j in range(i + 1, n):
                if fs.A[i, j] and fs.A[j, i]:
                    sig[names[i]] = sig[names[j]] = min(sig[names[i]], sig[names[j]])

    def coeff(x: float) -> float:
        return next((math.copysign(w, x) for w in weights if math.isclose(abs(x), w, rel_tol=1e-9)), x)

    if c.R is not None:
        terms = tuple(Term(m, coeff(T * c.R[0, k] * sig["int"] / ks[m])) for k, m in enumerate(y) if c.R[0, k])
        blocks.append(Block("int", "integrate", terms, sig["int"], "N",
                            "integral action: the integral states as one integrator of the measurements"))
    for i, nm in enumerate(names):
        terms = [Term(names[j], coeff(T * fs.A[i, j] * sig[nm] / sig[names[j]])) for j in range(n) if fs.A[i, j]]
        terms += [Term(m, coeff(T * fs.B[i, k] * sig[nm] / ks[m])) for k, m in enumerate(y) if fs.B[i, k]]
        blocks.append(Block(nm, "integrate", tuple(terms), sig[nm], "N",
                            f"compensator state {i + 1} of {n} ({form} form)"))
    uterms = []
    if c.R is not None:
        uterms.append(Term("int", coeff(1.0 / (sig["int"] * KU))))
    uterms += [Term(nm, coeff(fs.C[0, i] / (sig[nm] * KU))) for i, nm in enumerate(names) if fs.C[0, i]]
    uterms += [Term(m, coeff(c.D[0, k] / (ks[m] * KU))) for k, m in enumerate(y) if c.D[0, k]]
    blocks.append(Block("u_c", "sum", tuple(uterms), 1.0, "V", "control voltage to the servo amplifier"))
    if staged:
        blocks = staged_blocks(blocks, max(weights) * machine.pot_max, machine.pot_resolution)
    plant = spec.plant_model
    notes = (f"compensator realised as one system: {c.method}, {c.order} states, {form} form; each state "
             f"scaled to at most {AMPLITUDE:g} of the reference over a {math.degrees(SCALING_THETA0_RAD):g} deg "
             f"release and a {plant.step:g} {plant.units[plant.position]} {plant.body} offset",)
    return Realization(spec.name, dict(ks), tuple(blocks), KU, spec.patch.below_resolution, notes,
                       dict(spec.sensors.labels), plant=spec.plant_model)


def staged_blocks(blocks: list[Block], top: float, resolution: float) -> list[Block]:
    """Each block with a coefficient above ``top`` (but within top squared) split in two: a summer
    ``<name>_in`` of its terms at 1/g, and the block itself taking that summer at g = largest / top.
    A term that 1/g would put below the dial's ``resolution`` stays on the block itself, at its
    own coefficient (it would otherwise be left out).

    A fast compensator mode needs its own rate and its couplings above one input's reach; a gain
    stage per signal (patchgen.patch.large_gains) costs an amplifier per signal, this costs one per
    block. The summer carries the block's input (for an integrator, its rate of change) over g:
    the amplitude check after placing (patchgen.patch.compensator_fit) sees it like any amplifier.
    """
    out: list[Block] = []
    for b in blocks:
        big = max((abs(t.coeff) for t in b.terms), default=0.0)
        if big <= top * (1 + 1e-12) or big > top * top:
            out.append(b)
            continue
        g = big / top
        per = "/s" if b.kind == "integrate" else ""
        fine = tuple(t for t in b.terms if abs(t.coeff) / g < resolution)
        out.append(Block(f"{b.name}{STAGE_SUFFIX}", "sum",
                         tuple(Term(t.signal, t.coeff / g) for t in b.terms if t not in fine),
                         b.volts_per_unit / g, f"{b.unit}{per}",
                         f"the input of {b.name} over {g:.4g}: its coefficients above {top:g} summed here"))
        out.append(Block(b.name, b.kind, (Term(f"{b.name}{STAGE_SUFFIX}", g),) + fine, b.volts_per_unit, b.unit,
                         b.purpose))
    return out


def coefficient_range(real: Realization, resolution: float) -> tuple[float, float]:
    """The smallest and largest coefficient magnitude of a realisation's terms (those the dial reaches)."""
    mags = [abs(t.coeff) for b in real.blocks for t in b.terms if abs(t.coeff) >= resolution / 2]
    return (min(mags), max(mags)) if mags else (0.0, 0.0)
