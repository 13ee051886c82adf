"""What identify makes of a bench whose cart a DC motor drives by voltage (patchgen.plant.drive).

There the force is F = K_U u_c - b s_dot with K_U = amp_gain x a, and the rotor adds M_drive to the
cart's mass; a, b and M_drive follow from the motor's figures (a data sheet's), which no standard
test separates. What the tests do measure:

- the held cart's force per command volt (actuator_step): K_U itself. The bench profile of a
  dc_motor takes K_U from the motor, so the profile keeps the base profile's figures and writes
  the measured K_U as the amplifier's gain, amp_gain = K_U / a: the simulated force per volt is
  then the measured one. A check says whether the figures' own K_U lies within the measurement.
- the coast-down, amplifier on at 0 V: the total damping over the moving mass,
  (b_VF + b) / (M + m + M_drive). The masses give M + m, the figures M_drive, so the total damping
  is identified; b_VF is that total less the back-EMF's b computed from the figures (b has no
  interval of its own: the report says so).

The motor's figures, its inductance and the amplifier's limit come from the base profile; the force
limit follows from them (a x V_limit), as the profile's validation has it.
"""

from __future__ import annotations

import numpy as np

from patchgen.identify import lsq
from patchgen.identify.estimate import LSQ_HAC, Z_REJECT, Check, Estimate, Panel, Parameter, TestFit, normal
from patchgen.identify.lag_grid import dead_zone
from patchgen.inputs.drive_fields import amp_gain_of, motor_of
from patchgen.plant.drive import MOTOR_PARAMETER_NAMES, DCMotor
from patchgen.profiles.bench import BenchProfile

TOTAL_DAMPING = "damping_total"  # result.extra's key for b_VF + b


def figures(base: BenchProfile, origin_of) -> dict:
    """The base profile's motor figures, inductance and amplifier limit as profile entries
    (``actuator.<name>`` -> Parameter, built by ``origin_of(value, unit)``)."""
    act = base.actuator
    out = {}
    for name in (*MOTOR_PARAMETER_NAMES, "L_m", "V_limit"):
        value = getattr(act, name)
        if value is not None:
            out[f"actuator.{name}"] = origin_of(float(value), "V" if name == "V_limit" else "")
    return out


def actuator(result, base: BenchProfile) -> None:
    """Turn the generic actuator entries of ``result.bench`` into a dc_motor's: the measured K_U as
    the amplifier's gain (K_U and tau reported beside, in ``result.extra``), the figures from the base.

    Parameters
    ----------
    result : Identification
        What identify found, its ``actuator.*`` entries those of the step and ramp fits.
    base : BenchProfile
        The base profile, a dc_motor's.
    """
    motor = motor_of(base.actuator)
    a = motor.force_per_volt()
    own = amp_gain_of(base.actuator) * a
    origin = f"base profile {result.base}"
    bench = result.bench
    K = bench.pop("actuator.K_U")
    tau = bench.pop("actuator.tau")
    bench.pop("actuator.force_limit_N", None)
    dead = bench.pop("actuator.dead_zone_V")
    bench["actuator.model"] = Parameter("dc_motor", "", None, origin)
    bench.update(figures(base, lambda v, unit: Parameter(v, unit, None, f"{origin} (the " + (
        "amplifier's limit)" if unit == "V" else "motor's figures)"))))
    if K.estimate is not None:
        e = K.estimate
        result.extra["K_U"] = e
        if tau.estimate is not None and tau.value > 0:
            result.extra["tau (held cart)"] = tau.estimate
        gain = normal(e.value / a, e.se / a, "V/V", f"K_U / a, a = {a:.5g} N/V from the motor's figures; {e.method}",
                      e.source, e.dof)
        bench["actuator.amp_gain"] = Parameter(gain.value, "V/V", gain, f"{e.source}: the measured K_U / a")
        z = abs(e.value - own) / e.se if e.se > 0 else 0.0
        rejected = z > Z_REJECT
        text = (f"the motor's figures give K_U = amp_gain x a = {own:.5g} N/V; the held cart measured "
                f"{e.value:.5g} N/V, z = {z:.3g}: " +
                ("they differ (an efficiency, K_t or the amplifier's gain off its figure): the profile takes the "
                 "measured K_U as amp_gain" if rejected else "the figures hold"))
        result.checks.append(Check("the motor's force per volt", z, Z_REJECT, rejected, text))
        if rejected:
            result.warnings.append(text)
    else:
        bench["actuator.amp_gain"] = Parameter(amp_gain_of(base.actuator), "V/V", None, origin)
    bench["actuator.dead_zone_V"] = dead


