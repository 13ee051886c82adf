"""The scaling excursions (patchgen.patch.compensator_forms.excursion_peaks) against the closed
form of a diagonal loop: exp(a t) sampled every SCALING_STEP_S, and a diverging run cut at its
first sample past 1e12 without a warning."""

import math
import warnings

import numpy as np
import pytest

from patchgen.patch.compensator_forms import (
    SCALING_HORIZON_S,
    SCALING_STEP_S,
    SCALING_THETA0_RAD,
    excursion_peaks,
)
from patchgen.plant.plant_model import CART


def test_a_decaying_and_an_oscillating_loop_peak_as_their_closed_form():
    # theta decays at 2 1/s; s rotates into a third state at 3 rad/s; the second output is their sum
    A = np.zeros((4, 4))
    A[0, 0] = -2.0
    A[1, 2], A[2, 1] = 3.0, -3.0
    C = np.array([[1.0, 0, 0, 0], [0, 1.0, 1.0, 0]])
    t = SCALING_STEP_S * np.arange(1, round(SCALING_HORIZON_S / SCALING_STEP_S) + 1)
    theta = SCALING_THETA0_RAD * np.exp(-2.0 * t)
    rotated = CART.step * np.abs(np.cos(3 * t) - np.sin(3 * t))
    got = excursion_peaks(A, C, [(0, SCALING_THETA0_RAD), (1, CART.step)])
    assert got == pytest.approx([theta.max(), rotated.max()], rel=1e-12)


def test_a_diverging_loop_stops_at_its_first_sample_past_1e12_and_says_nothing():
    A = np.diag([3000.0, -1.0])
    growth = math.exp(3000.0 * SCALING_STEP_S)
    k = math.ceil(math.log(1e12 / SCALING_THETA0_RAD) / math.log(growth))  # the first sample past 1e12
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = excursion_peaks(A, np.eye(2), [(0, SCALING_THETA0_RAD), (1, CART.step)])
    assert got[0] == pytest.approx(SCALING_THETA0_RAD * growth ** k, rel=1e-9)
    assert got[1] == pytest.approx(CART.step * math.exp(-SCALING_STEP_S), rel=1e-12)
