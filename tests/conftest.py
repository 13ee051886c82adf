"""Shared test fixtures: the repository root and the shipped designs."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import patchgen  # noqa: F401  first, so its one-thread BLAS setting is in place before numpy loads

ROOT = Path(__file__).resolve().parent.parent
DESIGNS = ROOT / "designs"


@pytest.fixture
def root() -> Path:
    return ROOT


def pytest_configure(config: pytest.Config) -> None:
    """Before the workers of a run over several (pytest-xdist) start, compile patchgen's numba
    kernels into numba's cache once, the two groups side by side (tests/warm_kernels.py): without
    it, the workers' first modules meet the same kernels at the same moment on a fresh install and
    each compiles them, about 20 s of CPU twice over. With the cache filled it only loads them."""
    if hasattr(config, "workerinput") or not config.getoption("numprocesses", None):
        return
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    groups = [subprocess.Popen([sys.executable, "-m", "tests.warm_kernels", group], cwd=ROOT, env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for group in ("bench", "identify")]
    for proc in groups:
        proc.wait()  # a failure is the tests' to show: they run the same code


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Modules marked ``heavy(seconds)`` first, the longest first, then the rest as collected: the
    workers take whole modules in this order, so the long ones start early, the short ones fill in
    at the end, and neither worker idles while the other finishes a long module. The seconds are
    a rough guide (a warm run on two cores); only their order matters."""
    def weight(item: pytest.Item) -> float:
        mark = item.get_closest_marker("heavy")
        return -mark.args[0] if mark is not None else 0.0

    items.sort(key=weight)


def design_path(name: str) -> Path:
    return DESIGNS / f"{name}.toml"
