"""The reference integration: scipy's DOP853, restarted at every switch.

Speed is a lesser concern here; this is the anchor every faster integrator is measured against.
Each segment of the run (segments.py) is integrated on its own with the contact set and loaded
points held fixed, and ends exactly at the next contact switch, contact loss or regain, or input
change, so the method keeps its full order everywhere (stepping.py). It shares the equations of
motion and the mesh geometry with the compiled integrator, but finds its events and decides what
follows them by its own rule (segments.py, stepping.py), so that the two check each other.
"""
from __future__ import annotations

import numpy as np

from .arguments import check_reference_run, check_run_times
from .model import GearTrainModel
from .stepping import ScipyStepper, start_position


def output_times(stop_time: float, output_interval: float) -> np.ndarray:
    """0, h, 2h, … up to stop_time inclusive (stop_time added if h does not divide it)."""
    count = int(np.floor(stop_time / output_interval * (1 + 1e-12)))
    times = np.arange(count + 1) * output_interval
    if stop_time - times[-1] > 1e-9 * output_interval:
        times = np.append(times, stop_time)
    return times


def reference_simulate(scene, stop_time=None, output_interval=None, tolerance=1e-10,
                       method="DOP853", initial_pinion_angle=0.0, check_tension=False):
    """Simulate a scene; returns {"time": …, output name: …} sampled every output_interval.

    tolerance: the error allowed per step, relative to the force scale (the static mesh force),
    applied to every state entry through GearTrainModel.state_scales.
    initial_pinion_angle: φp at t = 0 (MODEL.md starts at 0; any other angle must give the same
    run shifted in mesh phase).
    check_tension: raise IntegrationError wherever a loaded point pulls or a free one penetrates
    (stepping.ScipyStepper's debug check; it costs a third more time).
    Arguments outside arguments.check_reference_run's ranges (tolerance in [1e-12, 1e-5], a
    solve_ivp method) raise ValueError before any work.
    """
    check_reference_run(scene, stop_time, output_interval, tolerance, method,
                        initial_pinion_angle)
    stepper = ScipyStepper(GearTrainModel(scene), tolerance, method, check_tension=check_tension)
    return simulate_with(stepper, scene,
                         stop_time, output_interval, initial_pinion_angle)


def simulate_with(stepper, scene, stop_time=None, output_interval=None,
                  initial_pinion_angle=0.0):
    """Run a scene with a stepper (stepping.ScipyStepper, integrator.CompiledStepper: anything
    with `model` and `advance(position, end, torques, sample_times, on_sample)`), sampling the
    outputs every output_interval; returns {"time": …, output name: …}. A bad span or start
    raises ValueError before any work (arguments.check_run_times)."""
    check_run_times(scene, stop_time, output_interval, initial_pinion_angle)
    stop_time = scene.experiment.stop_time if stop_time is None else stop_time
    output_interval = scene.experiment.output_interval if output_interval is None \
        else output_interval
    model = stepper.model
    times = output_times(stop_time, output_interval)
    results = {name: np.empty(len(times)) for name in model.output_names}
    index = {t: i for i, t in enumerate(times)}

    def store(t, outputs):
        for name, value in outputs.items():
            results[name][index[t]] = value

    position = start_position(model, scene.inputs.at(0.0)[0], initial_pinion_angle)
    changes = [t for t in scene.inputs.change_times() if 0.0 < t < stop_time]
    for start, end in zip([0.0] + changes, changes + [stop_time]):
        position = stepper.advance(position, end, scene.inputs.at(start), times, store)
    # the stop time itself, with the segment that holds from there on
    store(times[-1], model.outputs(position.state, position.segment.contact_set,
                                   position.segment.loaded))
    return {"time": times, **results}
