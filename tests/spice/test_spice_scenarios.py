"""ngspice against patchgen on every shipped scenario: the ideal runs agree within 1 % of peak at
ngspice's own time points, a mis-wired deck does not, and the comparison's interpolation is not
what it measures."""

import math
import shutil

import numpy as np
import pytest

from patchgen.bench.noise_drift import noise_and_drift
from patchgen.bench.prediction import STANDARD
from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.patch.netlist import Netlist
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.spice.compare import compare
from patchgen.spice.deck import SpiceSettings, spice_deck
from patchgen.spice.run import run_ngspice

needs_ngspice = pytest.mark.skipif(shutil.which("ngspice") is None, reason="ngspice not on the PATH")


class _Run:
    def __init__(self, history):
        self.t = history["t"]
        self.signals = history


def _both(name: str, scenario: str, miswire: bool, tmp_path):
    spec = load_spec(name)
    machine, bench = load_machine(spec.machine), load_bench(spec.bench)
    d = design_on(spec, machine, bench)
    net = build_patch(d, machine)
    plant = plant_params(d.spec)
    sc = load_scenario(scenario)
    own = simulate(net, plant, bench, machine, sc.model_copy(update={"record_dt_s": 1e-6}), ideal=True)
    wired = _flip_theta(net) if miswire else net
    levels = noise_and_drift([s.id for s in net.sensors], bench, machine, sc, ideal=True)
    deck = spice_deck(wired, plant, bench, machine, SpiceSettings(
        duration_s=sc.duration_s, step_s=0.005, x0=tuple(sc.initial.vector()), noise_and_drift=levels,
        actuator="ideal", seed=sc.seed, disturbances=tuple(sc.disturbances)))
    return compare(run_ngspice(deck, tmp_path), _Run(own.history))


def _flip_theta(net: Netlist) -> Netlist:
    """A missing inversion, as a technician could patch it: the cord from theta's pot moved from the
    summer it belongs on to the amplifier that summer feeds, so theta skips one inversion."""
    data = net.model_dump(by_alias=True)
    amps = {a["id"]: a for a in data["amplifiers"]}
    pot = next(p for p in data["pots"] if p["source"] == "theta" and p["amplifier"] != net.output.source)
    partner = next(a for a in data["amplifiers"] if any(i["source"] == pot["amplifier"] for i in a["inputs"]))
    moved = next(i for i in amps[pot["amplifier"]]["inputs"] if i.get("pot") == pot["id"])
    amps[pot["amplifier"]]["inputs"].remove(moved)
    moved["jack"] = next(j for j in ("x10a", "x10b") if j not in {i["jack"] for i in partner["inputs"]})
    partner["inputs"].append(moved)
    pot["amplifier"], pot["jack"] = partner["id"], moved["jack"]
    return Netlist.model_validate(data)


@needs_ngspice
@pytest.mark.parametrize("scenario", STANDARD)
@pytest.mark.parametrize("name", ["bench-recommended", "thesis-ch5"])
def test_ideal_runs_agree_on_every_shipped_scenario(name, scenario, tmp_path):
    cmp = _both(name, scenario, False, tmp_path)
    assert len(cmp.t) > 1000  # ngspice's own points, not a resampled grid
    for sig in ("theta", "s"):
        assert cmp.signals[sig].peak > 0
        assert cmp.signals[sig].max_rel < 0.01, cmp.lines()  # measured: 0.006 to 0.16 %


@needs_ngspice
@pytest.mark.parametrize("scenario", STANDARD)
def test_a_miswired_deck_disagrees_on_every_shipped_scenario(scenario, tmp_path):
    cmp = _both("thesis-ch5", scenario, True, tmp_path)
    assert not cmp.agrees(0.01), cmp.lines()


def test_the_interpolation_is_not_the_error():
    """A motion at 10 rad/s recorded every 10 ms (as the ideal simulator records it for spice):
    evaluated at other time points, cubic Hermite with the recorded derivative is within 1e-6 of
    the peak; linear interpolation of the same history would be off by about 0.1 %."""
    class Traj:
        def __init__(self, t, w):
            self.t = t
            self.signals = {"theta": np.sin(w * t), "theta_dot": w * np.cos(w * t), "s": np.cos(w * t)}

    own = Traj(np.arange(0.0, 2.0 + 1e-9, 0.01), 10.0)
    exact = Traj(np.sort(np.random.default_rng(1).uniform(0, 2.0, 5000)), 10.0)
    cmp = compare(exact, own)
    assert cmp.signals["theta"].max_rel < 1e-6  # Hermite: h^4/384 w^4 = 2.6e-7
    assert cmp.signals["s"].max_rel == pytest.approx(0.01 ** 2 * 100 / 8, rel=0.1)  # linear: h^2 w^2 / 8
    assert math.isclose(cmp.t[0], exact.t[0]) and len(cmp.t) == 5000
