"""Shared test fixtures: the repository root and the shipped designs."""

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

import patchgen  # noqa: F401  first, so its one-thread BLAS setting is in place before numpy loads
from tests.warm_kernels import GROUPS, WARM_DIR_ENV

ROOT = Path(__file__).resolve().parent.parent
DESIGNS = ROOT / "designs"
WARM_TIMEOUT_S = 300.0  # a worker waits this long at most for the kernels to be compiled
_WARMING = pytest.StashKey[list]()


@pytest.fixture
def root() -> Path:
    return ROOT


def pytest_configure(config: pytest.Config) -> None:
    """On the controller of a run over several workers (pytest-xdist), start compiling patchgen's
    numba kernels into numba's cache, the two groups side by side (tests/warm_kernels.py), while
    the workers start and collect; each worker waits for them before its first test
    (pytest_collection_finish). Without it, the workers' first modules meet the same kernels at the
    same moment on a fresh install and each compiles them, about 20 s of CPU twice over. With the
    cache filled it only loads them."""
    if hasattr(config, "workerinput") or not config.getoption("numprocesses", None):
        return
    folder = tempfile.mkdtemp(prefix="patchgen-warm-")
    os.environ[WARM_DIR_ENV] = folder  # the workers, started after this, inherit it
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    config.stash[_WARMING] = [subprocess.Popen([sys.executable, "-m", "tests.warm_kernels", group], cwd=ROOT,
                                               env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                              for group in GROUPS]


def pytest_collection_finish(session: pytest.Session) -> None:
    """A worker waits for the kernels its controller is compiling (pytest_configure)."""
    folder = os.environ.get(WARM_DIR_ENV)
    if not folder or not hasattr(session.config, "workerinput"):
        return
    deadline = time.monotonic() + WARM_TIMEOUT_S
    while not all((Path(folder) / f"{g}.done").exists() for g in GROUPS) and time.monotonic() < deadline:
        time.sleep(0.05)


def pytest_unconfigure(config: pytest.Config) -> None:
    for proc in config.stash.get(_WARMING, []):
        proc.wait()


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


def design_from_path(path, machine=None):
    """A spec file's design on the machine and bench it names (or on ``machine``, a shipped id), as
    patchgen design makes it, and that machine."""
    from patchgen.pipeline.design import run_design
    from patchgen.pipeline.inputs import load_inputs

    inputs = load_inputs(str(path)) if machine is None else load_inputs(str(path), machine=machine)
    return run_design(inputs).design, inputs.machine


def run_patchgen(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    """``python -m patchgen ARGS`` as a user runs it: its exit status and both streams, as text."""
    return subprocess.run([sys.executable, "-m", "patchgen", *args], capture_output=True, text=True, cwd=cwd)
