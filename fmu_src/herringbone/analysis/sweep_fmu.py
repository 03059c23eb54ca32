"""A sweep point through the gear FMU with fmpy, as a user who has only the FMU runs it: the
swept parameters and the protocol's tolerance as start values, the scene's torques as inputs,
one communication step per sample from t = 0 (fmpy.simulate_fmu records every step), the
window cut from the end of the record. The FMU must be built from the sweep's scene
(`herringbone build-fmu SCENE`): its other parameters are the scene's by construction.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..model.parameters import INPUTS
from .sweep_point import BEARINGS, Protocol, timing

RECORDED = ("F_mesh", "F_mesh_left", "F_mesh_right", "dte", *BEARINGS)


def check_fmu(fmu) -> None:
    """One line naming the file if `fmu` is not an FMU file."""
    path = Path(fmu)
    if path.suffix != ".fmu" or not path.is_file():
        raise ValueError(f"through-fmu {fmu}: no such FMU file; allowed: the path of a gear "
                         "FMU (herringbone build-fmu SCENE -o FILE.fmu builds one)")


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
