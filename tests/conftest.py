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
    """Modules marked heavy first (in collection order), then the rest as collected: the workers
    take whole modules in this order, and a long module started last would keep one worker busy
    while the other idles."""
    items.sort(key=lambda item: item.get_closest_marker("heavy") is None)


def design_path(name: str) -> Path:
    return DESIGNS / f"{name}.toml"
