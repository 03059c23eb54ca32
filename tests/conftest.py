from pathlib import Path

import pytest

import herringbone

MODELS = Path(__file__).resolve().parent.parent / "models"


@pytest.fixture(scope="session")
def reference_scene():
    return herringbone.load_scene(MODELS / "reference.toml")


@pytest.fixture(scope="session")
def torsional_scene():
    return herringbone.load_scene(MODELS / "torsional.toml")
