"""Pump-up (thesis chapter 3) on the nonlinear plant, with table B.1 parameters and 15 N."""

import matplotlib
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from patchgen.plant.equations import PlantParams
from patchgen.render.swingup_files import output_files, patch_sheet_rows
from patchgen.swingup.handoff import Zone, default_spread, estimate_zone, lqr_zone, lyapunov_matrix
from patchgen.swingup.pumping import HOLD_S, PUMP_T_MAX_S, STEP_S, simulate
from patchgen.swingup.run import swing_up
from patchgen.swingup.schedule import ScheduleSettings, optimise_schedule, replay, schedule_from_result
from patchgen.swingup.strategies import BRAKE, COAST, PUSH, Supervisor, hanging_state, pendulum_energy, upright_energy

pytestmark = pytest.mark.heavy(8)  # seconds, roughly: see tests/conftest.py

# Table B.1 of the thesis.
TABLE_B1 = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)
# Chapter 3 assumes 15 N of control (section 3.3); the pump-up must reach the zone within 7 s.
FORCE = 15.0
# python-control lqr on eq. 2.28 with Q = diag(25, 100, 25, 100), R = 0.1.
K_LQR = np.array([-15.8114, -209.0301, -31.0045, -52.9470])
HALF_TRACK = TABLE_B1.d / 2.0


@pytest.fixture(scope="module")
def zone() -> Zone:
    return lqr_zone(TABLE_B1, K_LQR, FORCE)


@pytest.fixture(scope="module")
def supervisory(zone):
    return swing_up(TABLE_B1, FORCE, "supervisory", K_LQR, zone)


def test_zone_contains_upright_not_hanging(zone):
    assert zone.contains(np.zeros(4))
    assert zone.contains(np.array([0.0, 2 * np.pi, 0.0, 0.0]))  # wrapped: a full turn is upright
    assert not zone.contains(hanging_state())
    assert zone.failures > 0  # the sampling box reached beyond what the saturated loop recovers


def test_estimate_zone_stops_at_first_failure():
    P = lyapunov_matrix(TABLE_B1, K_LQR, FORCE)
    spread = default_spread(TABLE_B1)
    # a criterion that is itself a level set: the estimate lies just inside it (shrink 0.9)
    z = estimate_zone(lambda x: float(x @ P @ x) < 0.5, P, spread, n_samples=400)
    assert z.failures == 1
    assert 0.45 <= z.r < 0.9 * 2.0
    assert z.contains(np.zeros(4))
    everything = estimate_zone(lambda x: True, P, spread, n_samples=50)
    assert everything.failures == 0 and everything.samples == 50


def test_supervisory_reaches_zone_within_7s_on_track(supervisory):
    assert supervisory.reached
    assert supervisory.handoff_time < 7.0
    assert supervisory.max_abs_s < HALF_TRACK
    assert supervisory.held  # the linear controller then balances it (5 s hold)


def test_energy_at_handoff_near_upright(supervisory):
    assert supervisory.energy_ratio_at_handoff == pytest.approx(1.0, abs=0.05)
    end = supervisory.x[-1]
    assert pendulum_energy(TABLE_B1, end) / upright_energy(TABLE_B1) == pytest.approx(1.0, abs=1e-3)


def test_switching_table_alternates_as_section_3_3(supervisory):
    rows = [s for s in supervisory.switches if s.time_s < supervisory.handoff_time]
    assert rows[0].phase == PUSH and rows[0].force_N == FORCE  # first bang positive (3.3)
    series = sorted({s.series for s in rows})
    assert len(series) >= 3
    first_push = {}
    for s in rows:
        in_series = [r for r in rows if r.series == s.series]
        assert [r.phase for r in in_series] == [PUSH, BRAKE, COAST][: len(in_series)]
        push, *rest = in_series
        if rest:
            assert rest[0].force_N == -push.force_N  # phase 2 reverses phase 1
        if len(rest) > 1:
            assert rest[1].force_N == 0.0  # phase 3 coasts
        first_push[s.series] = push.force_N
    signs = [np.sign(first_push[k]) for k in series]
    assert all(a == -b for a, b in zip(signs, signs[1:]))  # each series the other way
    times = [s.time_s for s in rows]
    assert times == sorted(times)


