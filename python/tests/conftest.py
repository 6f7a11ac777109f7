"""Shared paths: the tests run from a checkout of the repository, whose assets they load."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
ASSETS = ROOT / "assets"


@pytest.fixture
def assets() -> Path:
    return ASSETS
