"""Shared test fixtures: the repository root and the shipped designs."""

from pathlib import Path

import pytest

import patchgen  # noqa: F401  first, so its one-thread BLAS setting is in place before numpy loads

ROOT = Path(__file__).resolve().parent.parent
DESIGNS = ROOT / "designs"


@pytest.fixture
def root() -> Path:
    return ROOT


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
