"""The ngspice check of a patch: deck contents, pot loading, and agreement with an ideal-element
reference of the same netlist (a SciPy solve_ivp written here, independent of the deck)."""

from __future__ import annotations

import hashlib
import math
import shutil
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from patchgen.bench.noise_drift import noise_and_drift
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist, read_netlist
from patchgen.plant.equations import PlantParams, nonlinear_rhs
from patchgen.profiles.bench import BenchProfile, load_bench
from patchgen.profiles.machine import load_machine
from patchgen.render.spice_plot import comparison_plot
from patchgen.spice.compare import compare
from patchgen.spice.deck import SpiceSettings, spice_deck
from patchgen.spice.elements import loaded_ratio, pot_wiper_position
from patchgen.spice.run import NgspiceError, NgspiceMissing, run_ngspice

FIXTURE = Path(__file__).parents[1] / "fixtures" / "thesis-ch5.netlist.json"
# Table B.1 of the thesis.
PLANT = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)
# The 10 deg offset scenario: 10 s, released at rest.
SETTINGS = SpiceSettings(duration_s=10.0, step_s=0.005, x0=(0.0, math.radians(10.0), 0.0, 0.0),
                         actuator="ideal")



def _levels(net, bench, machine, noise="profile", drift="profile"):
    """The noise and drift of a scenario asking for them (the profiles' by default)."""
    return noise_and_drift([s.id for s in net.sensors], bench, machine,
                           Scenario(duration_s=1.0, noise=noise, drift=drift))


needs_ngspice = pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not on the PATH")


@dataclass
class Reference:
    t: np.ndarray
    signals: dict[str, np.ndarray]


def ideal_reference(net: Netlist, plant: PlantParams, bench: BenchProfile, settings: SpiceSettings,
                    n_points: int = 4001) -> Reference:
    """The netlist with ideal amplifiers (module docstring of patchgen.patch.netlist) closed around the
    nonlinear plant with an ideal actuator F = K_U u_c (or the bench's, with hard corners),
    integrated by solve_ivp."""
    pots = {p.id: p.setting for p in net.pots}
    dyn = [a for a in net.amplifiers if a.role in ("integrator", "differentiator", "lag")]
    index = {a.id: 4 + i for i, a in enumerate(dyn)}
    K_U = bench.actuator.K_U

    def outputs(x: np.ndarray) -> tuple[dict[str, float], dict[str, float]]:
        """Every amplifier's output and every amplifier's weighted input sum, at state x."""
        volts = {sid: getattr(bench.sensors, sid) * x[("s", "theta", "s_dot").index(sid)]
                 for sid in ("s", "theta", "s_dot")}
        sums: dict[str, float] = {}

        def value(src: str) -> float:
            if src in volts:
                return volts[src]
            amp = net.amp(src)
            u = sum(i.weight * (pots[i.pot] if i.pot else 1.0) * value(i.source) for i in amp.inputs)
            sums[src] = u
            if amp.role in ("summer", "inverter"):
                out = -u
            elif amp.role == "differentiator":
                out = -amp.T_d_s / amp.rolloff_s * (u - x[index[src]])
            else:
                out = x[index[src]]
            volts[src] = out
            return out

        for a in net.amplifiers:
            value(a.id)
        return volts, sums

    act = bench.actuator
    lag = settings.actuator == "bench"
    i_lag = 4 + len(dyn)

    def force(x: np.ndarray, u_c: float) -> tuple[float, float]:
        """Force on the cart and the lag state's rate: ideal gain, or the bench's lag, dead zone,
        force limit and limit switches (hard corners)."""
        if not lag:
            return K_U * u_c, 0.0
        v = np.sign(u_c) * max(abs(u_c) - act.dead_zone_V, 0.0)
        rate = (K_U * v - x[i_lag]) / act.tau
        f = float(np.clip(x[i_lag], -act.force_limit_N, act.force_limit_N))
        if bench.track.limit_switches and abs(x[0]) >= plant.d / 2:
            f = 0.0
        return f, rate

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        volts, sums = outputs(x)
        dx = np.empty_like(x)
        f, dx[-1] = force(x, volts[net.output.source])
        dx[:4] = nonlinear_rhs(plant, x[:4], f)
        for a in dyn:
            i = index[a.id]
            if a.role == "integrator":
                dx[i] = -sums[a.id] / net.time_scale_s
            elif a.role == "differentiator":
                dx[i] = (sums[a.id] - x[i]) / a.rolloff_s
            else:
                dx[i] = (-sums[a.id] - x[i]) / a.tau_s
        return dx

    x0 = np.zeros(5 + len(dyn))
    x0[:4] = settings.x0
    for a in dyn:
        x0[index[a.id]] = a.ic_V or 0.0
    _, sums0 = outputs(x0)
    for a in dyn:
        if a.role == "differentiator":
            x0[index[a.id]] = sums0[a.id]  # at rest: the input capacitor charged, output 0
    t = np.linspace(0.0, settings.duration_s, n_points)
    sol = solve_ivp(rhs, (0.0, settings.duration_s), x0, t_eval=t, method="LSODA",
                    rtol=1e-9, atol=1e-11, max_step=settings.step_s)
    assert sol.success, sol.message
    signals = {name: sol.y[i] for i, name in enumerate(("s", "theta", "s_dot", "theta_dot"))}
    signals["u_c"] = np.array([outputs(sol.y[:, k])[0][net.output.source] for k in range(len(sol.t))])
    return Reference(sol.t, signals)


