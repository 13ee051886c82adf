"""Plots that explain themselves: every line named, no legend over the data, one theta convention
(patchgen.render.plotting.THETA_LABEL), each amplifier's panel naming the signal it carries."""

from __future__ import annotations

from dataclasses import replace

import matplotlib
import numpy as np
import pytest

from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.spec import load_spec
from patchgen.pipeline.identify import run_bench_test, run_identify
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.simulate import SimulatePlan, run_simulate
from patchgen.pipeline.swingup import SwingupPlan, run_swingup
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.render import plotting
from patchgen.render.diagram_symbols import signed_label
from patchgen.render.identify_plots import fit_figure
from patchgen.render.manoeuvre_plot import manoeuvre_figure
from patchgen.render.simulation_files import history_figure
from patchgen.render.swingup_files import pump_figure

pytestmark = pytest.mark.heavy(12)  # seconds, roughly: see tests/conftest.py


@pytest.fixture(scope="module")
def inputs():
    spec = load_spec("bench-recommended")
    return Inputs(spec, load_machine(spec.machine), load_bench(spec.bench))


@pytest.fixture(scope="module")
def simulated(inputs):
    return run_simulate(inputs, load_scenario("offset-10deg"), SimulatePlan())


@pytest.fixture(scope="module")
def swingup(inputs):
    return run_swingup(inputs, SwingupPlan(hold_s=3.0))


def legend_texts(ax) -> list[str]:
    leg = ax.get_legend()
    return [] if leg is None else [t.get_text() for t in leg.get_texts()]


def assert_legends_outside_the_data(fig) -> None:
    """Every legend lies above its axes: it covers no curve."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    for ax in fig.axes:
        leg = ax.get_legend()
        if leg is None:
            continue
        assert leg.get_window_extent(renderer).y0 >= ax.get_window_extent(renderer).y1 - 1.0, ax.get_ylabel()


def test_history_names_the_rails_and_each_amplifiers_signal(simulated):
    result = simulated.result
    with matplotlib.rc_context({"font.size": 8}):
        fig = history_figure(result)
    assert_legends_outside_the_data(fig)
    labels = [ax.get_ylabel() for ax in fig.axes]
    rail = f"rails ±{result.settings.saturation_V:g} V"
    net = {a.id: a for a in simulated.netlist.amplifiers}
    named = [lab for lab in labels if lab.split(":")[0] in net]
    assert named, labels
    for lab in named:  # "A5: −dθ/dt (V)": the id and the signal it carries
        a = net[lab.split(":")[0]]
        assert lab == f"{a.id}: {signed_label(a.carries.polarity, a.carries.quantity)} (V)"
    for ax in fig.axes:
        if ax.get_ylabel() in named or ax.get_ylabel().startswith("u_c"):
            assert rail in legend_texts(ax), ax.get_ylabel()
    assert legend_texts(fig.axes[0]) == ["s", "s_ref"]
    assert plotting.THETA_LABEL in labels


def test_history_names_the_limit_switch_and_the_fall(simulated):
    result = simulated.result
    first = replace(result.runs[0], trip_time_s=2.5, fall_time_s=3.25, limit_switch_tripped=True, fallen=True)
    fig = history_figure(replace(result, runs=[first] + result.runs[1:]))
    assert_legends_outside_the_data(fig)
    for ax in fig.axes:
        texts = legend_texts(ax)
        assert "limit switch 2.50 s" in texts and "fallen 3.25 s" in texts, ax.get_ylabel()


def test_swingup_and_manoeuvre_show_theta_the_same_way(swingup):
    m = swingup.manoeuvre
    pump, whole = pump_figure(m.pump), manoeuvre_figure(m, "title")
    for fig in (pump, whole):
        assert_legends_outside_the_data(fig)
        theta = [ax for ax in fig.axes if ax.get_ylabel() == plotting.THETA_LABEL]
        assert len(theta) == 1  # the one label, "±180, 0 upright"
        ys = np.concatenate([line.get_ydata() for line in theta[0].get_lines() if len(line.get_ydata()) > 2])
        assert np.nanmax(ys) <= 180.0 and np.nanmin(ys) >= -180.0
        assert theta[0].get_ylim() == pytest.approx((-195.0, 195.0))
    assert "±180, 0 upright" in plotting.THETA_LABEL
    half = f"limit switches ±{m.pump.plant.d / 2:.3g} m"
    assert half in legend_texts(pump.axes[0]) and half in legend_texts(whole.axes[0])
    hand = f"hand-off {m.pump.handoff_time:.3f} s"
    assert all(hand in legend_texts(ax) for ax in pump.axes)
    assert "patched controller (bench)" in legend_texts(whole.axes[0])


def test_theta_is_wrapped_without_a_line_across_the_plot():
    t = np.linspace(0.0, 1.0, 101)
    tt, deg = plotting.theta_degrees(t, np.linspace(np.pi - 0.5, np.pi + 0.5, 101))
    gaps = np.flatnonzero(np.isnan(deg))
    assert gaps.size == 1 and np.all(np.diff(tt) > 0)  # one gap where it wraps, time still in order
    assert np.nanmax(deg) < 180.0 and np.nanmin(deg) >= -180.0
    assert np.all(np.abs(np.diff(deg[:gaps[0]])) < 2) and np.all(np.abs(np.diff(deg[gaps[0] + 1:])) < 2)


def test_fit_plots_keep_their_legends_off_the_data(inputs, tmp_path):
    for name, data in run_bench_test(inputs, seed=0).recordings.items():
        (tmp_path / name).write_bytes(data)
    fits = run_identify([str(tmp_path)]).result.fits
    with_fit = [f for f in fits if any(p.fitted is not None for p in f.panels)]
    assert any("free-swing" in f.source for f in with_fit)
    for f in with_fit:
        fig = fit_figure(f)
        assert_legends_outside_the_data(fig)
        for ax, p in zip(fig.axes, f.panels):
            assert legend_texts(ax) == (["measured", "fitted"] if p.fitted is not None else [])
