"""Compile (or load) one group of patchgen's numba kernels by running a small real workload:
``python -m tests.warm_kernels bench`` (the simulator's engine, the plant, swing-up's schedule
kernel) or ``identify`` (bench-test's recordings and identify's filters). tests/conftest.py runs
both side by side while the workers of a run over several collect, so that each kernel is
compiled once into numba's cache rather than by every worker that meets it first at the same
moment. When WARM_DIR_ENV names a folder, ``<group>.done`` is written there at the end, whether
the workload succeeded or not (a failure is the tests' to show: they run the same code)."""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import numpy as np

WARM_DIR_ENV = "PATCHGEN_TESTS_WARM_DIR"
GROUPS = ("bench", "identify")


def bench() -> None:
    from patchgen.bench.simulate import simulate
    from patchgen.design.lqg import design_on
    from patchgen.design.model import plant_params
    from patchgen.inputs.scenario import load_scenario
    from patchgen.inputs.spec import load_spec
    from patchgen.patch.build import build_patch
    from patchgen.profiles.bench import load_bench
    from patchgen.profiles.machine import load_machine
    from patchgen.swingup.schedule import _batch_terminal

    spec, machine, bench_ = load_spec("bench-recommended"), load_machine("gp6"), load_bench("uw-1991")
    net = build_patch(design_on(spec, machine, bench_), machine)
    simulate(net, plant_params(spec), bench_, machine, load_scenario("offset-10deg"), runs=1)
    _batch_terminal(plant_params(spec), np.array([[0.1], [0.3]]), np.array([5.0, -5.0, 5.0]), np.array([0.5]), 0.01)


def identify() -> None:
    from patchgen.identify.benchtest import bench_test_files
    from patchgen.identify.identify import identify as fit
    from patchgen.profiles.bench import load_bench
    from patchgen.profiles.machine import load_machine
    from tests.identify.benches import TRUE_PLANT, true_bench

    folder = Path(tempfile.mkdtemp(prefix="patchgen-warm-"))
    for name, data in bench_test_files(TRUE_PLANT, true_bench(), load_machine("gp6"), 0).items():
        (folder / name).write_bytes(data)
    fit(sorted(str(p) for p in folder.iterdir()), load_bench("uw-1991"))


if __name__ == "__main__":
    try:
        {"bench": bench, "identify": identify}[sys.argv[1]]()
    finally:
        if os.environ.get(WARM_DIR_ENV):
            (Path(os.environ[WARM_DIR_ENV]) / f"{sys.argv[1]}.done").touch()
