"""The design report as data: a JSON-ready dict of the design (gains, poles, zeros, estimator, margins);
its terminal tables are patchgen.render.design_tables'."""

from __future__ import annotations

import numpy as np

from patchgen.design.lqg import Design
from patchgen.design.margins import Margins
from patchgen.design.precision import significant_digits


def _c(v: complex) -> list[float]:
    return [float(np.real(v)), float(np.imag(v))]


def margins_dict(m: Margins | None) -> dict | None:
    """The margins as the design's JSON gives them (None stays None)."""
    if m is None:
        return None
    d = m.as_dict()
    return {k: d[k] for k in ("stable", "lower_gm", "lower_gm_db", "upper_gm", "upper_gm_db", "pm_deg",
                              "pm_freq", "delay_margin_s", "gain_crossovers", "phase_crossovers")}


def design_notes(d: Design) -> list[str]:
    """What the linear design leaves out, in words (the report prints them, the JSON carries them)."""
    a = d.spec.actuator
    if a.dead_zone_V:
        return [f"the dead zone ({a.dead_zone_V} V) is invisible to the linear design; the bench simulation "
                "includes it"]
    return []


def design_dict(d: Design) -> dict:
    """Everything a script wants from a design, JSON-serialisable. u = -K x."""
    spec = d.spec
    out = {
        "name": spec.name,
        "description": spec.description,
        "source": spec.source,
        "states": list(d.states),
        "control_law": f"u = -K x (u: {spec.plant_model.input_what}, {spec.plant_model.input_unit})",
        "A": d.model.A.tolist(),
        "B": d.model.B[:, 0].tolist(),
        "Q": d.Q.tolist(),
        "R": float(d.R[0, 0]),
        "K": [float(k) for k in d.K[0]],
        # how far each gain moves when the Riccati inputs move at rounding level, and the
        # significant digits that leaves fixed (0: not determined beyond its size)
        "K_spread": [float(v) for v in d.spread.K[0]],
        "K_digits": d.spread.K_digits(d.K),
        "open_loop_poles": [_c(p) for p in d.open_loop_poles],
        "closed_loop_poles": [_c(p) for p in d.closed_loop_poles],
        "zeros": {k: [_c(z) for z in v] for k, v in d.zeros.items()},
        "lqr_margins": margins_dict(d.lqr_margins),
        "actuator_model": spec.actuator.model,
        "actuator_K_U": spec.actuator.K_U,  # the plant's input (N, or motor V) per command volt
        "actuator_tau_s": None if spec.actuator.model == "gain" else spec.actuator.tau,
        "notes": design_notes(d),
    }
    if d.estimator is not None:
        e = d.estimator
        est = {"kind": e.kind, "states": list(e.states), "poles": [_c(p) for p in e.poles]}
        if e.kind == "kalman":
            est["L"] = e.L.tolist()
            if d.spread.L is not None:
                est["L_spread"] = d.spread.L.tolist()
                est["L_digits"] = [[significant_digits(float(v), float(u)) for v, u in zip(row, urow)]
                                   for row, urow in zip(e.L, d.spread.L)]
            est["rho"] = e.rho
            est["rho_tries"] = [{"rho": t.rho, "accepted": t.accepted, "margins": margins_dict(t.margins)}
                                for t in e.rho_tries]
            est["margins_rho1"] = margins_dict(e.margins_rho1)
        else:
            est["rolloff_s"] = e.rolloff_s
        out["estimator"] = est
        out["lqg_margins"] = margins_dict(d.lqg_margins)
    return out
