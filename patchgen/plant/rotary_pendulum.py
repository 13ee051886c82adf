"""The rotary (Furuta) pendulum as a plant model describes itself: its states, its input, its
parameters (unit, physical bounds, default, meaning) and the roles a few of them play, in the
shape of patchgen.plant.cart_pendulum, so that a layer above can ask either plant the same
questions.

A DC motor turns an arm about a vertical axis; at the arm's tip a pendulum swings about the arm's
own axis. The equations are patchgen.plant.rotary_equations (numpy) and
patchgen.plant.rotary_compiled (numba); a QUBE-Servo 2's figures are patchgen.plant.qube_servo2.
patchgen.plant.plant_model gathers these for the layers above (ROTARY).
"""

from __future__ import annotations

import math

from patchgen.plant.cart_pendulum import Parameter, State

NAME = "rotary-pendulum"  # as a spec's [plant] model names it
WHAT = "a pendulum on an arm turned by a DC motor (Furuta's; a Quanser QUBE-Servo 2)"
BODY = "arm"  # what the position is of, as a sentence names it

STATES = (
    State("alpha", "rad", "arm angle about the motor's axis, positive the way a positive motor voltage turns it"),
    State("theta", "rad", "pendulum angle from upright, positive when its tip leans the way +alpha moves the "
          "arm's tip"),
    State("alpha_dot", "rad/s", "arm angular velocity"),
    State("theta_dot", "rad/s", "pendulum angular velocity"),
)
STATE_NAMES = tuple(s.name for s in STATES)
STATE_UNITS = {s.name: s.unit for s in STATES}
INPUT, INPUT_UNIT = "V_m", "V"  # the motor's armature voltage
INPUT_NOUN, INPUT_WHAT = "motor voltage", "voltage on the arm's motor"  # a table's heading; a control law's note

POSITION = "alpha"  # the state the cable's wind-up and a step command act on
ANGLE = "theta"  # the state whose excursion past the fall angle ends a run
RATE_OF = {"alpha": "alpha_dot", "theta": "theta_dot"}  # each position-like state's rate
POSITION_OF = {rate: position for position, rate in RATE_OF.items()}  # the position a rate is the rate of
# What the bench's sensors read: an encoder on the motor's shaft and one at the pendulum's pivot.
# No tachometer: both rates are the patch's to find (differentiators or an estimator). A bench with
# a tachometer on the motor may read the arm's rate too (MEASURABLE)
MEASURED = (POSITION, ANGLE)
MEASURABLE = (POSITION, ANGLE, RATE_OF[POSITION])
ESTIMATED_RATES = (RATE_OF[POSITION], RATE_OF[ANGLE])
SENSOR_LABELS = dict(zip(MEASURED, ("arm encoder", "pendulum encoder")))
# How a patch sheet speaks of the plant (as patchgen.plant.cart_pendulum's)
AT_REST = "the arm held at its centre, the pendulum hanging"
LIMIT_EVENT = "cable wound up"  # what ends a run at the position's limit, as a table heads it
KEPT_INSIDE = "the arm short of its cable's wind-up"  # what a held run kept, beside the pendulum up
BY_HAND = "the arm or the pendulum"
HAND_WORDS = {POSITION: "turn the arm toward +α", ANGLE: "lean the pendulum toward +α"}
SIGN_WORDS = ("+α is the way a positive u_c turns the arm; θ is positive when the pendulum leans the way +α moves "
              "the arm's tip.")

# A bench-sized rotary pendulum. l_r, J_r, l_p and J_p have no number for a default: left out, each
# is a uniform rod's, from its mass and length (FROM_ROD; patchgen.plant.rotary_equations.RotaryParams)
PARAMETERS = (
    Parameter("m_r", "kg", 1e-3, 10, None, "rotary arm's mass, kg (1 g to 10 kg)"),
    Parameter("L_r", "m", 0.01, 2, None, "arm length, the motor's axis to the pendulum's pivot, m (1 cm to 2 m)"),
    Parameter("m_p", "kg", 1e-3, 10, None, "pendulum mass, kg (1 g to 10 kg)"),
    Parameter("L_p", "m", 0.01, 2, None, "pendulum length, pivot to tip, m (1 cm to 2 m)"),
    Parameter("D_r", "N m s/rad", 0, 1, None, "arm's viscous damping at the motor's axis, N m s/rad"),
    Parameter("D_p", "N m s/rad", 0, 1, None, "pendulum's viscous damping at its pivot, N m s/rad"),
    Parameter("R_m", "ohm", 1e-3, 1e3, None, "motor's armature resistance, ohm"),
    Parameter("k_t", "N m/A", 1e-5, 10, None, "motor's torque constant, N m/A"),
    Parameter("k_m", "V s/rad", 1e-5, 10, None, "motor's back-EMF constant, V s/rad (equal to k_t in SI for an "
              "ideal motor)"),
    Parameter("g", "m/s^2", 1, 30, 9.81, "gravity, m/s^2 (the Moon's 1.6 to Jupiter's 25; 9.81 is Quanser's "
              "figure)", uncertain=False),
    Parameter("l_r", "m", 0, 2, None, "the motor's axis to the arm's centre of mass, m (left out: L_r / 2, a "
              "uniform arm pivoted at its end; 0 for one pivoted at its centre)"),
    Parameter("J_r", "kg m^2", 0, 10, None, "arm's moment of inertia about its centre of mass, about an axis "
              "parallel to the motor's, kg m^2 (left out: m_r L_r^2 / 12, a uniform rod)"),
    Parameter("l_p", "m", 1e-3, 2, None, "the pendulum's pivot to its centre of mass, m (left out: L_p / 2, a "
              "uniform rod)"),
    Parameter("J_p", "kg m^2", 0, 10, None, "pendulum's moment of inertia about its centre of mass, across "
              "the rod, kg m^2 (left out: m_p L_p^2 / 12, a uniform rod; none about its own long axis)"),
    Parameter("alpha_limit", "rad", 0.1, math.inf, math.inf, "the arm angle either way past which the "
              "pendulum encoder's cable winds up, rad (left out: a slip ring, nothing winds up)", uncertain=False),
)
PARAMETER_NAMES = tuple(p.name for p in PARAMETERS)
FROM_ROD = ("l_r", "J_r", "l_p", "J_p")  # no default number: a uniform rod's when left out
REQUIRED = tuple(p.name for p in PARAMETERS if p.default is None and p.name not in FROM_ROD)
UNCERTAIN = tuple(p.name for p in PARAMETERS if p.uncertain)  # what a sweep or a sensitivity may put off
OPTIONAL = FROM_ROD  # left out, a uniform rod's
STEP = 0.3  # rad: sims/qube-arm-step.toml's step, over which a patch's amplitudes are scaled
