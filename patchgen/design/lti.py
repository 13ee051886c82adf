"""The design as python-control systems: the plant, the compensator and the loop broken at the
plant input, each a ``control.StateSpace`` with named states, inputs and outputs.

patchgen computes its gains, poles and margins with numpy and scipy; these functions hand the same
objects to python-control so that a user can take a design further (Bode and Nyquist plots, disk
margins, step responses, other interconnections) without rebuilding the matrices by hand. The
``control`` package is imported only when one of them is called, so ``import patchgen`` and the
command line stay fast.

Sign conventions (docs/api.md):

- the control law is u = -K x, u the force command on the cart in newtons;
- the compensator maps the signals it reads (s, theta, s_dot for every estimator patchgen builds;
  every plant state for plain state feedback) to u itself, minus sign included, so the physical
  loop is the *positive* interconnection ``feedback(plant_ss(d), compensator_ss(d), sign=+1)``;
- the loop broken at the plant input takes the force injected there and returns the force the
  compensator commands, negated: L(s) = -C(s) P(s), K (sI - A)^-1 B for the state-feedback law.
  Unity *negative* feedback ``feedback(loop_ss(d), 1)`` closes it, as ``control.stability_margins``
  assumes, and its margins are the ones patchgen reports;
- the closed loop ``closed_loop_ss(d)`` is driven by a force disturbance at the plant input.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from patchgen.design.controller import Controller
from patchgen.design.lqg import Design, design_on, loop_with_controller
from patchgen.inputs.drive_fields import motor_of
from patchgen.inputs.spec import DesignSpec, load_spec

if TYPE_CHECKING:  # pragma: no cover - for annotations only
    import control

LOOP_INPUT = "u"
LOOP_OUTPUT = "minus_u_c"


def _plant_part(d: Design) -> tuple[list[int], tuple[str, ...]]:
    """Indices and names of the model's states that belong to the plant (no integral states)."""
    keep = [i for i, s in enumerate(d.model.states) if not s.startswith("int_")]
    return keep, tuple(d.model.states[i] for i in keep)


def _state_feedback_controller(d: Design) -> Controller:
    """u = -K x as a compensator reading every plant state: the integral states are its own."""
    model, K = d.model, d.K
    keep, _ = _plant_part(d)
    idx = [i for i, s in enumerate(model.states) if s.startswith("int_")]
    Ac = model.A[np.ix_(idx, idx)]
    Bc = model.A[np.ix_(idx, keep)]
    Cc = -K[:, idx]
    Dc = -K[:, keep]
    return Controller(tuple(model.states[i] for i in idx), Ac, Bc, Cc, Dc)


def _controller(d: Design) -> tuple[Controller, tuple[str, ...]]:
    """The implemented law and the signals it reads."""
    if d.controller is not None:
        return d.controller, d.model.measured
    return _state_feedback_controller(d), _plant_part(d)[1]


