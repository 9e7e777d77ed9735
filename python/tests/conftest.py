"""Shared fixtures: where the repository's data and the built tools are."""
import os
import pathlib

import pytest

SOURCE = pathlib.Path(os.environ.get("HAPTICFIELD_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


@pytest.fixture
def coffee():
    return str(SOURCE / "examples" / "data" / "coffee.png")


@pytest.fixture
def hatt_dir():
    return SOURCE / "tests" / "data" / "hatt"
