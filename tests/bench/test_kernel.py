"""The blocked kernel: its noise (Philox bits, ziggurat normals), its sine, and its runs against
the per-run loop it replaced, run for run on the same noise; a run's result depends on nothing
but its own draws (not its block, its place in it, the threads)."""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import numpy as np
import pytest
from scipy import stats

from patchgen.bench import kernel
from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config
from patchgen.bench.engine import draw_batch, run_batch
from patchgen.bench.lanes import TERMS, input_groups
from patchgen.bench.noise import ZIGGURAT_EDGES, philox, run_normals
from patchgen.design.model import plant_params
from patchgen.inputs.scenario import Scenario, load_scenario
from patchgen.patch.build import build_patch
from patchgen.plant.compiled import sincos
from patchgen.profiles.bench import load_bench
from tests.conftest import ROOT, design_from_path, design_path

from .engine_reference import reference_runs

SIMS = ROOT / "sims"
FIELDS = ("trip_time", "fall_time", "max_abs_theta", "max_abs_s", "rms_theta", "max_abs_u_c",
          "max_abs_force", "limit_time", "overload_first", "overload_time", "amp_peak", "final_state")


@pytest.mark.parametrize("ctr, key, expected", [
    # Random123's known-answer vectors for philox4x32-10: counter, key, output
    ((0, 0, 0, 0), (0, 0), (0x6627E8D5, 0xE169C58D, 0xBC57AC4C, 0x9B00DBD8)),
    ((0xFFFFFFFF,) * 4, (0xFFFFFFFF,) * 2, (0x408F276D, 0x41C83B0E, 0xA20BC7C6, 0x6D5451FD)),
    ((0x243F6A88, 0x85A308D3, 0x13198A2E, 0x03707344), (0xA4093822, 0x299F31D0),
     (0xD16CFE09, 0x94FDCCEB, 0x5001E420, 0x24126EA1)),
])
def test_philox_known_answers(ctr, key, expected):
    out = philox(*(np.uint64(c) for c in ctr), *(np.uint64(k) for k in key))
    assert tuple(int(v) for v in out) == expected


def test_ziggurat_layers_close_at_the_top():
    """Equal-area layers from r: the last edge above 0 leaves exactly one layer's area."""
    x = ZIGGURAT_EDGES
    r = x[1]
    v = r * math.exp(-r * r / 2) + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2))
    assert v / x[-2] + math.exp(-x[-2] ** 2 / 2) == pytest.approx(1.0, abs=1e-12)


def test_normals_are_standard_normal():
    z = run_normals(12345, 678, 50_000, 8).ravel()  # 400 008 draws
    assert abs(z.mean()) < 5 * 1 / math.sqrt(z.size)
    assert z.var() == pytest.approx(1.0, abs=0.01)
    assert stats.kstest(z, "norm").pvalue > 0.01
    assert abs(stats.kurtosis(z)) < 0.05
    for k in (2.0, 3.0, 4.0):  # the tails, where the wedges and the tail draw take over
        p = 2 * stats.norm.sf(k)
        assert abs(np.mean(np.abs(z) > k) - p) < 5 * math.sqrt(p / z.size)
    other = run_normals(12346, 678, 1000, 8)
    assert abs(np.corrcoef(other.ravel(), z[:other.size])[0, 1]) < 0.05


def test_sincos_is_libm_to_a_few_ulp():
    xs = np.concatenate([np.linspace(-60, 60, 20001), np.geomspace(1e-300, 1.0, 500),
                         [0.0, -0.0, math.pi / 4, math.pi / 2, math.pi, 1e4]])
    for x in xs:
        s, c = sincos(x)
        assert abs(s - math.sin(x)) <= 4e-16 * max(1.0, abs(x) / 10)
        assert abs(c - math.cos(x)) <= 4e-16 * max(1.0, abs(x) / 10)


def _config(design: str, scenario: str, *, ideal=False, spread=None, duration=None, machine=None):
    d, machine = design_from_path(design_path(design), machine)
    net = build_patch(d, machine)
    base = load_scenario(SIMS / f"{scenario}.toml").model_dump()
    if duration:
        base["duration_s"] = duration
    bench = load_bench(d.spec.bench, d.spec.path)
    cfg, _ = engine_config(compile_circuit(net, machine, bench), plant_params(d.spec), bench, machine,
                           Scenario.model_validate(base), ideal=ideal, spread=spread)
    return cfg


