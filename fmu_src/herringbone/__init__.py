"""Dynamics of a herringbone Novikov gear train: scenes, model, reference run, the fast
(compiled) run, sweeps, and the FMU.

The package by concept:
- `model/`: parameters, scenes, gear geometry, the mesh, the assembled model (GearTrainModel);
- `integrate/`: the stepping contract and run loop (`contract`), the scipy reference, the
  compiled integrator and its numba kernels (`compiled/`);
- `analysis/`: Floquet stability, mesh phasing and `info`, sweeps, Campbell diagram, plots;
- `fmu/`: the FMI 2.0 co-simulation slave, its builder, and running a scene through an FMU;
- `arguments` (the allowed run arguments), `shipped` (the scenes that come with the package),
  `optional` (the analysis and co-simulation dependencies, imported where used), `suggest`
  ("did you mean"), `cli` (the `herringbone` command, which the library never imports).

The public API: `load_scene`, `scene_from_dict` and `Scene` (SceneError for a bad scene);
`simulate` (the compiled integrator, what the FMU runs) and `reference_simulate` (scipy's),
which give a `Result` and raise ValueError for a bad argument, IntegrationError
(StepBudgetExceeded among them) for a run that cannot go on (the reference warns with
ReferenceAccuracyWarning where it cannot hold its tolerance); `sweep` and its `Protocol`;
`scene_inputs` (a scene's input table for fmpy).

The public API is loaded on first use, so that `import herringbone.fmu.runtime` (which the FMU
runs before numpy is imported, to name a missing dependency) imports nothing heavy.
"""
from __future__ import annotations

import importlib
import importlib.util as _util
import os as _os
import sys as _sys

from .installed import installed_twin as _installed_twin

# An FMU's copy of the package gives way to the same version installed, which has what the
# copy leaves out (installed.py): an import returns what sys.modules holds once it is done
_twin = _installed_twin(__name__, _os.path.dirname(__file__))
if _twin is not None:
    for _name in [name for name in _sys.modules if name.startswith(f"{__name__}.")]:
        del _sys.modules[_name]  # the copy's own (installed): the twin imports its own
    _spec = _util.spec_from_file_location(__name__, _os.path.join(_twin, "__init__.py"),
                                          submodule_search_locations=[_twin])
    assert _spec is not None and _spec.loader is not None
    _sys.modules[__name__] = _util.module_from_spec(_spec)
    _spec.loader.exec_module(_sys.modules[__name__])

# name -> the module that holds it
_API = {
    "Scene": ".model.scene", "SceneError": ".model.scene", "load_scene": ".model.scene",
    "scene_from_dict": ".model.scene",
    "reference_simulate": ".integrate.reference",
    "simulate": ".integrate.compiled_stepper",
    "sweep": ".analysis.sweep", "Protocol": ".analysis.sweep_point",
    # what a run gives and what it raises (besides ValueError for a bad argument)
    "Result": ".integrate.contract", "IntegrationError": ".integrate.contract",
    "StepBudgetExceeded": ".integrate.compiled_stepper", "MissingDependency": ".optional",
    "ReferenceAccuracyWarning": ".integrate.global_error",
    # a scene's input table for fmpy, held between its rows
    "scene_inputs": ".fmu.run",
}
_SUBMODULES = ("model", "integrate", "analysis", "fmu", "arguments", "shipped", "cli", "optional",
               "suggest")
__all__ = ["Scene", "SceneError", "load_scene", "scene_from_dict", "reference_simulate",
           "simulate", "sweep", "Protocol", "Result", "IntegrationError", "StepBudgetExceeded",
           "MissingDependency", "ReferenceAccuracyWarning", "scene_inputs", "__version__"]


def __getattr__(name):
    if name in _API:
        value = getattr(importlib.import_module(_API[name], __name__), name)
    elif name in _SUBMODULES:  # herringbone.model.assembly.GearTrainModel without an import
        value = importlib.import_module(f".{name}", __name__)
    elif name == "__version__":
        value = _version()
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # once: later lookups find it directly
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))


def _version() -> str:
    """The installed distribution's version; in a source tree that is not installed (an FMU's
    resources, a checkout on PYTHONPATH), the version pyproject.toml declares beside it."""
    from importlib import metadata
    from pathlib import Path

    try:
        return metadata.version("herringbone")
    except metadata.PackageNotFoundError:
        pass
    try:
        import tomllib

        pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
        return tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]["version"]
    except (OSError, ValueError, KeyError):
        return "unknown"
