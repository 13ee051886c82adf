"""Quanser's QUBE-Servo 2 with its rotary pendulum module, as a RotaryParams and the figures of
its sensors and drive, each with its source; the ones no public figure gives are marked assumed.

Sources: the QUBE-Servo 2 User Manual's table of system parameters (motor, links, encoders) and
the rotary pendulum workbook's model and parameter script (qube2_rotpen_param.m: damping, gravity,
the rods' inertias).
"""

from __future__ import annotations

import math

from patchgen.plant.rotary_equations import RotaryParams

# Assumed: the arm turns half a turn either way before the pendulum encoder's cable winds up (no
# public figure; measure it on the bench)
ARM_LIMIT_RAD = math.pi

QUBE_SERVO_2 = RotaryParams(
    R_m=8.4,  # ohm, motor terminal resistance (user manual)
    k_t=0.042,  # N m/A, motor torque constant (user manual)
    k_m=0.042,  # V s/rad, motor back-EMF constant (user manual)
    m_r=0.095,  # kg, rotary arm (user manual)
    L_r=0.085,  # m, rotary arm's length, the motor's axis to the pendulum's pivot (user manual)
    m_p=0.024,  # kg, pendulum link (user manual)
    L_p=0.129,  # m, pendulum link's length (user manual)
    # N m s/rad, about: the workbook's script's figures, "tuned heuristically" to a QUBE's response
    D_r=1.5e-3,
    D_p=5e-4,
    g=9.81,  # m/s^2, the workbook's figure
    # assumed: l_r, J_r, l_p and J_p left out, so each link is a uniform rod (inertia m L^2 / 12
    # about its centre), the arm pivoted at its end (l_r = L_r / 2) and the pendulum at the arm's
    # tip; the workbook's script takes the arm's inertia about the motor's axis as m_r L_r^2 / 12,
    # an arm pivoted at its centre (l_r = 0), a quarter of this one's
    alpha_limit=ARM_LIMIT_RAD,
)

ENCODER_COUNTS_PER_REV = 2048  # both encoders: 512 lines, 2048 counts a turn in quadrature (user manual)
ENCODER_STEP_RAD = 2.0 * math.pi / ENCODER_COUNTS_PER_REV  # the angle one count stands for
# V, either way: the motor voltage the pendulum labs' controllers saturate at (not the amplifier's rating)
VOLTAGE_LIMIT_V = 10.0
