"""Tests that give summary figures rather than a recording: a small TOML file whose ``test`` key
names the test.

::

    test = "incline"            # thesis B.2.1: the cart slides down the tilted track
    angle_deg = 9.5
    distance_m = 1.325
    time_s = 1.460
    mass_kg = 3.876             # M + m, pendulum fixed to the cart

    test = "masses"             # thesis B.1: weighed and measured
    M_kg = 3.552
    m_kg = 0.324

Every figure is checked as a spec's fields are (finite, of its type, within bounds; unknown keys
are errors). The standard uncertainties default to the values below, each a choice stated here.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Literal

from pydantic import Field

from patchgen.identify.cells import PLAIN
from patchgen.inputs.errors import InputError
from patchgen.inputs.fields import InputModel, Real, bounded
from patchgen.inputs.inputfile import decode_text, read_bytes
from patchgen.inputs.validation import parse_toml, validate

# Standard uncertainties (one sigma) of hand measurements, when a file does not state its own.
# Assumed: no source gives the thesis's; these are what a stopwatch, a tape and a protractor give.
ASSUMED_TIME_UNCERTAINTY_S = 0.05  # a hand stopwatch: reaction at start and stop
ASSUMED_DISTANCE_UNCERTAINTY_M = 0.005  # a tape between two marks on the track
ASSUMED_ANGLE_UNCERTAINTY_DEG = 0.1  # a protractor or inclinometer on the rail
G_B2 = 9.81  # m/s^2: the gravity equation B.2 is written with
G_TABLE_B1 = 9.807  # m/s^2: table B.1's


G_WORKBOOK = 9.81  # m/s^2: gravity as Quanser's rotary pendulum workbook takes it (a links file may say otherwise)
ASSUMED_MASS_UNCERTAINTY_KG = 0.5e-3  # a kitchen scale's half gram (assumed)
ASSUMED_LENGTH_UNCERTAINTY_M = 0.5e-3  # a ruler's half millimetre (assumed)


class Masses(InputModel):
    """Thesis B.1's direct measurements: the masses (weighed), gravity and the track's length."""

    test: Literal["masses"]
    M_kg: Real = bounded(0.01, 100, description="cart mass")
    m_kg: Real = bounded(1e-3, 10, description="pendulum mass")
    M_uncertainty_kg: Real = bounded(0, 10, default=0.0, description="standard uncertainty of M")
    m_uncertainty_kg: Real = bounded(0, 1, default=0.0, description="standard uncertainty of m")
    g_m_per_s2: Real = bounded(1, 30, default=G_TABLE_B1)
    d_m: Real | None = bounded(0.05, 20, default=None, description="usable track between the switches")
    l_cm_m: Real | None = bounded(0.01, 10, default=None,
                                  description="pivot to the pendulum's centre of mass (balanced on an edge): "
                                              "a rigid pendulum's l, its J from the swing")


class Incline(InputModel):
    """Thesis B.2.1's inclined slide: from rest at the high end, ``distance_m`` in ``time_s``."""

    test: Literal["incline"]
    angle_deg: Real = bounded(0, 60, open_lo=True)
    distance_m: Real = bounded(0, 20, open_lo=True)
    time_s: Real = bounded(0, 600, open_lo=True)
    mass_kg: Real = bounded(0.01, 110, description="M + m, the pendulum fixed to the cart")
    g_m_per_s2: Real = bounded(1, 30, default=G_B2)
    angle_uncertainty_deg: Real = bounded(0, 10, default=ASSUMED_ANGLE_UNCERTAINTY_DEG)
    distance_uncertainty_m: Real = bounded(0, 1, default=ASSUMED_DISTANCE_UNCERTAINTY_M)
    time_uncertainty_s: Real = bounded(0, 10, default=ASSUMED_TIME_UNCERTAINTY_S)
    mass_uncertainty_kg: Real = bounded(0, 10, default=0.0)
    reported_b_per_s: Real | None = bounded(0, 1e3, default=None,
                                            description="a value printed elsewhere for these figures, shown beside")
    reported_source: str = Field(default="", max_length=200)


class Links(InputModel):
    """A rotary pendulum's direct measurements: each link weighed and measured (uniform rods, as the
    plant takes them when l and J are left out), gravity, and the motor's terminal resistance read
    on an ohmmeter; each with its standard uncertainty."""

    test: Literal["links"]
    m_r_kg: Real = bounded(1e-3, 10, description="the rotary arm's mass")
    L_r_m: Real = bounded(0.01, 2, description="the motor's axis to the pendulum's pivot")
    m_p_kg: Real = bounded(1e-3, 10, description="the pendulum's mass")
    L_p_m: Real = bounded(0.01, 2, description="the pendulum, pivot to tip")
    R_m_ohm: Real = bounded(1e-3, 1e3, description="the motor's terminal resistance (ohmmeter, rotor still)")
    g_m_per_s2: Real = bounded(1, 30, default=G_WORKBOOK)
    mass_uncertainty_kg: Real = bounded(0, 1, default=ASSUMED_MASS_UNCERTAINTY_KG)
    length_uncertainty_m: Real = bounded(0, 1, default=ASSUMED_LENGTH_UNCERTAINTY_M)
    R_m_uncertainty_ohm: Real = bounded(0, 100, default=0.0, description="the ohmmeter's standard uncertainty")


FIGURES = {"masses": Masses, "incline": Incline, "links": Links}


def read_figures(path: str | Path) -> Masses | Incline | Links:
    """Read a test-figures TOML file.

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    Masses or Incline
        The checked figures, as its ``test`` key names.

    Raises
    ------
    InputError
        The file and the key at fault.
    """
    source = str(path)
    raw = read_bytes(path)
    data = parse_toml(raw, source)
    _plain_figures(decode_text(raw, source), data, source)
    test = data.get("test")
    if test is None:
        names = " or ".join(f'"{k}"' for k in FIGURES)
        raise InputError(source, "test", f"missing: name the test (test = {names})")
    if test not in FIGURES:
        raise InputError(source, "test", f"unknown test {test!r} in a TOML file (one of {', '.join(FIGURES)}; "
                                         "recorded tests are CSV files)")
    return validate(FIGURES[test], data, source)


def _plain_figures(text: str, data: dict, source: str) -> None:
    """Each figure written in plain decimal notation, as in a recording (patchgen.identify.cells):
    TOML also reads 0x10, 1_000 and inf, none of them how a measured figure is written."""
    for key, value in data.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        name = re.escape(key)
        m = re.search(rf"^[ \t]*(?:{name}|\"{name}\"|'{name}')[ \t]*=[ \t]*([^#\s]+)", text, re.MULTILINE)
        if m is None or not PLAIN.fullmatch(m.group(1)):
            shown = m.group(1) if m else str(value)
            raise InputError(source, key, f"{shown!r} is not a number in plain decimal notation (digits, one "
                                          "point, an optional exponent)")
