"""patchgen swingup on the rotary pendulum: pumped up from hanging by energy control, handed to the
*patched* controller inside its zone of control and held by it on the bench for 30 s in at least
95 of 100 noise seeds; the zone leaves out fast arrivals and makes a too-fast pump wait; with the
workbook's pendulum damping the pump cannot get there, and the command says so; a reversed
pendulum encoder loses the pendulum at the hand-off; a cart's options are refused."""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest
import tomli_w

from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.inputs.resources import resolve
from patchgen.pipeline.inputs import load_inputs
from patchgen.pipeline.scaling import scaled_patch
from patchgen.profiles.measured_plant import as_on_bench
from patchgen.swingup.rotary_energy import CATCH_ANGLE_RAD, SWITCHING, EnergyGains, simulate_swingup, wrap
from patchgen.swingup.rotary_manoeuvre import PUMP_S, rotary_manoeuvre
from patchgen.swingup.rotary_zone import start_scenario
from tests.conftest import ROOT, run_patchgen

pytestmark = pytest.mark.heavy(30)  # seconds, roughly: see tests/conftest.py
SPEC = (ROOT / "designs" / "qube-servo-2.toml").read_text()
HOLD_S = 30.0  # the command's hold after the hand-off



def test_the_patch_takes_the_pendulum_from_the_pump_and_holds_it_30_s(tmp_path):
    """The shipped QUBE (designed with the workbook's D_p, its bench's pendulum its own 5e-5)."""
    r = run_patchgen("swingup", "qube-servo-2", "-o", str(tmp_path / "out"), "--json")
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    assert got["strategy"] == "energy" and got["reached_zone"] and got["held"] and got["hold_s"] == 30.0
    assert 0.5 < got["handoff_time_s"] < 30.0  # it took pumping: hanging is 180 deg away
    at = got["handoff_state"]
    assert abs(at["theta_deg"]) < math.degrees(CATCH_ANGLE_RAD) and abs(at["theta_dot_rad_s"]) < 5.0
    zone = got["zone"]
    assert zone["level_r"] > 0.0 and zone["starts_tried"] > 10 and np.array(zone["P"]).shape == (4, 4)
    hold = got["hold"]
    assert hold["held"] and hold["max_abs_theta_deg"] < 30.0
    history = np.genfromtxt(tmp_path / "out" / "hold-history.csv", delimiter=",", names=True)
    assert history["t_s"][-1] == pytest.approx(30.0, abs=0.02)
    assert abs(np.degrees(history["theta_rad"][-1])) < 5.0  # upright at the end, by the patch
    assert (tmp_path / "out" / "patch-sheet.md").read_text().count("Swing-up switching table") == 1


@pytest.fixture(scope="module")
def qube():
    """The shipped QUBE's inputs, design (the workbook's D_p), patch and manoeuvre (hold seed 0) on
    its bench, whose pendulum swings freely for seconds (its [measured_plant] D_p)."""
    inputs = load_inputs("qube-servo-2", command="swingup")
    d = design_on(*inputs)
    net = scaled_patch(d, inputs.machine, inputs.bench).netlist
    m = rotary_manoeuvre(net, d.plant, inputs.bench, inputs.machine, d.K[:, :4], hold_s=30.0, seed=0)
    return inputs, d, net, m


def _held(qube, x, seeds, duration=HOLD_S, bench=None):
    """How many of the hold's noise seeds (each its own run 0, as the command's --seed) keep the pendulum."""
    inputs, d, net, _ = qube
    return sum(simulate(net, d.plant, bench or inputs.bench, inputs.machine, start_scenario(x, duration, s),
                        keep_history=False).runs[0].held for s in seeds)


def test_the_pump_hands_off_inside_the_patch_s_zone_and_the_patch_holds_it_in_95_of_100_seeds(qube):
    """The hand-off state, the pump alone up to it: within 20 deg, inside the patch's zone of
    control, the arm near its centre and the pendulum slow; the patch keeps it for 30 s in at
    least 95 of the hold's seeds 0..99 (100 seen: docs/plants.md) and, its pendulum encoder
    reversed, in none of 40."""
    inputs, d, net, m = qube
    assert m.reached and m.held
    x = m.pump.x[-1]
    assert abs(wrap(x[1])) < CATCH_ANGLE_RAD and m.zone.contains(x) and not m.pump.lqr[:-1].any()
    assert 0.5 < m.pump.handoff_time < 3.0  # it took pumping: hanging is 180 deg away (1.42 s seen)
    assert abs(x[0]) < 0.5 and abs(x[3]) < 5.0  # arm 0.20 rad, pendulum 4.5 rad/s seen
    assert m.pump.max_abs_alpha < 0.5 * d.plant.alpha_limit  # the arm kept near its centre (1.35 rad seen)
    assert _held(qube, x, range(100)) >= 95
    reversed_encoder = inputs.bench.model_copy(update={"sensors": inputs.bench.sensors.model_copy(
        update={"theta": -inputs.bench.sensors.theta})})
    assert _held(qube, x, range(40), 10.0, reversed_encoder) == 0


