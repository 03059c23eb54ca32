"""A sweep point through the gear FMU with fmpy, as a user who has only the FMU runs it: the
swept parameters and the protocol's tolerance as start values, the scene's torques as inputs,
one communication step per sample from t = 0 (fmpy.simulate_fmu records every step), the
window cut from the end of the record. The FMU must be built from the sweep's scene
(`herringbone build-fmu SCENE`): the scene it carries (resources/scene.toml) is checked
against the sweep's before any work (`check_fmu`), since only the swept parameters and the
torques are set on it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..arguments import FMU_SCENE_MEMBER, GEAR_FMU_ALLOWED, gear_fmu_problem
from ..model.parameters import INPUTS
from ..shipped import named_as_typed
from .sweep_point import BEARINGS, Protocol, timing

RECORDED = ("F_mesh", "F_mesh_left", "F_mesh_right", "dte", *BEARINGS)


def check_fmu(fmu, scene=None, swept=()) -> None:
    """One line naming the file if `fmu` is not a gear FMU (arguments.gear_fmu_problem), or,
    given the sweep's `scene`, if the FMU was built from another: the scene it carries must
    have the same components, input torques and parameters but the `swept` ones (each point
    sets those); its name, file and experiment do not matter."""
    problem = gear_fmu_problem(Path(fmu))
    if problem is not None:
        raise ValueError(f"through-fmu {fmu}: {problem}; allowed: {GEAR_FMU_ALLOWED}")
    if scene is None:
        return
    difference = scene_difference(carried_scene(fmu), scene, swept)
    if difference is not None:
        raise ValueError(f"through-fmu {fmu}: built from another scene than {scene.name}: "
                         f"{difference}; allowed: an FMU of the sweep's scene (herringbone "
                         f"build-fmu {named_as_typed(scene)})")


def carried_scene(fmu):
    """The scene a gear FMU carries (arguments.FMU_SCENE_MEMBER), validated as the FMU
    validates it; ValueError naming the FMU where it is not a valid scene."""
    import tomllib
    import zipfile

    from ..model.scene import SceneError, scene_from_dict

    source = f"{fmu}:{FMU_SCENE_MEMBER}"
    try:
        with zipfile.ZipFile(fmu) as archive:
            data = tomllib.loads(archive.read(FMU_SCENE_MEMBER).decode("utf-8"))
        return scene_from_dict(data, name=Path(fmu).stem, source=source)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, SceneError) as error:
        raise ValueError(f"through-fmu {fmu}: the scene it carries is not valid ({error}); "
                         f"allowed: {GEAR_FMU_ALLOWED}") from None


def scene_difference(carried, scene, swept=()) -> str | None:
    """The first difference that would make a run of `carried` (an FMU's scene) not a run of
    `scene`, in words, or None: a component, the input torques, a parameter not `swept`."""
    for name in sorted(set(carried.components) | set(scene.components)):
        if carried.components.get(name) != scene.components.get(name):
            return (f"[components] {name} is {carried.components.get(name)} in the FMU's "
                    f"scene, {scene.components.get(name)} in {scene.name}")
    if not set(swept) & set(INPUTS) and carried.inputs != scene.inputs:
        return (f"[inputs] M_motor, M_load are {carried.inputs.M_motor}, "
                f"{carried.inputs.M_load} N·m in the FMU's scene, {scene.inputs.M_motor}, "
                f"{scene.inputs.M_load} N·m in {scene.name}")
    for name in sorted(set(carried.parameters) | set(scene.parameters)):
        mine, theirs = scene.parameters.get(name), carried.parameters.get(name)
        if name not in swept and mine != theirs:
            return f"{name} is {theirs!r} in the FMU's scene, {mine!r} in {scene.name}"
    return None


def run_window_through_fmu(fmu, scene, point, protocol: Protocol) -> dict[str, np.ndarray]:
    """The window's samples from the FMU (same times as sweep_point.run_window)."""
    import fmpy

    from ..fmu.run import scene_inputs

    when = timing(scene, protocol)
    first = round(when.settle / when.interval)
    stop = (first + when.samples - 1) * when.interval
    declared = {v.name for v in fmpy.read_model_description(str(fmu)).modelVariables}
    recorded = [name for name in RECORDED if name in declared]
    start_values = {name: value for name, value in point.values if name not in INPUTS}
    start_values["solver_tolerance"] = protocol.tolerance
    for name in start_values:
        if name not in declared:
            raise ValueError(f"through-fmu {fmu}: the FMU has no parameter {name}; allowed: "
                             "the parameters of the scene it was built from")
    result = fmpy.simulate_fmu(str(fmu), stop_time=stop, output_interval=when.interval,
                               input=scene_inputs(scene, stop), start_values=start_values,
                               output=recorded)
    if len(result) < first + when.samples:
        raise RuntimeError(f"{fmu}: the FMU stopped at t = {result['time'][-1]:g} s of "
                           f"{stop:g} s (run fmpy with debug_logging to see why)")
    window = {name: np.asarray(result[name][first:first + when.samples], dtype=float)
              for name in recorded}
    return {"time": when.sample_times(), **window}
