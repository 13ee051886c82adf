"""Shared test fixtures: the repository root and the shipped designs."""

from pathlib import Path

import pytest

import patchgen  # noqa: F401  first, so its one-thread BLAS setting is in place before numpy loads

ROOT = Path(__file__).resolve().parent.parent
DESIGNS = ROOT / "designs"


@pytest.fixture
def root() -> Path:
    return ROOT


def design_path(name: str) -> Path:
    return DESIGNS / f"{name}.toml"
