"""The cart's drive when it is a DC motor driven by voltage (a Quanser IP02's): a motor with a
gear and a pinion on the track's rack, its electrical lag negligible or stated.

With the armature's inductance neglected, the force on the cart is F = a V - b s_dot, and the
rotor, geared up, adds to the cart's mass (Quanser's IP02 equations):

    a = eta_g K_g eta_m K_t / (R_m r)              N per motor volt
    b = eta_g K_g^2 eta_m K_t K_m / (R_m r^2)      N s/m, the back-EMF's damping
    M_drive = eta_g K_g^2 J_m / r^2                kg, the rotor referred to the cart

With an inductance L_m the current lags the voltage: F' = (a V - b s_dot - F) / tau_e with
tau_e = L_m / R_m. Every other layer asks this module for a, b, M_drive and tau_e.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from patchgen.plant.cart_pendulum import Parameter

# The motor's figures, as a data sheet or Quanser's configuration files state them
MOTOR_PARAMETERS = (
    Parameter("R_m", "ohm", 1e-3, 1e3, None, "armature resistance, ohm"),
    Parameter("K_t", "N m/A", 1e-5, 10, None, "torque constant, N m/A"),
    Parameter("K_m", "V s/rad", 1e-5, 10, None, "back-EMF constant, V s/rad (equal to K_t in SI for an ideal motor)"),
    Parameter("K_g", "1", 0.01, 1e3, 1.0, "gear ratio, motor turns per pinion turn"),
    Parameter("J_m", "kg m^2", 0, 1, 0.0, "rotor's moment of inertia, kg m^2"),
    Parameter("r_pinion", "m", 1e-4, 1, None, "radius of the pinion that drives the cart, m"),
    Parameter("eta_g", "1", 0.01, 1, 1.0, "gearbox efficiency"),
    Parameter("eta_m", "1", 0.01, 1, 1.0, "motor efficiency"),
)
MOTOR_PARAMETER_NAMES = tuple(p.name for p in MOTOR_PARAMETERS)
INDUCTANCE = Parameter("L_m", "H", 0, 1, 0.0, "armature inductance, H (0: the current follows the voltage at once)")


@dataclass(frozen=True)
class DCMotor:
    """A DC motor, gear and pinion driving the cart (MOTOR_PARAMETERS; SI units)."""

    R_m: float
    K_t: float
    K_m: float
    r_pinion: float
    K_g: float = 1.0
    J_m: float = 0.0
    eta_g: float = 1.0
    eta_m: float = 1.0
    L_m: float = 0.0

    def force_per_volt(self) -> float:
        """a: the force on the cart per motor volt at standstill (N/V)."""
        return self.eta_g * self.K_g * self.eta_m * self.K_t / (self.R_m * self.r_pinion)

    def back_emf_damping(self) -> float:
        """b: the damping the back-EMF puts on the cart (N s/m)."""
        return self.eta_g * self.K_g ** 2 * self.eta_m * self.K_t * self.K_m / (self.R_m * self.r_pinion ** 2)

    def referred_mass(self) -> float:
        """M_drive: the rotor's inertia as a mass on the cart (kg)."""
        return self.eta_g * self.K_g ** 2 * self.J_m / self.r_pinion ** 2

    def electrical_lag(self) -> float:
        """tau_e = L_m / R_m (s): how long the current lags the voltage."""
        return self.L_m / self.R_m


def with_rotor(plant, motor: DCMotor | None):
    """The plant as the motor moves it: the rotor's referred mass added to the cart's."""
    if motor is None:
        return plant
    return replace(plant, M=plant.M + motor.referred_mass())


def driven(plant, motor: DCMotor | None):
    """The plant with the whole drive folded in (rotor mass, back-EMF damping): with the force
    a V on it, the plant of the motor's linear model (the inductance neglected)."""
    if motor is None:
        return plant
    return replace(with_rotor(plant, motor), b_VF=plant.b_VF + motor.back_emf_damping())
