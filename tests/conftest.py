import os
from pathlib import Path

# Small matrices only: BLAS threads fighting over two cores slow them tenfold (measured on
# tests/test_stability.py); set before numpy loads BLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import herringbone  # noqa: E402

MODELS = Path(__file__).resolve().parent.parent / "models"

# The forces every comparison of two runs is judged on: the mesh force and the bearing forces
# (a scene without bearings has F_mesh alone).
FORCES = ("F_mesh", "F_brg_pinion_left", "F_brg_pinion_right", "F_brg_wheel_left",
          "F_brg_wheel_right")


def _names(run) -> set[str]:
    """The outputs a run has: a dict's keys, or a structured array's fields (fmpy's result)."""
    names = getattr(getattr(run, "dtype", None), "names", None)
    return set(names if names is not None else run)


def force_errors(a, b, scene) -> dict[str, float]:
    """For each of FORCES that both runs have ({name: samples} as simulate gives them, or
    fmpy's structured array): max |a − b| over the samples, as a fraction of
    GearTrainModel.force_scale() (the static mesh force of the largest input torque).
    `scene`: a Scene or a GearTrainModel."""
    from herringbone.model.assembly import GearTrainModel

    model = scene if isinstance(scene, GearTrainModel) else GearTrainModel(scene)
    scale = model.force_scale()
    present = _names(a) & _names(b)
    return {name: float(np.abs(np.asarray(a[name]) - np.asarray(b[name])).max()) / scale
            for name in FORCES if name in present}


def force_error(a, b, scene) -> float:
    """The standard measure of two runs' disagreement: the largest of `force_errors`."""
    return max(force_errors(a, b, scene).values())


@pytest.fixture(scope="session")
def reference_scene():
    return herringbone.load_scene(MODELS / "reference.toml")


@pytest.fixture(scope="session")
def torsional_scene():
    return herringbone.load_scene(MODELS / "torsional.toml")


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory):
    """The gear FMUs of the shipped scenes and the example drive-train FMUs, built once."""
    from herringbone.fmu import builder

    folder = tmp_path_factory.mktemp("fmus")
    fmus = {name: builder.build_gear_fmu(MODELS / f"{name}.toml", folder / f"{name}.fmu")
            for name in ("reference", "torsional", "staggered", "lead_error")}
    motor, fan = builder.build_example_fmus(folder)
    return {**fmus, "motor": motor, "fan": fan}


@pytest.fixture(scope="session")
def scene_fmu(tmp_path_factory):
    """Build the gear FMU of a scene in models/ on first use, once per session:
    scene_fmu("undamped") is the path of models/undamped.toml's FMU."""
    from herringbone.fmu import builder

    folder = tmp_path_factory.mktemp("scene_fmus")
    built = {}

    def build(name):
        if name not in built:
            built[name] = builder.build_gear_fmu(MODELS / f"{name}.toml", folder / f"{name}.fmu")
        return built[name]

    return build
