"""Running a scene through its FMU with fmpy: the scene's experiment and input torques."""
from __future__ import annotations

import numpy as np

from ..arguments import STOP_TIME, check_scene


def scene_inputs(scene, stop_time: float) -> np.ndarray:
    """The scene's input table as fmpy's `input`, held between rows (not ramped).

    fmpy interpolates a Real input linearly between the rows it is given; at a time stamp
    given twice it takes the second row from that time on (its Input class, `after_event`).
    So each change of the table is written as two rows at its time, the old torques and the
    new, and the torques hold between changes, as a co-simulation master holds inputs over a
    communication step (and as herringbone.simulate runs the table).

    Parameters
    ----------
    scene : Scene
    stop_time : float
        Seconds; the last row holds the last torques to here.

    Returns
    -------
    numpy.ndarray
        Structured, fields "time" (s), "M_motor" and "M_load" (N·m): pass it as
        `fmpy.simulate_fmu(..., input=scene_inputs(scene, stop_time))`.

    Raises
    ------
    SceneError
        `scene` is no Scene.
    ValueError
        `stop_time` is not finite and > 0.

    Examples
    --------
    >>> import herringbone
    >>> herringbone.scene_inputs(herringbone.load_scene("torque_step"), 0.02).tolist()
    [(0.0, 500.0, 1800.0), (0.005, 500.0, 1800.0),
     (0.005, 5000.0, 18000.0), (0.02, 5000.0, 18000.0)]
    """
    check_scene(scene)
    STOP_TIME.check(stop_time)
    rows = []
    schedule = scene.inputs
    for i, time in enumerate(schedule.times):
        if i > 0:
            rows.append((time, schedule.M_motor[i - 1], schedule.M_load[i - 1]))
        rows.append((time, schedule.M_motor[i], schedule.M_load[i]))
    rows.append((max(stop_time, rows[-1][0]), schedule.M_motor[-1], schedule.M_load[-1]))
    return np.array(rows, dtype=[("time", float), ("M_motor", float), ("M_load", float)])


def simulate_scene_fmu(fmu_path, scene, stop_time=None, output_interval=None,
                       start_values=None, step_finished=None, output=None
                       ) -> dict[str, np.ndarray]:
    """Simulate a gear FMU with fmpy under the scene's experiment and inputs; the
    communication step is the output interval; `step_finished(time, recorder)` is fmpy's,
    called after each step (it returns True to go on); `output`: the names of the variables
    to record (None: the FMU's outputs). Returns {"time": …, name: …}."""
    import fmpy

    stop_time = stop_time or scene.experiment.stop_time
    output_interval = output_interval or scene.experiment.output_interval
    result = fmpy.simulate_fmu(str(fmu_path), stop_time=stop_time,
                               output_interval=output_interval,
                               input=scene_inputs(scene, stop_time),
                               start_values=start_values or {},
                               step_finished=step_finished, output=output)
    if result["time"][-1] < stop_time - 1e-9 * output_interval:
        raise RuntimeError(f"{fmu_path}: the FMU stopped at t = {result['time'][-1]:g} s "
                           "(run with fmpy's debug_logging to see why)")
    return {name: np.asarray(result[name], dtype=float) for name in result.dtype.names}
