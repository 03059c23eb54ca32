"""Advancing a gear train through its segments with scipy's solve_ivp.

Contract of `ScipyStepper.advance(position, end, torques)`: starting from `position` (time,
state, segment), integrate with the torques held to exactly `end`, integrating each segment on
its own and ending it exactly at its first event (segments.py), so the method keeps its order
across every switch. The result depends only on the position passed in (its step-size hint
included), never on earlier calls: a position saved and restored re-runs identically.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from . import segments
from .model import GearTrainModel

# consecutive zero-length segments before a run is declared stuck (chattering contact)
MAX_STALLED_SEGMENTS = 100


class IntegrationError(RuntimeError):
    """The integrator could not advance (it says where and why)."""


@dataclass(frozen=True)
class Position:
    """Where a run stands: all it takes to go on. Plain data, so it can be copied and pickled."""

    time: float
    state: np.ndarray
    segment: segments.Segment
    step_hint: float | None = None  # the step size to try first (None: let the method choose)
    outputs: np.ndarray | None = None  # model.output_vector here, if the stepper computed it
    # per contact interval, the step size the compiled integrator starts it with (None: no
    # interval entered yet; the scipy stepper goes without)
    first_steps: np.ndarray | None = None


def start_position(model: GearTrainModel, motor_torque: float, pinion_angle: float = 0.0):
    """Time 0: the rigid rotation at w0_pinion on the static deflection (MODEL.md section 6)."""
    segment, state = segments.start(model, pinion_angle, motor_torque,
                                    model.scene.parameters["w0_pinion"])
    return Position(0.0, state, segment)


class ScipyStepper:
    def __init__(self, model: GearTrainModel, tolerance: float, method: str = "DOP853",
                 max_step: float = np.inf):
        self.model = model
        self.tolerance = tolerance
        self.absolute_tolerance = tolerance * model.state_scales()
        self.method = method
        self.max_step = max_step

    def advance(self, position: Position, end: float, torques: tuple[float, float],
                sample_times=(), on_sample=None) -> Position:
        """Integrate to `end`; for every t in `sample_times` with position.time <= t < end,
        call on_sample(t, outputs) with the outputs at t."""
        sample_times = [t for t in sample_times if position.time <= t < end]
        stalled = 0
        while position.time < end:
            solution, event = self._integrate_segment(position, end, torques,
                                                      dense_output=bool(sample_times))
            reached = solution.t[-1]
            segment = position.segment
            while sample_times and sample_times[0] < reached:
                t = sample_times.pop(0)
                on_sample(t, self.model.outputs(solution.sol(t), segment.contact_set,
                                                segment.loaded))
            stalled = stalled + 1 if reached == position.time else 0
            if stalled > MAX_STALLED_SEGMENTS:
                raise IntegrationError(f"stuck at t = {reached:.9g} s: contact switches "
                                       "without progress. If the pinion sits on a switch, "
                                       "its points take load at once (edge_ramp = 0) and "
                                       "throw it back: give edge_ramp > 0 (e.g. 1e-3 m)")
            state = solution.y[:, -1]
            if event is not None:
                segment, state = segments.after(self.model, segment, event, state)
            position = Position(reached, state, segment, _step_hint(solution, position))
        return position

    def _integrate_segment(self, position, end, torques, dense_output):
        """One segment from position.time towards `end`; stops at its first event. The dense
        output (three more evaluations a step for DOP853) is kept only for sampling."""
        model, segment = self.model, position.segment
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

        first_step = None if position.step_hint is None else min(position.step_hint,
                                                                 end - position.time)
        solution = solve_ivp(lambda t, x: model.derivative(x, segment.contact_set,
                                                           segment.loaded, *torques),
                             (position.time, end), position.state, method=self.method,
                             rtol=self.tolerance, atol=self.absolute_tolerance,
                             dense_output=dense_output, first_step=first_step,
                             max_step=self.max_step,
                             events=[make_event(i, e) for i, e in enumerate(event_list)])
        if solution.status < 0 or not np.all(np.isfinite(solution.y[:, -1])):
            raise IntegrationError(f"integration failed at t = {position.time:.9g} s: "
                                   f"{solution.message}")
        if solution.status == 1:
            fired = [i for i, t in enumerate(solution.t_events) if len(t)]
            return solution, event_list[fired[0]]
        return solution, None


def _step_hint(solution, position):
    """The last full step the method took (the final one is cut short by the segment's end)."""
    steps = np.diff(solution.t)
    if len(steps) >= 2:
        return float(steps[-2])
    return position.step_hint