def plant_ss(design: Design, outputs: str | tuple[str, ...] | None = None,
             input: Literal["u", "u_c", "V_m"] = "u") -> control.StateSpace:
    """The plant the compensator drives, as a named ``control.StateSpace``.

    Parameters
    ----------
    design : Design
        A design from :func:`patchgen.design.lqg.design` or :func:`load_design`.
    outputs : str or tuple of str, optional
        Plant states to output (``"s"`` for the transfer function s/u, say). By default the
        signals the compensator reads: s, theta, s_dot when the design has an estimator, every
        plant state for plain state feedback.
    input : {"u", "u_c", "V_m"}
        The input's unit: ``"u"`` the force command (N); ``"u_c"`` the command voltage (V, u =
        K_U u_c); ``"V_m"`` the motor's voltage (V) of a design driven by a ``dc_motor``, as a
        lab driving its cart by voltage (a Quanser IP02) states its model.

    Returns
    -------
    control.StateSpace
        States s, theta, s_dot, theta_dot (SI units) and, when the design models the actuator,
        ``actuator``; input named as ``input``; outputs named by state. The design's
        integral states are not part of the plant: they are integrators in the compensator. A
        dc_motor's rotor and back-EMF are in A (patchgen.plant.drive).

    Notes
    -----
    This is the design model (eq. 2.28 plus the actuator model of the spec), the same A and B the
    Riccati equations were solved with, restricted to the plant's states.
    """
    import control

    keep, names = _plant_part(design)
    if outputs is None:
        outputs = _controller(design)[1]
    outputs = (outputs,) if isinstance(outputs, str) else tuple(outputs)
    unknown = [o for o in outputs if o not in names]
    if unknown:
        raise ValueError(f"not plant states: {', '.join(unknown)} (plant states: {', '.join(names)})")
    A = design.model.A[np.ix_(keep, keep)]
    B = design.model.B[keep] * _newtons_per(design, input)
    C = np.zeros((len(outputs), len(keep)))
    for r, o in enumerate(outputs):
        C[r, names.index(o)] = 1.0
    return control.ss(A, B, C, np.zeros((len(outputs), 1)), states=list(names), inputs=[input],
                      outputs=list(outputs), name=f"{design.spec.name}_plant")


def _newtons_per(design: Design, unit: str) -> float:
    """The force command (N) per unit of ``unit``: 1 for u, K_U for u_c, a for a motor's V_m."""
    if unit == "u":
        return 1.0
    if unit == "u_c":
        return design.spec.actuator.K_U
    if unit == "V_m":
        motor = motor_of(design.spec.actuator)
        if motor is None:
            raise ValueError(f"input 'V_m' is a motor's voltage: {design.spec.name}'s actuator is "
                             f"{design.spec.actuator.model}, not a dc_motor")
        return motor.force_per_volt()
    raise ValueError(f"input must be 'u', 'u_c' or 'V_m' (got {unit!r})")


def compensator_ss(design: Design) -> control.StateSpace:
    """The implemented control law, from the signals it reads to the force command u.

    Parameters
    ----------
    design : Design
        As for :func:`plant_ss`.

    Returns
    -------
    control.StateSpace
        Inputs: s, theta, s_dot for a Kalman estimator, a differentiator or a reduced observer
        (each with the integrators of the spec's integral states); every plant state for plain
        state feedback.
        Output ``u``, the force on the cart in newtons *including* the minus sign of u = -K x, so
        the closed loop is ``control.feedback(plant_ss(d), compensator_ss(d), sign=+1)``.
        States named as the design names them (``xhat_*`` estimates, ``int_*`` integrators,
        ``dfilt_theta`` the differentiator's filter, ``z_*`` reduced-observer states).
    """
    import control

    ctl, reads = _controller(design)
    return control.ss(ctl.Ac, ctl.Bc, ctl.Cc, ctl.Dc, states=list(ctl.states), inputs=list(reads),
                      outputs=[LOOP_INPUT], name=f"{design.spec.name}_compensator")


def loop_ss(design: Design, law: Literal["compensator", "lqr"] | None = None) -> control.StateSpace:
    """The loop broken at the plant input, whose margins patchgen reports.

    Parameters
    ----------
    design : Design
        As for :func:`plant_ss`.
    law : {"compensator", "lqr"}, optional
        ``"lqr"``: the full state feedback u = -K x on the design model (integral and actuator
        states included), the loop of ``design.lqr_margins``. ``"compensator"``: the law as
        implemented (Kalman estimator after loop transfer recovery, differentiator or observer),
        the loop of ``design.lqg_margins``. By default the compensator; a design without an
        estimator has no other law than the state feedback, and both give its LQR loop.

    Returns
    -------
    control.StateSpace
        Input ``u`` (force injected at the plant input, N), output ``minus_u_c`` (the force the
        compensator then commands, negated). Closed by unity negative feedback,
        ``control.feedback(L, 1)``, as ``control.stability_margins`` expects; its closed-loop
        poles are those of the plant under the law. The plant is open-loop unstable, so the loop
        has a lower gain margin: read margins with that in mind (docs/api.md).
    """
    import control

    law = law or "compensator"
    if law not in ("compensator", "lqr"):
        raise ValueError(f"law must be 'compensator' or 'lqr' (got {law!r})")
    if design.controller is None:
        law = "lqr"
    model = design.model
    if law == "lqr":
        A, B, C, states = model.A, model.B, design.K, model.states
    else:
        A, B, C = loop_with_controller(model, design.controller)
        states = _plant_part(design)[1] + design.controller.states
    return control.ss(A, B, C, np.zeros((1, 1)), states=list(states), inputs=[LOOP_INPUT],
                      outputs=[LOOP_OUTPUT], name=f"{design.spec.name}_loop_{law}")