CASES = {  # held with noise and drift; tripped with overloads; ideal with a push; spread plants
    "hold": ("bench-recommended", "hold-120s", False, None, 10.0),
    "trip": ("thesis-ch5", "offset-10deg", False, None, None),
    "ideal": ("thesis-ch5", "finger-push", True, None, None),
    "spread": ("bench-recommended", "step-cart", False, {"M": 0.2, "l": 0.2, "b_VF": 0.2}, None),
    # a motor at its amplifier's limit, encoder counts, a filtered velocity; the rigid pendulum
    "motor": ("quanser-ip02", "ip02-release-5deg", False, None, 3.0),
    # a machine without a differentiator: the rate from theta minus its lag, the lag starting settled
    "difference": ("bench-recommended", "offset-10deg", False, None, 3.0, "lucidac"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_blocks_match_the_per_run_loop(case):
    """70 runs (a full block and part of another) against the old one-run loop fed the same
    normals: the same events at the same steps, figures and histories to 1e-9."""
    design, scenario, ideal, spread, duration, *machine = CASES[case]
    cfg = _config(design, scenario, ideal=ideal, spread=spread, duration=duration, machine=(machine or [None])[0])
    draws = draw_batch(cfg, [np.random.default_rng([3, i]) for i in range(70)])
    new = run_batch(cfg, draws, 1)
    ref = reference_runs(cfg, draws)
    for name in FIELDS:
        a, b = getattr(new, name), ref[name]
        assert np.array_equal(np.isnan(a), np.isnan(b)), name
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9, err_msg=name)
    assert new.history_length[0] == ref["history_length"][0]
    k = new.history_length[0]
    np.testing.assert_allclose(new.history[0, :k], ref["history"][0, :k], rtol=1e-9, atol=1e-9)
    if case == "trip":
        assert not np.isnan(new.trip_time).any() and not np.isnan(new.overload_first).all()
    if case == "difference":  # the path the case is for was taken: a lag with no IC, settled on theta
        assert np.isnan(cfg.wiring.ic).sum() == 1
    if case == "motor":  # the paths the case is for were taken
        assert (new.limit_time > 0).all() and cfg.sensors.quantum.any() and (cfg.sensors.filt >= 0).any()


def test_a_run_is_the_same_in_any_block_and_on_any_number_of_threads():
    """Bit for bit: run i alone, in a small block, at another place in a block, one thread."""
    cfg = _config("bench-recommended", "hold-120s", duration=2.0)
    rngs = lambda lo, hi: [np.random.default_rng([9, i]) for i in range(lo, hi)]
    full = run_batch(cfg, draw_batch(cfg, rngs(0, 150)), 1)
    alone = run_batch(cfg, draw_batch(cfg, rngs(0, 1)), 1)
    shifted = run_batch(cfg, draw_batch(cfg, rngs(37, 140)), 0)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        single = run_batch(cfg, draw_batch(cfg, rngs(0, 150)), 1)
    finally:
        numba.set_num_threads(threads)
    for name in FIELDS:
        a = getattr(full, name)
        np.testing.assert_array_equal(getattr(alone, name), a[:1], err_msg=name)
        np.testing.assert_array_equal(getattr(shifted, name), a[37:140], err_msg=name)
        np.testing.assert_array_equal(getattr(single, name), a, err_msg=name)
    np.testing.assert_array_equal(alone.history, full.history)


@pytest.mark.parametrize("module", ["patchgen.bench.kernel", "patchgen.identify.motion", "patchgen.swingup.schedule"])
def test_the_kernel_names_the_code_compiled_into_it(module):
    """numba's cache of a compiled module is stamped with that file alone: a change in a file whose
    functions are compiled into it must change it too, through its COMPILED_IN. Every module that
    compiles the plant's equations (patchgen/plant/compiled.py) carries one."""
    mod = importlib.import_module(module)
    package = Path(kernel.__file__).parents[1]
    assert "plant/compiled.py" in mod.COMPILED_FILES
    digest = hashlib.sha256()
    for name in mod.COMPILED_FILES:
        digest.update((package / name).read_bytes())
    assert mod.COMPILED_IN == digest.hexdigest()[:16], (
        f"{', '.join(mod.COMPILED_FILES)} changed: set COMPILED_IN = {digest.hexdigest()[:16]!r} "
        f"in {module.replace('.', '/')}.py")


def test_every_module_compiling_the_plant_names_it():
    """A module that imports the compiled plant is among those the test above checks."""
    package = Path(kernel.__file__).parents[1]
    users = {str(p.relative_to(package.parent).with_suffix("")).replace("/", ".") for p in package.rglob("*.py")
             if "from patchgen.plant.compiled import" in p.read_text() and "nb.njit" in p.read_text()}
    assert users == {"patchgen.bench.kernel", "patchgen.bench.lanes", "patchgen.identify.motion",
                     "patchgen.swingup.schedule"}
    assert "bench/lanes.py" in kernel.COMPILED_FILES  # lanes is compiled into the kernel, which names it


def test_compile_notice_only_when_numba_will_compile(tmp_path):
    """will_compile reads numba's disk cache: True in a fresh cache, False once it is written."""
    (tmp_path / "tiny.py").write_text(textwrap.dedent("""
        import numba
        @numba.njit(cache=True)
        def twice(x):
            return 2.0 * x
    """))
    probe = textwrap.dedent("""
        import sys, tiny
        from patchgen.bench.engine import will_compile
        before = will_compile(tiny.twice, (1.0,))
        tiny.twice(1.0)
        print(before, will_compile(tiny.twice, (1.0,)))
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=f"{tmp_path}:{ROOT}")
    runs = [subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env,
                           check=True).stdout.split() for _ in range(2)]
    assert runs == [["True", "False"], ["False", "False"]]


def test_input_groups_pad_with_the_zero_signal():
    """Groups of TERMS in order, padded at gain 0 from the zero row; an unwired amplifier gets one."""
    ptr, src, gain = input_groups(np.array([0, 6, 6, 7]), np.arange(7), np.arange(1.0, 8.0), zero_row=99)
    assert ptr.tolist() == [0, 2, 3, 4]
    assert src.tolist() == [[0, 1, 2, 3], [4, 5, 99, 99], [99] * TERMS, [6, 99, 99, 99]]
    assert gain.tolist() == [[1, 2, 3, 4], [5, 6, 0, 0], [0] * TERMS, [7, 0, 0, 0]]


def test_an_amplifier_with_more_inputs_than_a_pass_sums():
    """A summer of TERMS + 2 inputs (bench-recommended's cart and pendulum summer, each input split
    in two halves) runs as the per-run loop runs it, and as the patch it stands for does."""
    cfg = _config("bench-recommended", "step-cart", duration=3.0)
    w = cfg.wiring
    j = int(np.argmax(np.diff(w.in_ptr)))  # the summer with the most inputs (3)
    lo, hi = w.in_ptr[j], w.in_ptr[j + 1]
    src = np.concatenate([w.in_src[:lo], np.repeat(w.in_src[lo:hi], 2), w.in_src[hi:]])
    gain = np.concatenate([w.in_gain[:lo], np.repeat(w.in_gain[lo:hi] / 2, 2), w.in_gain[hi:]])
    ptr = w.in_ptr + np.where(np.arange(len(w.in_ptr)) > j, hi - lo, 0)
    assert ptr[j + 1] - ptr[j] > TERMS
    zero = len(cfg.noise.a)
    split = dataclasses.replace(cfg, wiring=w._replace(in_ptr=ptr, in_src=src, in_gain=gain,
                                                       **dict(zip(("group_ptr", "group_src", "group_gain"),
                                                                  input_groups(ptr, src, gain, zero)))))
    draws = draw_batch(split, [np.random.default_rng([5, i]) for i in range(20)])
    new, ref, whole = run_batch(split, draws, 1), reference_runs(split, draws), run_batch(cfg, draws, 1)
    for name in FIELDS:
        np.testing.assert_allclose(getattr(new, name), ref[name], rtol=1e-9, atol=1e-9, err_msg=name)
        np.testing.assert_allclose(getattr(new, name), getattr(whole, name), rtol=1e-6, atol=1e-9, err_msg=name)
