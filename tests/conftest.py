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


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory):
    """The gear FMUs of the shipped scenes and the example drive-train FMUs, built once."""
    import sys
    sys.path.insert(0, str(MODELS.parent))
    import build_fmu

    folder = tmp_path_factory.mktemp("fmus")
    fmus = {name: build_fmu.build_gear_fmu(MODELS / f"{name}.toml", folder / f"{name}.fmu")
            for name in ("reference", "torsional", "staggered", "lead_error")}
    motor, fan = build_fmu.build_example_fmus(folder)
    return {**fmus, "motor": motor, "fan": fan}
