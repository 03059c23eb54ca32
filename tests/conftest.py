import os
import sys

# Small matrices only: BLAS threads fighting over two cores slow them tenfold (measured on
# tests/analysis/test_stability.py); set before numpy loads BLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import pytest  # noqa: E402
from helpers import MODELS  # noqa: E402

import herringbone  # noqa: E402

# the fixtures every folder of tests shares; the shared functions live in helpers/


@pytest.fixture(autouse=True)
def _compiles_said_before_the_test():
    """An announcement of compiles that are done ends a second after the last, from a thread
    of its own (compiling/announce.py): in a test process it would land in the next test's
    captured stderr, which may assert a command's one line. Said here, before the test
    captures anything (on a warm cache there is none)."""
    announce = sys.modules.get("herringbone.compiling.announce")
    if announce is not None:
        announce.finish()


@pytest.fixture(scope="session")
def reference_scene():
    return herringbone.load_scene(MODELS / "reference.toml")


@pytest.fixture(scope="session")
def torsional_scene():
    return herringbone.load_scene(MODELS / "torsional.toml")


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory, scene_fmu):
    """The gear FMUs of four shipped scenes (scene_fmu's: a worker builds each once) and the
    example drive-train FMUs, built once."""
    from herringbone.fmu import builder

    fmus = {name: scene_fmu(name) for name in ("reference", "torsional", "staggered",
                                                "lead_error")}
    motor, fan = builder.build_example_fmus(tmp_path_factory.mktemp("fmus"))
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
