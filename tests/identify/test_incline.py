"""The thesis's inclined slide (B.2.1): B.2 solved directly as a boundary-value problem, the printed
B.3 shown beside it."""

import math

import pytest
from scipy.optimize import brentq

from patchgen.identify.figures import Incline
from patchgen.identify.friction import fit_incline, slide_distance, solve_b2
from patchgen.inputs.errors import InputError

# B.2.1: 9.5 deg, 132.5 cm in 1.460 s, M + m = 3.876 kg; B.2 is written with g = 9.81
THESIS = dict(test="incline", angle_deg=9.5, distance_m=1.325, time_s=1.460, mass_kg=3.876, g_m_per_s2=9.81,
              reported_b_per_s=0.665, reported_source="Shaw (1991) eq. B.3")


def printed_b3(b: float) -> float:
    """B.3 exactly as printed: 1.325 b^2 - 2.3886 b + e^(1.46 b) - 1.636 = 0."""
    return 1.325 * b * b - 2.3886 * b + math.exp(1.46 * b) - 1.636


def test_b2_solved_directly_gives_0_583_and_b3_as_printed_0_665():
    b = solve_b2(9.5, 1.325, 1.460, 9.81)
    assert b == pytest.approx(0.5825, abs=5e-4)  # conventions.md: 0.583 1/s
    # the boundary-value problem's answer meets the boundary condition in closed form
    assert slide_distance(b, 9.81 * math.sin(math.radians(9.5)), 1.460) == pytest.approx(1.325, abs=1e-9)
    # the printed B.3 has its root at the thesis's 0.665 (0.6644), not at B.2's
    assert brentq(printed_b3, 0.1, 1.0) == pytest.approx(0.665, abs=1e-3)
    assert abs(printed_b3(b)) > 0.01


def test_the_report_shows_both_and_b_vf():
    fit = fit_incline(Incline.model_validate(THESIS), "thesis-incline.toml")
    b = fit.estimates["decay"]
    assert b.value == pytest.approx(0.5825, abs=5e-4)
    assert (b.low, b.high) == pytest.approx((0.299, 0.866), abs=1e-3)  # stopwatch 0.05 s, tape 5 mm, 0.1 deg
    assert fit.estimates["b_VF"].value == pytest.approx(0.5825 * 3.876, rel=1e-3)  # 2.258 kg/s, not 2.5775
    text = " ".join(fit.notes)
    assert "0.665" in text and "0.5825" in text and "boundary-value problem" in text
    check = fit.checks[0]
    assert check.name == "reported value" and "inside" in check.text  # the stopwatch's 0.05 s allows 0.665
    assert "B.3" in check.text


def test_the_interval_follows_the_stated_uncertainties():
    tight = fit_incline(Incline.model_validate(dict(THESIS, time_uncertainty_s=0.005, distance_uncertainty_m=0.0005,
                                                    angle_uncertainty_deg=0.01)), "t.toml")
    loose = fit_incline(Incline.model_validate(THESIS), "t.toml")
    width = lambda f: f.estimates["decay"].high - f.estimates["decay"].low
    assert width(tight) == pytest.approx(0.1 * width(loose), rel=1e-3)  # every uncertainty a tenth
    assert not tight.estimates["decay"].covers(0.665) and tight.checks[0].rejected


def test_a_slide_faster_than_without_friction_is_refused():
    with pytest.raises(InputError) as e:
        fit_incline(Incline.model_validate(dict(THESIS, time_s=1.2)), "fast.toml")
    assert e.value.source == "fast.toml" and e.value.field == "distance_m" and "frictionless" in e.value.message