@pytest.fixture(scope="module")
def net() -> Netlist:
    return read_netlist(FIXTURE)


@pytest.fixture(scope="module")
def gp6():
    return load_machine("gp6")


@pytest.fixture(scope="module")
def bench():
    return load_bench("uw-1991")


@pytest.fixture(scope="module")
def reference(net, bench) -> Reference:
    return ideal_reference(net, PLANT, bench, SETTINGS)


# ---------------------------------------------------------------------------------------------
# Pot loading


@pytest.mark.parametrize("setting", [0.001, 0.226, 0.267, 0.599, 0.999, 1.0])
@pytest.mark.parametrize("load", [1.0e5, 1.0e6])
def test_wiper_position_gives_the_loaded_setting(setting, load, gp6):
    rp = gp6.components.pot_resistance_ohm
    a = pot_wiper_position(setting, rp, load)
    assert 0.0 <= a <= 1.0
    assert loaded_ratio(a, rp, load) == pytest.approx(setting, rel=1e-12, abs=1e-15)


def test_a_loaded_pot_sits_above_its_setting(gp6):
    # With a 10 kOhm pot into a 100 kOhm x10 input, the 0.267 setting of P2 needs the wiper
    # higher: the load pulls the wiper voltage down (hand calculation: a = 0.272291).
    a = pot_wiper_position(0.267, gp6.components.pot_resistance_ohm, gp6.components.input_resistor_x10_ohm)
    assert a == pytest.approx(0.272291, abs=1e-6)


# ---------------------------------------------------------------------------------------------
# Deck contents


def test_deck_has_every_amplifier_pot_and_profile_value(net, gp6, bench):
    deck = spice_deck(net, PLANT, bench, gp6, SETTINGS).text
    lines = deck.splitlines()
    for amp in net.amplifiers:
        n = amp.id.lower()
        plus = "0"  # drift off: the non-inverting input is grounded
        # Finite open-loop gain 1e5, 50 ohm output resistance, bound at 10 V (gp6.toml).
        assert f"E_{n} {n}_core 0 {plus} {n}_sj 100000.0" in lines, amp.id
        assert f"R_{n}_o {n}_core {n}_out 50.0" in lines, amp.id
        assert any(ln.startswith(f"B_{n}_bound {n}_out {n}_sj I = 0.001*(") and "-10.0)" in ln
                   for ln in lines), amp.id
    for pot in net.pots:
        p = pot.id.lower()
        assert any(ln.startswith(f"R_{p}_up ") for ln in lines)
        assert any(ln.startswith(f"R_{p}_lo ") for ln in lines)
    # A6's x10 inputs use the profile's x10 resistor, A7's the x1 one; A1 has its 1 uF capacitor.
    assert "R_a6_x10a pot_p2_w a6_sj 100000.0" in lines
    assert "R_a7_x1a pot_p4_w a7_sj 1000000.0" in lines
    assert "C_a1_f a1_sj a1_out 1e-06" in lines
    # Differentiator A5: 1 uF input capacitor with a series resistor for the 0.01 s roll-off.
    assert "C_a5_x1a sens_theta a5_x1a_m 1e-06" in lines
    assert "R_a5_x1a_s a5_x1a_m a5_sj 10000.0" in lines
    assert "wrdata patch.data v(x_s) v(x_theta)" in deck
    assert "PWL(" not in deck and "_offset" not in deck


