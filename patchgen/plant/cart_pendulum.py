"""The cart-pendulum as a plant model describes itself: its states, its parameters (unit, physical
bounds, default, meaning) and the roles a few of them play for the layers above.

Every other layer asks this module for the plant's state names, units and parameter lists (the
spec's [plant] table is built from PARAMETERS, the bench's spread and the swing-up's sensitivity
take their names from here), so that the plant is said once. The equations are
patchgen.plant.equations (numpy) and patchgen.plant.compiled (numba), checked against each other
by the tests.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class State:
    """One state of the plant: its name, SI unit and what it is."""

    name: str
    unit: str
    what: str


@dataclass(frozen=True)
class Parameter:
    """One physical parameter: name, SI unit, inclusive physical bounds, default (None: required),
    what it is (with its bounds' reason), and whether it is a physical property of the bench that
    a sweep or a sensitivity study may put off (gravity and the track's length are not)."""

    name: str
    unit: str
    lo: float
    hi: float
    default: float | None
    what: str
    uncertain: bool = True


NAME = "cart-pendulum"  # as a spec's [plant] model names it
WHAT = "a pendulum on a cart driven along a track (Shaw's thesis; a Quanser IP02)"
BODY = "cart"  # what the position is of, as a sentence names it
INPUT, INPUT_UNIT = "F_U", "N"  # the force on the cart
INPUT_NOUN, INPUT_WHAT = "force", "force on the cart"  # a table's heading; a control law's note

STATES = (
    State("s", "m", "cart position, from the track's centre"),
    State("theta", "rad", "pendulum angle from upright"),
    State("s_dot", "m/s", "cart velocity"),
    State("theta_dot", "rad/s", "pendulum angular velocity"),
)
STATE_NAMES = tuple(s.name for s in STATES)
STATE_UNITS = {s.name: s.unit for s in STATES}

POSITION = "s"  # the state the limit switches and a step command act on
ANGLE = "theta"  # the state whose excursion past the fall angle ends a run
RATE_OF = {"s": "s_dot", "theta": "theta_dot"}  # each position-like state's rate
POSITION_OF = {rate: position for position, rate in RATE_OF.items()}  # the position a rate is the rate of
# What a lab's sensors read (the thesis's pots and tachometer; an IP02's encoders and filtered velocity):
# the pendulum's rate is the patch's to find (a differentiator or an estimator)
MEASURED = (POSITION, ANGLE, RATE_OF[POSITION])
MEASURABLE = MEASURED  # what a bench's sensors may read
ESTIMATED_RATE = RATE_OF[ANGLE]
# the instruments that read them on the thesis's bench, as a sheet names them (a spec may name its own)
SENSOR_LABELS = dict(zip(MEASURED, ("cart position pot", "pendulum angle pot", "motor tachometer")))
# How a patch sheet speaks of the plant to the person at the bench: the plant as it is held while
# the patch is set, what is moved by hand, how each hand-moved state is moved, and its signs
AT_REST = "the cart held at the centre of the track"
LIMIT_EVENT = "limit switch"  # what ends a run at the position's limit, as a table heads it
KEPT_INSIDE = "the cart inside the limit switches"  # what a held run kept, beside the pendulum up
BY_HAND = "the cart or the pendulum"
HAND_WORDS = {POSITION: "move the cart toward +s", ANGLE: "lean the pendulum toward +s"}
SIGN_WORDS = "+s is the way a positive u_c drives the cart; θ is positive when the pendulum leans toward +s."

# Table B.1's parameters, within the bounds of a bench-sized cart and pendulum (docs/spec.md)
PARAMETERS = (
    Parameter("M", "kg", 0.01, 100, None, "cart mass, kg (10 g to 100 kg)"),
    Parameter("m", "kg", 1e-3, 10, None, "pendulum mass, kg (1 g to 10 kg)"),
    Parameter("l", "m", 0.01, 10, None, "pivot to the pendulum's centre of mass, m (1 cm to 10 m; a point "
              "mass's length)"),
    Parameter("g", "m/s^2", 1, 30, 9.807, "gravity, m/s^2 (the Moon's 1.6 to Jupiter's 25)", uncertain=False),
    Parameter("b_VF", "kg/s", 0, 1000, None, "cart viscous friction, kg/s"),
    Parameter("c", "kg m^2/s", 0, 10, None, "pendulum rotational friction, kg m^2/s"),
    Parameter("d", "m", 0.05, 20, 1.090, "usable track length between the switches, m", uncertain=False),
    Parameter("J", "kg m^2", 0, 10, 0.0, "pendulum's moment of inertia about its centre of mass, kg m^2 (0: a point "
              "mass, as the thesis's; a rod of length L: m L^2 / 12)", uncertain=False),  # not yet swept or fitted
    Parameter("F_C", "N", 0, 1e3, 0.0, "cart Coulomb friction, N (0: viscous alone, as the thesis's; a linear design "
              "cannot see it, the bench's simulation has it)", uncertain=False),
)
PARAMETER_NAMES = tuple(p.name for p in PARAMETERS)
UNCERTAIN = tuple(p.name for p in PARAMETERS if p.uncertain)  # what a sweep or a sensitivity may put off
OPTIONAL = ()  # no parameter without a default number may be left out
STEP = 0.2  # m: sims/step-cart.toml's step, over which a patch's amplitudes are scaled