def test_the_switching_table_is_what_the_pump_did(qube):
    """Row 1 (inside the band and the zone: the patch) matched first at the hand-off and at no
    sample before it; the table on the sheet and in manoeuvre.json is SWITCHING."""
    *_, m = qube
    band = np.abs(wrap(m.pump.x[:, 1])) < CATCH_ANGLE_RAD
    first_row = band & np.array([bool(m.zone.contains(x)) for x in m.pump.x])
    assert first_row[-1] and not first_row[:-1].any()
    assert np.array_equal(first_row, m.pump.lqr)
    assert "zone of control" in SWITCHING[0].condition and f"{math.degrees(CATCH_ANGLE_RAD):.0f} deg" in \
        SWITCHING[0].condition and "-K x" in SWITCHING[0].law
    assert SWITCHING[1].condition == "otherwise" and "E_r" in SWITCHING[1].law
    assert m.summary()["switching_table"] == [{"condition": r.condition, "law": r.law} for r in SWITCHING]


def test_the_zone_leaves_out_the_fast_hand_off_the_patch_catches_only_sometimes(qube):
    """The pump aimed 0.5 G above upright (as before the zone) handed off at 19.8 deg, 7.7 rad/s,
    the arm 1.46 rad off centre: the patch keeps that in about 60 of 100 seeds, and the zone
    leaves it out."""
    *_, m = qube
    fast = np.array([-1.4605, math.radians(-19.78), 0.8502, 7.702])
    assert not m.zone.contains(fast)
    assert 40 <= _held(qube, fast, range(100)) <= 80  # 61 seen


def test_the_zone_makes_a_too_fast_pump_wait(qube):
    """Aimed 0.2 G above upright the pump first comes within 20 deg with the arm at 7 rad/s: the
    angle alone hands off there and the patch loses every seed; the zone waits for the next pass,
    which the patch keeps."""
    inputs, d, net, m = qube
    fast = EnergyGains(margin=0.2)
    bench_plant = as_on_bench(d.plant, inputs.bench)  # the pump runs on the bench's pendulum
    by_angle = simulate_swingup(bench_plant, m.v_limit, t_end=PUMP_S, K=d.K[:, :4], gains=fast, stop_at_handoff=True)
    by_zone = simulate_swingup(bench_plant, m.v_limit, t_end=PUMP_S, K=d.K[:, :4], gains=fast, stop_at_handoff=True,
                               zone=m.zone)
    assert by_angle.handoff_time < by_zone.handoff_time < 3.0  # 0.96 s and 1.48 s seen
    assert _held(qube, by_angle.x[-1], range(20)) == 0
    assert _held(qube, by_zone.x[-1], range(20)) == 20


def test_same_seed_same_manoeuvre_another_seed_the_same_hand_off(qube):
    inputs, d, net, m = qube
    again = rotary_manoeuvre(net, d.plant, inputs.bench, inputs.machine, d.K[:, :4], hold_s=5.0, seed=0)
    other = rotary_manoeuvre(net, d.plant, inputs.bench, inputs.machine, d.K[:, :4], hold_s=5.0, seed=1)
    assert np.array_equal(again.pump.x, m.pump.x) and again.zone.r == m.zone.r
    assert np.array_equal(other.pump.x, m.pump.x)  # the zone and the pump do not depend on the hold's seed
    first = simulate(net, d.plant, inputs.bench, inputs.machine, start_scenario(m.pump.x[-1], 5.0, 0))
    assert np.array_equal(again.hold.history["theta"], first.history["theta"])
    assert not np.array_equal(other.hold.history["theta"], first.history["theta"])


def test_with_the_workbook_s_damping_the_pump_falls_short_and_says_so(tmp_path):
    """A bench whose pendulum has the workbook's D_p (the shipped bench without its measured one)."""
    bench = tomllib.loads(resolve("bench", "qube-servo-2").read_text())
    assert bench.pop("measured_plant") == {"D_p": 5e-5}
    (tmp_path / "workbook.toml").write_text(tomli_w.dumps(bench))
    spec = tmp_path / "qube.toml"
    spec.write_text(SPEC.replace('bench = "qube-servo-2"', f'bench = "{tmp_path / "workbook.toml"}"'))
    r = run_patchgen("swingup", str(spec), "-o", str(tmp_path / "out"), "--json")
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    assert not got["reached_zone"] and not got["held"] and got["handoff_time_s"] is None
    assert got["closest_to_upright_deg"] > math.degrees(CATCH_ANGLE_RAD)
    assert not (tmp_path / "out" / "hold-history.csv").exists()


@pytest.mark.parametrize("option, value", [("--strategy", "supervisory"), ("--force-limit", "5"), ("--compare", None)])
def test_a_cart_s_option_is_refused_in_one_line(option, value, tmp_path):
    args = ["swingup", "qube-servo-2", "-o", str(tmp_path / "out"), option] + ([value] if value else [])
    r = run_patchgen(*args)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and option in r.stderr, r.stderr
    assert not (tmp_path / "out").exists()