def test_noise_and_drift_switch_their_sources(net, gp6, bench):
    settings = replace(SETTINGS, noise_and_drift=_levels(net, bench, gp6), actuator="bench")
    deck = spice_deck(net, PLANT, bench, gp6, settings)
    text = deck.text
    assert "V_a1_offset a1_plus 0 DC 0.002" in text  # integrator_offset_V of gp6.toml
    assert "I_a1_bias a1_sj 0 DC 3e-09" in text  # integrator_bias_A of gp6.toml
    assert "E_sens_theta_noise sens_theta sens_theta_clean nz_1 0 1" in text
    assert "a_lag" in text and "ln(1+exp(" in text  # bench lag and smoothed dead zone
    assert "V_a5_offset" not in text  # drift belongs to integrators
    # The bench's random forces on the cart and at the tip join the scenario's pushes
    assert "E_force_cart_noise fz_cart 0 nz_7 0 1" in text and "E_force_tip_noise fz_tip 0 nz_8 0 1" in text
    assert "v(f_cart) + v(fz_cart)" in text and "(v(fz_tip))*cos(" in text
    # The noise table: sensors s, theta, s_dot, amplifiers A1, A5, A6, A7, then the two forces, at
    # the finest sample step (1 kHz amplifier noise -> 0.5 ms), each column's rms as its profile says.
    table = np.loadtxt(deck.files["patch.noise"].splitlines())
    assert table.shape == (20001, 10)
    assert np.diff(table[:, 0]) == pytest.approx(0.0005)
    rms = table[:, 1:].std(axis=0)
    expected = [0.002, 0.002, 0.005] + [gp6.imperfections.amplifier_noise_V_rms] * 4 + [0.1, 0.01]  # uw-1991.toml
    # Sensor and force columns are 200 Hz and 10 Hz samples joined linearly onto the finer grid:
    # their rms drops to sqrt(2/3) of the sample rms (mean square of a linear blend of two
    # independent samples).
    blend = math.sqrt(2 / 3)
    expected = [e * blend for e in expected[:3]] + expected[3:7] + [e * blend for e in expected[7:]]
    assert rms[:7] == pytest.approx(expected[:7], rel=0.05)
    # the forces have 101 independent samples in 10 s: the sample rms is within 25 % (3.5 sigma)
    assert rms[7:] == pytest.approx(expected[7:], rel=0.25)


def test_deck_is_deterministic(net, gp6, bench):
    noisy = replace(SETTINGS, noise_and_drift=_levels(net, bench, gp6), seed=7)
    a = spice_deck(net, PLANT, bench, gp6, noisy)
    b = spice_deck(read_netlist(FIXTURE), PLANT, bench, gp6, noisy)
    assert a == b
    assert spice_deck(net, PLANT, bench, gp6, replace(noisy, seed=8)).files != a.files


# ---------------------------------------------------------------------------------------------
# ngspice runs


