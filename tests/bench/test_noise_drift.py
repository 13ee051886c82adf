"""A run's noise and drift, resolved once: the simulator and the SPICE deck take the same levels."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest

from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config
from patchgen.bench.noise_drift import noise_and_drift
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.spice.deck import SpiceSettings, spice_deck
from patchgen.spice.elements import num

FIXTURE = json.loads((Path(__file__).parents[1] / "fixtures" / "thesis-ch5.netlist.json").read_text())
PLANT = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)  # table B.1
GP6, UW = load_machine("gp6"), load_bench("uw-1991")
# Explicit levels unlike the profiles' (uw-1991: 2, 2, 5 mV; gp6: 5 mV/s drift)
EXPLICIT = Scenario(duration_s=1.0, noise={"mode": "explicit", "s": 0.01}, drift=0.01)


def _net(lag: bool = False) -> Netlist:
    data = copy.deepcopy(FIXTURE)
    if lag:  # the integrator A1 as a lag of 0.5 s
        a1 = next(a for a in data["amplifiers"] if a["id"] == "A1")
        a1.update(role="lag", tau_s=0.5)
    return Netlist.model_validate(data)


def _deck(net: Netlist, scenario: Scenario) -> tuple[str, dict[str, str]]:
    levels = noise_and_drift([s.id for s in net.sensors], UW, GP6, scenario)
    deck = spice_deck(net, PLANT, UW, GP6, SpiceSettings(1.0, 0.01, (0, 0.1, 0, 0), noise_and_drift=levels))
    return deck.text, deck.files


def test_explicit_levels_and_drift_rate_reach_simulator_and_deck_alike():
    net = _net()
    levels = noise_and_drift(["s", "theta", "s_dot"], UW, GP6, EXPLICIT)
    assert levels.sensor_V_rms == {"s": 0.01, "theta": 0.0, "s_dot": 0.0}
    assert levels.amplifier_V_rms == 0.0 and levels.drift_V_per_s == 0.01
    _, sim = engine_config(compile_circuit(net, GP6, UW), PLANT, UW, GP6, EXPLICIT)
    assert sim.sensor_noise_V_rms == levels.sensor_V_rms
    assert sim.amplifier_noise_V_rms == 0.0 and sim.integrator_drift_V_per_s == 0.01

    text, files = _deck(net, EXPLICIT)
    assert "E_sens_s_noise" in text and "E_sens_theta_noise" not in text and "E_a1_noise" not in text
    table = np.loadtxt(files["patch.noise"].splitlines())
    assert table.shape[1] == 2  # time and the one noisy sensor, at its own 200 Hz samples
    assert table[:, 1].std() == pytest.approx(0.01, rel=0.15)
    # drift at twice the profile's rate: the profile's offset and bias, doubled
    assert GP6.integrator_drift_V_per_s() == pytest.approx(0.005)
    assert "V_a1_offset a1_plus 0 DC 0.004" in text
    assert "I_a1_bias a1_sj 0 DC 6e-09" in text
    assert "_offset" not in text.replace("V_a1_offset", "")  # only the integrator drifts


def test_a_lag_drifts_through_its_own_capacitor():
    """The simulator drifts a lag's state at the run's rate: its output settles tau x rate off.
    In the deck a bias current rate x C_lag into the summing junction does the same."""
    text, _ = _deck(_net(lag=True), EXPLICIT)
    bias = 0.01 * 0.5 / GP6.components.feedback_resistor_ohm
    assert f"I_a1_bias a1_sj 0 DC {num(bias)}" in text
    assert "V_a1_offset" not in text
    c = compile_circuit(_net(lag=True), GP6, UW)
    assert c.drifting()[c.amp_ids.index("A1")]


@pytest.mark.parametrize("scenario, ideal", [
    (Scenario(duration_s=1.0, noise="profile", drift="profile"), True),
    (Scenario(duration_s=1.0, noise="off", drift="off"), False),
])
def test_ideal_or_off_is_quiet_everywhere(scenario, ideal):
    levels = noise_and_drift(["s", "theta"], UW, GP6, scenario, ideal)
    assert levels.sensor_V_rms == {"s": 0.0, "theta": 0.0}
    assert not levels.noisy and levels.drift_V_per_s == 0.0


def test_profile_levels_are_the_profiles():
    levels = noise_and_drift(["s", "theta", "s_dot"], UW, GP6, Scenario(duration_s=1.0))
    assert levels.sensor_V_rms == {"s": 0.002, "theta": 0.002, "s_dot": 0.005}  # uw-1991.toml
    assert levels.amplifier_V_rms == GP6.imperfections.amplifier_noise_V_rms
    assert levels.drift_V_per_s == GP6.integrator_drift_V_per_s()
    assert levels.sensor_bandwidth_Hz == UW.sensors.noise_bandwidth_Hz


def test_random_forces_are_the_bench_profiles_and_reach_the_engine():
    """The bench's random forces on the plant (uw-1991.toml: 0.1 N on the cart, 0.01 N at the tip,
    to 5 Hz) are on with the profiles' noise, as two more noise channels of the engine."""
    from patchgen.bench.engine import noise_process

    scenario = Scenario(duration_s=1.0)
    levels = noise_and_drift(["s", "theta", "s_dot"], UW, GP6, scenario)
    assert (levels.cart_force_N_rms, levels.tip_force_N_rms, levels.force_bandwidth_Hz) == (0.1, 0.01, 5.0)
    assert levels.noisy
    circuit = compile_circuit(_net(), GP6, UW)
    cfg, sim = engine_config(circuit, PLANT, UW, GP6, scenario)
    n_v = len(circuit.sensor_ids) + circuit.n_amps
    assert cfg.noise.a.shape == (n_v + 2,)
    for k, rms in enumerate((0.1, 0.01)):
        a, std = noise_process(rms, 5.0, cfg.settings.dt)
        assert cfg.noise.a[n_v + k] == pytest.approx(a, rel=1e-12)
        assert cfg.noise.std[n_v + k] == pytest.approx(std, rel=1e-12)
        assert std / math.sqrt(1 - a * a) == pytest.approx(rms, rel=1e-12)  # stationary rms
    assert (sim.cart_force_N_rms, sim.tip_force_N_rms) == (0.1, 0.01)