def test_energy_strategy_reaches_zone(zone):
    r = swing_up(TABLE_B1, FORCE, "energy", K_LQR, zone)
    assert r.reached and r.handoff_time < 7.0 and r.max_abs_s < HALF_TRACK and r.held


def test_optimised_schedule_no_slower_than_supervisory(zone):
    seed_run = simulate(TABLE_B1, Supervisor(TABLE_B1, FORCE), zone, strategy="supervisory",
                        force_limit=FORCE)
    seed, T = schedule_from_result(seed_run)
    opt = optimise_schedule(TABLE_B1, zone, seed, T)
    r = replay(TABLE_B1, opt.schedule, zone, FORCE, K_LQR)
    assert r.reached
    assert r.handoff_time <= seed_run.handoff_time + 1e-9
    assert r.max_abs_s_pump < HALF_TRACK
    assert r.held
    # it moved the switches, and says so: no note of a kept seed
    assert not opt.kept_seed and opt.note() is None and {s.reason for s in opt.schedule.switches} == {"optimised"}
    assert not np.array_equal(opt.schedule.times, seed.times)
    # no round allowed: the seed comes back unchanged, and the note says so
    kept = optimise_schedule(TABLE_B1, zone, seed, T, ScheduleSettings(rounds=0))
    assert kept.kept_seed and not kept.success and {s.reason for s in kept.schedule.switches} == {"seed"}
    assert np.allclose(kept.schedule.times, seed.times, atol=1e-4) and "kept its seed" in kept.note()


def test_outputs_are_deterministic(supervisory):
    a = output_files(supervisory, svg=True)
    b = output_files(supervisory, svg=True)
    assert list(a) == ["swingup-history.csv", "swingup-switching.csv", "swingup-switching.md", "swingup.png",
                       "swingup.svg"]
    assert a == b
    rows = a["swingup-history.csv"].decode().splitlines()
    assert len(rows) == supervisory.t.size + 1 and rows[1].startswith("0.0000,")
    sheet = patch_sheet_rows(supervisory)
    assert sheet[0] == ["Series", "Phase", "Force (N)", "Time (s)"]
    assert sheet[-1][0].startswith("hand-off")


def test_plots_leave_matplotlib_settings_alone(supervisory):
    before = {k: repr(v) for k, v in matplotlib.rcParams.items()}
    files = output_files(supervisory, svg=True)
    assert {k: repr(v) for k, v in matplotlib.rcParams.items()} == before
    # the SVG's own settings applied all the same: glyphs as paths, no date
    svg = files["swingup.svg"].decode()
    assert "<path" in svg and "<dc:date>" not in svg and "<text" not in svg


def test_a_run_has_the_named_length_and_step(supervisory):
    assert supervisory.dt == STEP_S == 1e-3
    assert np.allclose(np.diff(supervisory.t), STEP_S)
    # the thesis's pump-up takes 5.2 s (Table 3.1): well inside the longest allowed
    assert supervisory.handoff_time < PUMP_T_MAX_S / 2
    # the hold after the hand-off runs its full HOLD_S
    assert supervisory.t[-1] == pytest.approx(supervisory.handoff_time + HOLD_S, abs=STEP_S)
    missed = swing_up(TABLE_B1, 2.0, "supervisory", K_LQR, Zone.box((1e-3, 1e-4, 1e-3, 1e-3)))
    assert not missed.reached and missed.t[-1] == pytest.approx(PUMP_T_MAX_S, abs=STEP_S)


@settings(max_examples=12, deadline=None)
@given(st.tuples(*[st.floats(0.9, 1.1) for _ in range(5)]))
def test_supervisory_keeps_cart_on_track_near_table_b1(factors):
    """The supervisor designs on table B.1 but runs on a plant up to 10 % off in each parameter."""
    plant = TABLE_B1.scaled(**dict(zip(("M", "m", "l", "b_VF", "c"), factors)))
    zone = Zone.box((0.2, 0.1, 0.3, 0.5))
    r = simulate(plant, Supervisor(TABLE_B1, FORCE), zone, strategy="supervisory",
                 force_limit=FORCE, t_max=8.0)
    assert r.max_abs_s < HALF_TRACK