def test_missing_ngspice_is_its_own_error(monkeypatch, net, gp6, bench, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(NgspiceMissing, match="apt-get install ngspice"):
        run_ngspice(spice_deck(net, PLANT, bench, gp6, SETTINGS), tmp_path)
    assert NgspiceMissing.exit_status == 3


@needs_ngspice
def test_broken_deck_reports_ngspice_error(tmp_path):
    with pytest.raises(NgspiceError, match="ngspice failed"):
        run_ngspice("broken\nR1 a 0 1k\nB1 a 0 V = nosuchfunc(v(a))\n.control\ntran 1m 1\n"
                    "wrdata patch.data v(a)\nquit\n.endc\n.end\n", tmp_path)


@needs_ngspice
def test_ngspice_agrees_with_ideal_reference(net, gp6, bench, reference, tmp_path):
    result = run_ngspice(spice_deck(net, PLANT, bench, gp6, SETTINGS), tmp_path)
    cmp = compare(result, reference)
    print("\n" + "\n".join(cmp.lines()) + f"\nngspice run time {result.run_time_s:.3f} s")
    # The pendulum really moves: 10 deg at the start, the cart travels tens of centimetres.
    assert cmp.signals["theta"].peak == pytest.approx(math.radians(10.0), rel=1e-6)
    assert cmp.signals["s"].peak > 0.1
    for name in ("theta", "s"):
        assert cmp.signals[name].max_rel < 0.01, cmp.lines()
    assert cmp.agrees(0.01)
    # u_c leaves A7 (the netlist's output) and starts at the loop's static value.
    assert result.signals["u_c"][0] == pytest.approx(reference.signals["u_c"][0], rel=1e-3)
    files = comparison_plot(cmp, "overlay", title="thesis-ch5, 10 deg", svg=True)
    assert list(files) == ["overlay.png", "overlay.svg"] and all(len(b) > 0 for b in files.values())
    assert files["overlay.png"].startswith(b"\x89PNG") and b"<svg" in files["overlay.svg"]
    assert list(comparison_plot(cmp, "png")) == ["png.png"]  # SVG on request
    again = comparison_plot(cmp, "overlay", title="thesis-ch5, 10 deg", svg=True)
    assert hashlib.sha256(files["overlay.svg"]).digest() == hashlib.sha256(again["overlay.svg"]).digest()


@needs_ngspice
def test_miswired_deck_disagrees(net, gp6, bench, reference, tmp_path):
    # theta fed to the final summer A7 instead of the pre-summer A6: its sign flips.
    data = net.model_dump(by_alias=True)
    for amp in data["amplifiers"]:
        if amp["id"] == "A6":
            moved = next(i for i in amp["inputs"] if i["source"] == "theta")
            amp["inputs"].remove(moved)
    for amp in data["amplifiers"]:
        if amp["id"] == "A7":
            amp["inputs"].append({**moved, "jack": "x10a"})
    for pot in data["pots"]:
        if pot["source"] == "theta":
            pot["amplifier"], pot["jack"] = "A7", "x10a"
    wrong = Netlist.model_validate(data)
    result = run_ngspice(spice_deck(wrong, PLANT, bench, gp6, SETTINGS), tmp_path)
    cmp = compare(result, reference)
    assert cmp.signals["theta"].max_rel > 0.5
    assert not cmp.agrees(0.01)


@needs_ngspice
def test_bench_actuator_agrees_until_saturation_and_the_pendulum_falls(net, gp6, bench, tmp_path):
    # With the bench's lag (0.2 s), dead zone and 15 N limit the ch5 patch cannot hold 10 deg
    # (conventions.md: the static law is unstable with the lag). Until the amplifiers saturate
    # (u_c reaches 7.2 V at 0.8 s) the circuit follows the ideal-element reference closely.
    settings = replace(SETTINGS, actuator="bench", duration_s=0.8, step_s=0.001)
    ref = ideal_reference(net, PLANT, bench, settings)
    result = run_ngspice(spice_deck(net, PLANT, bench, gp6, settings), tmp_path)
    cmp = compare(result, ref, names=("theta", "s", "u_c"))
    assert cmp.agrees(0.01), cmp.lines()
    assert abs(result.signals["theta"][-1]) > math.radians(20.0)  # falling: 27 deg at 0.8 s
    assert np.max(np.abs(result.signals["force"])) == pytest.approx(bench.actuator.force_limit_N, rel=2e-3)


@needs_ngspice
def test_integrator_drift_rate_is_the_profiles(net, gp6, bench, tmp_path):
    # At rest (all states 0) only drift moves the integrator A1: e_os/(R C) + i_b/C = 5 mV/s.
    settings = replace(SETTINGS, x0=(0.0, 0.0, 0.0, 0.0), noise_and_drift=_levels(net, bench, gp6, noise="off"))
    result = run_ngspice(spice_deck(net, PLANT, bench, gp6, settings), tmp_path)
    rate = np.polyfit(result.t, result.signals["A1"], 1)[0]
    assert rate == pytest.approx(gp6.integrator_drift_V_per_s(), rel=0.02)
    assert gp6.integrator_drift_V_per_s() == pytest.approx(0.005)


@needs_ngspice
def test_noisy_bench_run_is_reproducible(net, gp6, bench, tmp_path):
    settings = replace(SETTINGS, actuator="bench", noise_and_drift=_levels(net, bench, gp6), duration_s=1.0, seed=3)
    deck = spice_deck(net, PLANT, bench, gp6, settings)
    a = run_ngspice(deck, tmp_path / "a")
    b = run_ngspice(deck, tmp_path / "b")
    assert (tmp_path / "a" / "patch.data").read_bytes() == (tmp_path / "b" / "patch.data").read_bytes()
    drift_only = replace(settings, noise_and_drift=_levels(net, bench, gp6, noise="off"))
    quiet = run_ngspice(spice_deck(net, PLANT, bench, gp6, drift_only), tmp_path / "c")
    # Noise moves u_c (A7 sums 2 mV sensor noise through x10 inputs and the differentiator).
    assert np.max(np.abs(np.interp(quiet.t, a.t, a.signals["u_c"]) - quiet.signals["u_c"])) > 0.01
    assert len(a.t) == len(b.t)