def test_explicit_forces_and_quiet_modes():
    explicit = Scenario(duration_s=1.0, noise={"mode": "explicit", "cart_force_N": 0.3})
    levels = noise_and_drift(["s"], UW, GP6, explicit)
    assert (levels.cart_force_N_rms, levels.tip_force_N_rms) == (0.3, 0.0)
    for scenario, ideal in ((Scenario(duration_s=1.0), True), (Scenario(duration_s=1.0, noise="off"), False)):
        levels = noise_and_drift(["s"], UW, GP6, scenario, ideal)
        assert levels.cart_force_N_rms == levels.tip_force_N_rms == 0.0


def test_a_pendulum_the_patch_does_not_hold_falls_on_the_bench():
    """With the actuator all but cut (K_U at its 0.01 N/V floor), a pendulum released exactly upright
    with no push stays up only when nothing at all disturbs it: the bench's random forces topple it
    in every seed."""
    from patchgen.bench.simulate import simulate

    dead = UW.model_copy(update={"actuator": UW.actuator.model_copy(update={"K_U": 0.01})})
    quiet = Scenario(duration_s=20.0, noise="off", drift="off")
    still = simulate(_net(), PLANT, dead, GP6, quiet, seed=1, runs=1)
    assert still.runs[0].held and still.runs[0].max_abs_theta_deg == 0.0
    pushed_by_the_bench = Scenario(duration_s=20.0, noise="profile", drift="off")
    res = simulate(_net(), PLANT, dead, GP6, pushed_by_the_bench, seed=1, runs=32, keep_history=False)
    assert not any(r.held for r in res.runs)