def closed_loop_ss(design: Design) -> control.StateSpace:
    """The plant under the implemented law, driven by a force disturbance at the plant input.

    Parameters
    ----------
    design : Design
        As for :func:`plant_ss`.

    Returns
    -------
    control.StateSpace
        Input ``d``, a force added to the command at the plant input (N), so that a step is a
        push on the cart; outputs every plant state (``s``, ``theta``, ``s_dot``, ``theta_dot``
        and ``actuator`` if modelled) and the command ``u`` (N); states those of the plant then
        the compensator. It equals ``control.feedback(plant_ss(d), compensator_ss(d), sign=+1)``
        but keeps the names, which python-control's ``feedback`` replaces by generic ones.
    """
    import control

    keep, names = _plant_part(design)
    ctl, reads = _controller(design)
    Ap, Bp = design.model.A[np.ix_(keep, keep)], design.model.B[keep]
    Cy = np.zeros((len(reads), len(keep)))
    for r, name in enumerate(reads):
        Cy[r, names.index(name)] = 1.0
    n, nc = len(keep), ctl.Ac.shape[0]
    A = np.block([[Ap + Bp @ ctl.Dc @ Cy, Bp @ ctl.Cc], [ctl.Bc @ Cy, ctl.Ac]])
    B = np.vstack([Bp, np.zeros((nc, 1))])
    C = np.vstack([np.hstack([np.eye(n), np.zeros((n, nc))]), np.hstack([ctl.Dc @ Cy, ctl.Cc])])
    return control.ss(A, B, C, np.zeros((n + 1, 1)), states=list(names + ctl.states), inputs=["d"],
                      outputs=[*names, LOOP_INPUT], name=f"{design.spec.name}_closed_loop")


def load_design(spec: str | Path | DesignSpec, *, rho: float | None = None) -> Design:
    """Load a spec (a shipped design's name, a file, or a spec object) and design it.

    Parameters
    ----------
    spec : str, Path or DesignSpec
        ``"thesis-case1"`` and the other shipped names, a TOML file, or an already loaded spec.
    rho : float, optional
        Replace the spec's loop-transfer-recovery factor (Kalman designs only): ``rho=1`` gives
        the plain LQG loop before recovery, whose poor margins are the reason for LTR.

    Returns
    -------
    Design
        As ``patchgen design SPEC`` computes it: a differentiator without a roll-off of its own
        takes the machine profile's, a filtered differentiator or a reduced observer is shaped
        for the noise of the bench profile the spec names.
    """
    from patchgen.profiles.bench import load_bench
    from patchgen.profiles.machine import load_machine

    if not isinstance(spec, DesignSpec):
        spec = load_spec(spec)
    if rho is not None:
        if spec.estimator.kind != "kalman":
            raise ValueError(f"rho applies to a Kalman estimator; {spec.name} has {spec.estimator.kind!r}")
        if not rho > 0:
            raise ValueError(f"rho must be positive (got {rho!r})")
        spec = spec.model_copy(update={"estimator": spec.estimator.model_copy(update={"rho": float(rho)})})
    return design_on(spec, load_machine(spec.machine, spec.path), load_bench(spec.bench, spec.path))
