"""identify against known truth: bench-test's recordings of a bench and plant unlike uw-1991 and
table B.1 (tests/identify/benches.py), with the profile's noise and random forces, fitted seed by
seed. Each identified value must fall inside its own reported 95 % interval in at least 90 % of
the seeds, and the estimates must centre on the truth."""

from __future__ import annotations

import numpy as np
import pytest

from patchgen.identify.benchtest import bench_test_files
from patchgen.identify.identify import identify
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from tests.identify.benches import TRUE_BENCH, TRUE_PLANT, true_bench

pytestmark = pytest.mark.heavy(30)  # seconds, roughly: see tests/conftest.py

SEEDS = range(60)  # the first sixty seeds, no others: 90 % of them is 54
TRUE = dict(TRUE_BENCH, l=TRUE_PLANT.l, b_VF=TRUE_PLANT.b_VF, c=TRUE_PLANT.c)


@pytest.fixture(scope="module")
def fitted(tmp_path_factory) -> list[dict]:
    """Each seed's identified parameters (bench and plant), name -> Parameter."""
    bench, machine, base = true_bench(), load_machine("gp6"), load_bench("uw-1991")
    out = []
    for seed in SEEDS:
        folder = tmp_path_factory.mktemp(f"seed{seed}")
        for name, data in bench_test_files(TRUE_PLANT, bench, machine, seed).items():
            (folder / name).write_bytes(data)
        result = identify(sorted(str(p) for p in folder.iterdir()), base)
        out.append({**result.bench, **result.plant})
    return out


@pytest.mark.parametrize("key", list(TRUE))
def test_each_value_inside_its_interval_in_90_percent_of_seeds(fitted, key):
    truth = TRUE[key]
    estimates = [f[key].estimate for f in fitted]
    assert all(e is not None for e in estimates), f"{key} has no interval"
    inside = sum(e.low <= truth <= e.high for e in estimates)
    assert inside >= 0.9 * len(SEEDS), f"{key}: {inside} of {len(SEEDS)} intervals hold {truth}"
    # and the estimates centre on the truth: their mean within three standard errors of the mean
    values = np.array([e.value for e in estimates])
    assert abs(values.mean() - truth) <= 3 * values.std(ddof=1) / np.sqrt(values.size), (key, values.mean())


def test_the_identified_model_is_the_bench_s(fitted):
    assert all(f["actuator.model"].value == "lag" for f in fitted)
