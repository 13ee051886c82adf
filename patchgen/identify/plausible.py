"""Each recording's estimates checked against what a bench profile and a plant table take.

A fit that runs can still give a value no profile holds (a force gauge read in another unit, a
clock in milliseconds, a pot wired backwards): the recording and the column it came from are
named, before any value is combined or written. The bounds are the profiles' own
(patchgen.profiles.bench, patchgen.inputs.spec), read off their fields.
"""

from __future__ import annotations

from patchgen.identify.estimate import TestFit
from patchgen.inputs.errors import InputError
from patchgen.inputs.spec import PlantSpec
from patchgen.profiles.bench import BenchActuator, BenchSensors


def field_bounds(model: type, name: str) -> tuple[float, float]:
    """The [low, high] a model's field takes (its Ge/Gt and Le/Lt metadata; open sides infinite)."""
    lo, hi = -float("inf"), float("inf")
    for m in model.model_fields[name].metadata:
        lo = getattr(m, "ge", None) if getattr(m, "ge", None) is not None else getattr(m, "gt", lo)
        hi = getattr(m, "le", None) if getattr(m, "le", None) is not None else getattr(m, "lt", hi)
    return float(lo), float(hi)


# estimate -> (what it is, model and field it becomes, the column it is read from, what to look at)
CHECKED = {
    "K_U": ("the force per volt K_U", BenchActuator, "K_U", "force_N", "is force_N in newtons and u_c_V in volts, "
            "both the same way round?"),
    "tau": ("the lag tau", BenchActuator, "tau", "force_N", "is t_s in seconds, u_c_V the command as applied?"),
    "dead_zone": ("the dead zone", BenchActuator, "dead_zone_V", "u_c_V", "does the command leave it?"),
    "K_s": ("the position pot's constant", BenchSensors, "s", "s_V", "is s_m in metres, the pot connected the "
            "right way round?"),
    "K_theta": ("the angle pot's constant", BenchSensors, "theta", "theta_V", "is theta_rad in radians, the pot "
                "connected the right way round?"),
    "l": ("the effective length l", PlantSpec, "l", "theta_V", "is t_s in seconds?"),
    "c": ("the pendulum's friction c", PlantSpec, "c", "theta_V", "is t_s in seconds?"),
}


def _refuse(fit: TestFit, column: str, what: str, value: float, unit: str, lo: float, hi: float,
            hint: str) -> InputError:
    return InputError(fit.source, column, f"gives {what} = {value:.4g} {unit}, outside the {lo:g} to {hi:g} "
                                          f"{unit} a bench or plant takes: {hint}")


def check_fit(fit: TestFit, k_s: float, total_mass: float | None) -> None:
    """Refuse a fit any of whose estimates no profile or plant table would take.

    Parameters
    ----------
    fit : TestFit
        One recording's fit.
    k_s : float
        The position pot's constant (V/m), which turns a coast-down's rho into the tachometer's.
    total_mass : float or None
        M + m (kg) when weighed, which turns a coast-down's decay rate into b_VF.
    """
    for name, (what, model, key, column, hint) in CHECKED.items():
        e = fit.estimates.get(name)
        if e is None:
            continue
        lo, hi = field_bounds(model, key)
        if not lo <= e.value <= hi:
            raise _refuse(fit, column, what, e.value, e.unit, lo, hi, hint)
    rho, decay = fit.estimates.get("rho"), fit.estimates.get("decay")
    if fit.test == "coast_down" and rho is not None:
        lo, hi = field_bounds(BenchSensors, "s_dot")
        k = k_s / rho.value if rho.value else float("inf")
        if not lo <= k <= hi:
            raise _refuse(fit, "s_dot_V", "the tachometer's constant K_s / rho", k, "V/(m/s)", lo, hi,
                          "are s_V and s_dot_V the same way round?")
    if fit.test == "coast_down" and decay is not None and total_mass is not None:
        lo, hi = field_bounds(PlantSpec, "b_VF")
        b = decay.value * total_mass
        if not lo <= b <= hi:
            raise _refuse(fit, "s_dot_V", "the viscous friction b_VF", b, "kg/s", lo, hi, "is t_s in seconds?")