def damping(result, motor: DCMotor, total: Estimate) -> None:
    """The plant's b_VF from the total damping a motor-driven coast-down measures: the total less
    the back-EMF's b from the motor's figures (``plant['b_VF']``; the total in ``result.extra``)."""
    b = motor.back_emf_damping()
    result.extra[TOTAL_DAMPING] = total
    value = total.value - b
    method = f"the total damping less the back-EMF's b = {b:.5g} kg/s (the motor's figures); {total.method}"
    est = normal(value, total.se, "kg/s", method, total.source, total.dof)
    if est.high < 0 or value < 0:
        result.warnings.append(f"the coast-down's total damping {total.value:.4g} kg/s is below the back-EMF's "
                               f"{b:.4g} kg/s from the motor's figures: the plant takes b_VF = 0 (are the motor's "
                               "figures, or the masses, right?)")
    result.plant["b_VF"] = Parameter(max(value, 0.0), "kg/s", est,
                                     f"{total.source}: total damping {total.value:.5g} kg/s (95 %: {total.low:.4g} "
                                     f"to {total.high:.4g}) less the back-EMF's {b:.5g} kg/s")


def moving_mass(motor: DCMotor | None) -> float:
    """The rotor's mass on the cart (kg; 0 without a motor)."""
    return 0.0 if motor is None else motor.referred_mass()



def fit_step_gain(rec) -> TestFit:
    """The held cart's step test on a motor without an electrical lag (L_m = 0): the force is the
    command's, F = K_U v + F0 with v the command after the dead zone held over the sample interval,
    by least squares with the sandwich covariance; the score test of a lag (an inductance the
    figures leave out) is reported.

    Parameters
    ----------
    rec : Recording
        An ``actuator_step`` recording (t_s, u_c_V, force_N).

    Returns
    -------
    TestFit
        Estimates K_U (N/V), dead_zone (V) and gauge_zero (N); notes ``model: gain``.
    """
    t, u, f = rec.columns["t_s"], rec.columns["u_c_V"], rec.columns["force_N"]
    dt = rec.dt
    held = np.concatenate([u[:1], u[:-1]])  # the command over the step that ends at each sample
    model = lambda p: p[0] * dead_zone(held, p[1]) + p[2]  # noqa: E731
    K0 = float(np.polyfit(held, f, 1)[0])
    fit = lsq.fit(lambda p: model(p) - f, np.array([K0, 0.01, 0.0]),
                  np.array([1e-2 * max(abs(K0), 1e-3), 1e-2, 1e-2 * max(abs(K0), 1e-3)]),
                  bounds=([-np.inf, 0.0, -np.inf], np.inf))
    K, dz = fit.p[0], fit.p[1]
    v = dead_zone(held, dz)
    z = fit.score_test(-K * np.diff(v, prepend=v[0]) / dt)
    lag = abs(z) > Z_REJECT
    checks = [Check("no lag", abs(z), Z_REJECT, lag,
                    f"score z = {z:.3g} for a lag: " + ("the data show one (an inductance the motor's figures leave "
                                                        "out: L_m = tau R_m)" if lag else
                                                        "the force follows the command within a sample, as the "
                                                        "motor's figures have it"))]
    est = {name: normal(fit.p[i], fit.se(i), unit, LSQ_HAC, rec.source)
           for i, (name, unit) in enumerate((("K_U", "N/V"), ("dead_zone", "V"), ("gauge_zero", "N")))}
    fitted = model(fit.p)
    return TestFit(rec.source, rec.test, est, checks, notes=["model: gain"], title="actuator step: motor, cart held",
                   panels=[Panel(t, f, fitted, "force (N)"), Panel(t, u, None, "u_c (V)"),
                           Panel(t, f - fitted, None, "residual (N)")])
