"""Fixtures of the render tests: one headless Chromium per module for the tests that print sheets."""

import pytest

from .chromium import Chromium, find


@pytest.fixture(scope="module")
def chromium(tmp_path_factory):
    """A Chromium that prints the module's PDFs (one start instead of one a sheet); without
    Chromium the tests that print skip."""
    binary = find()
    if binary is None:
        pytest.skip("chromium is not installed")
    with Chromium(binary, tmp_path_factory.mktemp("chromium")) as browser:
        yield browser
