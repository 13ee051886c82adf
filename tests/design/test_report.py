"""The design report on its own: the JSON dict against the design it describes, the terminal tables."""

from __future__ import annotations

import io
import json
import math
import re

import numpy as np
import pytest
from rich.console import Console

from patchgen.design.lqg import design
from patchgen.design.margins import loop_margins
from patchgen.design.precision import significant_digits
from patchgen.design.report import design_dict, margins_dict
from patchgen.inputs.spec import load_spec
from patchgen.profiles.bench import load_bench
from patchgen.render.design_tables import REPORT_DIGITS, margins_table, print_design

BENCH = load_bench("uw-1991")
MARGIN_KEYS = {"stable", "lower_gm", "lower_gm_db", "upper_gm", "upper_gm_db", "pm_deg", "pm_freq",
               "delay_margin_s", "gain_crossovers", "phase_crossovers"}


def _design(name: str):
    return design(load_spec(name), BENCH)


def _cells(line: str) -> list[str]:
    """The non-empty cells of one rendered table row (columns two spaces apart or more)."""
    return [c for c in re.split(r"\s{2,}", line.strip()) if c]


def _text(renderable) -> str:
    console = Console(file=io.StringIO(), width=200, record=True)
    console.print(renderable)
    return console.export_text()


def _k_over_s_s1():
    """T(s) = 1/(s(s+1)): |T(jw)| = 1 at w^2 = (sqrt 5 - 1)/2, phase margin 90 - atan(w) deg."""
    return loop_margins(np.array([[0.0, 1.0], [0.0, -1.0]]), np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]]))


def test_margins_dict_is_json_ready_and_keeps_the_values():
    assert margins_dict(None) is None
    d = margins_dict(_k_over_s_s1())
    assert set(d) == MARGIN_KEYS
    wc = math.sqrt((math.sqrt(5) - 1) / 2)
    assert d["pm_freq"] == pytest.approx(wc, rel=1e-9)
    assert d["pm_deg"] == pytest.approx(90 - math.degrees(math.atan(wc)), abs=1e-9)
    assert d["stable"] is True and d["upper_gm"] is None and d["lower_gm"] is None
    assert json.loads(json.dumps(d, allow_nan=False)) == d


def test_design_dict_describes_the_design():
    d = _design("thesis-case1")
    out = json.loads(json.dumps(design_dict(d), allow_nan=False))  # plain JSON, no NaN
    assert out["name"] == "thesis-case1"
    assert out["states"] == ["s", "theta", "s_dot", "theta_dot", "int_s", "int_theta"]
    K = np.array(out["K"])
    np.testing.assert_array_equal(K, d.K[0])
    A, B = np.array(out["A"]), np.array(out["B"])[:, None]
    # the closed-loop poles it lists are those of A - B K, recomputed from the listed A, B, K
    poles = np.array([complex(*p) for p in out["closed_loop_poles"]])
    want = np.linalg.eigvals(A - B @ K[None, :])
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(want), rtol=1e-9, atol=1e-9)
    assert all(p.real < 0 for p in poles)
    assert out["R"] == pytest.approx(float(d.R[0, 0])) and len(out["Q"]) == 6
    est = out["estimator"]
    assert est["kind"] == "kalman" and "rolloff_s" not in est
    assert np.array(est["L"]).shape == (len(est["states"]), 3)  # one column per measured s, theta, s_dot
    assert est["rho"] == pytest.approx(1e7)  # the thesis's case 1 recovers the LQR loop at rho = 1e7
    assert est["rho_tries"][-1]["rho"] == est["rho"]
    assert est["rho_tries"][-1]["margins"] == out["lqg_margins"]  # the last try is the loop patched
    assert set(out["lqg_margins"]) == MARGIN_KEYS and set(out["lqr_margins"]) == MARGIN_KEYS


def test_design_dict_of_a_differentiator_gives_its_roll_off():
    out = design_dict(_design("thesis-ch5"))
    assert out["estimator"]["kind"] == "differentiator"
    assert out["estimator"]["rolloff_s"] == pytest.approx(0.01)
    assert "L" not in out["estimator"]
    # the differentiator's one pole at -1/roll-off
    assert out["estimator"]["poles"] == [[pytest.approx(-100.0), 0.0]]


def test_margins_table_lists_loops_with_margins_only():
    unstable = loop_margins(np.array([[1.0]]), np.array([[1.0]]), np.array([[0.5]]))  # pole at +0.5 closed
    assert not unstable.stable
    table = margins_table([("LQR", _k_over_s_s1()), ("none", None), ("bad", unstable)])
    assert table.row_count == 2
    text = _text(table)
    lqr_line = next(line for line in text.splitlines() if "LQR" in line)
    # no lower limit, infinite upper limit, PM to two decimals at the crossover
    assert _cells(lqr_line)[1:5] == ["none", "inf", "51.83", "0.786"]
    assert "unstable" in next(line for line in text.splitlines() if "bad" in line)


def test_print_design_shows_gains_weights_and_estimator():
    d = _design("thesis-case1")
    console = Console(file=io.StringIO(), width=200, record=True)
    print_design(d, console)
    text = console.export_text()
    rows = {c[0]: c for c in (_cells(line) for line in text.splitlines()) if len(c) == 3}
    for i, s in enumerate(d.states):
        name, q, k = rows[s]
        assert q == f"{d.Q[i, i]:g}"
        digits = significant_digits(float(d.K[0, i]), float(d.spread.K[0, i]))
        if digits >= REPORT_DIGITS:  # printed to 7 significant digits, the last one rounded
            assert float(k) == pytest.approx(d.K[0, i], abs=0.5 * 10 ** (np.floor(np.log10(abs(d.K[0, i]))) - 6))
        else:  # a gain the design does not fix to 7 digits is marked, and its row's note says so
            assert k.endswith(" *")
    # thesis-case1's integral-of-theta gain is rounding noise (~1e-9 against gains of 10 to 250)
    assert rows["int_theta"][2].startswith("0 ± ") and "int_theta not beyond its size" in " ".join(text.split())
    assert f"R = {d.R[0, 0]:g}" in text
    assert f"Kalman gain L (rho = {d.estimator.rho:g})" in text
    assert "LQG + LTR" in text and "unstable" not in text
