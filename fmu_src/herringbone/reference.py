"""The reference integration: scipy's solve_ivp, restarted at every switch (MODEL.md section 10).

Speed is no concern here; this is the anchor every faster integrator is measured against. Each
segment of the run (segments.py) is integrated on its own with the contact set and loaded points
held fixed, and ends exactly at the next contact switch, contact loss or regain, or input change,
so the method keeps its full order everywhere.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from . import segments
from .model import GearTrainModel

# consecutive zero-length segments before a run is declared stuck (chattering contact)
MAX_STALLED_SEGMENTS = 100


def output_times(stop_time: float, output_interval: float) -> np.ndarray:
    """0, h, 2h, … up to stop_time inclusive (stop_time added if h does not divide it)."""
    count = int(np.floor(stop_time / output_interval * (1 + 1e-12)))
    times = np.arange(count + 1) * output_interval
    if stop_time - times[-1] > 1e-9 * output_interval:
        times = np.append(times, stop_time)
    return times


def reference_simulate(scene, stop_time=None, output_interval=None, tolerance=1e-10,
                       method="DOP853", initial_pinion_angle=0.0):
    """Simulate a scene; returns {"time": …, output name: …} sampled every output_interval.

    tolerance: the error allowed per step, relative to the force scale (the static mesh force),
    applied to every state entry through GearTrainModel.state_scales.
    initial_pinion_angle: φp at t = 0 (MODEL.md starts at 0; any other angle must give the same
    run shifted in mesh phase).
    """
    stop_time = scene.experiment.stop_time if stop_time is None else stop_time
    output_interval = scene.experiment.output_interval if output_interval is None \
        else output_interval
    model = GearTrainModel(scene)
    times = output_times(stop_time, output_interval)
    results = {name: np.empty(len(times)) for name in model.output_names}
    absolute_tolerance = tolerance * model.state_scales()

    motor_torque, _ = scene.inputs.at(0.0)
    segment, state = segments.start(model, initial_pinion_angle, motor_torque,
                                    scene.parameters["w0_pinion"])
    input_changes = [t for t in scene.inputs.change_times() if 0.0 < t < stop_time]
    time, sample, stalled = 0.0, 0, 0
    while time < stop_time:
        end = min([stop_time] + [t for t in input_changes if t > time])
        torques = scene.inputs.at(time)
        solution, event = _integrate_segment(model, segment, state, time, end, torques,
                                             method, tolerance, absolute_tolerance)
        reached = solution.t[-1]
        while sample < len(times) and times[sample] < reached:
            _store(results, sample, model.outputs(solution.sol(times[sample]),
                                                  segment.contact_set, segment.loaded))
            sample += 1
        state = solution.y[:, -1]
        stalled = stalled + 1 if reached == time else 0
        if stalled > MAX_STALLED_SEGMENTS:
            raise RuntimeError(f"reference integration stuck at t = {time:.9g} s: contact "
                               "switches without progress (grazing contact)")
        if event is not None:
            segment, state = segments.after(model, segment, event, state)
        time = reached
    # the stop time itself, with the segment that holds from there on
    for sample in range(sample, len(times)):
        _store(results, sample, model.outputs(state, segment.contact_set, segment.loaded))
    return {"time": times, **results}


def _store(results, sample, outputs):
    for name, value in outputs.items():
        results[name][sample] = value


def _integrate_segment(model, segment, state, time, end, torques, method, tolerance,
                       absolute_tolerance):
    """Integrate one segment from `time` towards `end`; stops at its first event."""
    event_list = segments.events(model, segment)
    cache = {}

    def values(t, x):
        key = (t, x.tobytes())
        if key not in cache:
            cache.clear()
            cache[key] = segments.event_values(model, segment, x)
        return cache[key]

    def make_event(index, event):
        def function(t, x):
            return values(t, x)[index]
        function.terminal = True
        function.direction = event.direction
        return function

    solution = solve_ivp(lambda t, x: model.derivative(x, segment.contact_set, segment.loaded,
                                                       *torques),
                         (time, end), state, method=method, rtol=tolerance,
                         atol=absolute_tolerance, dense_output=True,
                         events=[make_event(i, e) for i, e in enumerate(event_list)])
    if solution.status < 0:
        raise RuntimeError(f"reference integration failed at t = {time:.9g} s: "
                           f"{solution.message}")
    if solution.status == 1:
        fired = [i for i, t in enumerate(solution.t_events) if len(t)]
        return solution, event_list[fired[0]]
    return solution, None
