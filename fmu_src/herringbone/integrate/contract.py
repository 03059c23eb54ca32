"""The stepping contract: what every integrator of the gear train takes and gives, and the one
run loop that drives them.

- `Position`: where a run stands (time, state, segment, step-size hints): all it takes to go on;
- `Stepper`: what an integrator is to the run loop: its `model`, and `advance(position, end,
  torques, sample_times, on_sample)`, which integrates with the torques held to exactly `end`,
  stopping on every contact switch, and depends on nothing but the position passed in. The scipy
  reference (stepping.ScipyStepper) and the compiled integrator
  (compiled_stepper.CompiledStepper) both satisfy it; a `SamplingStepper` (the compiled one)
  also writes its samples into an array, with no Python per sample;
- `IntegrationError`: an integrator could not advance (it says where and why); `Result`: the
  outputs of a run;
- `start_position`: the initial condition every integrator starts from;
- `output_times`, `simulate_with`: the output grid and the run loop (a scene's input table,
  sampled every output interval) that herringbone.reference_simulate, herringbone.simulate, the
  command line and the benchmarks all run.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ..arguments import check_run_times
from ..model.assembly import GearTrainModel
from ..model.parameters import unit_of
from . import segments


class IntegrationError(RuntimeError):
    """The integrator could not advance (it says where and why)."""


class Result(dict):
    """A run's outputs: {"time": sample times, s; output name: samples}, numpy arrays of one
    length, in SI units (`units`); a dict, so `result["F_mesh"]` and `list(result)` work as
    they always have. `steps`: the compiled integrator's internal steps over the run, what
    its cost grows with (an exact segment of the exponential method is one); None where they
    are not counted (the scipy reference)."""

    steps: int | None = None

    @property
    def time(self) -> np.ndarray:
        """The sample times, s."""
        return self["time"]

    @property
    def units(self) -> dict[str, str]:
        """The unit of each column ("time": "s", "F_mesh": "N", "dte": "m", …)."""
        return {name: unit_of(name) for name in self}


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
    """Time 0: the rigid rotation at w0_pinion on the static deflection (docs/model.md
    section 6)."""
    segment, state = segments.start(model, pinion_angle, motor_torque,
                                    model.scene.parameters["w0_pinion"])
    return Position(0.0, state, segment)


@runtime_checkable
class Stepper(Protocol):
    """An integrator of the gear train, as the run loop (`simulate_with`) and the sweeps use it."""

    model: GearTrainModel

    def advance(self, position: Position, end: float, torques: tuple[float, float],
                sample_times=(), on_sample: Callable[[float, dict], None] | None = None
                ) -> Position:
        """Integrate from `position` to exactly `end` with the torques held; for every t in
        `sample_times` with position.time <= t < end, call on_sample(t, outputs) with the
        outputs at t. The result depends only on the position passed in."""


@runtime_checkable
class SamplingStepper(Stepper, Protocol):
    """A Stepper that also samples into an array (`simulate_with` takes this way where it is
    given no on_sample)."""

    def advance_sampled(self, position: Position, end: float, torques: tuple[float, float],
                        times: np.ndarray, rows: np.ndarray) -> Position:
        """Integrate from `position` to exactly `end` with the torques held; rows[k] gets the
        outputs (model.output_layout) at times[k], rising, in [position.time, end)."""


def output_times(stop_time: float, output_interval: float) -> np.ndarray:
    """0, h, 2h, … up to stop_time inclusive (stop_time added if h does not divide it); the
    last is stop_time itself, not k·h a rounding past it (3·0.1 is 0.30000000000000004)."""
    count = int(np.floor(stop_time / output_interval * (1 + 1e-12)))
    times = np.arange(count + 1) * output_interval
    if stop_time - times[-1] > 1e-9 * output_interval:
        times = np.append(times, stop_time)
    times[-1] = stop_time
    return times


def simulate_with(stepper: Stepper, scene, stop_time=None, output_interval=None,
                  initial_pinion_angle=0.0, on_sample=None):
    """Run a scene with a stepper (stepping.ScipyStepper, compiled_stepper.CompiledStepper:
    anything that is a `Stepper`), sampling the outputs every output_interval; returns
    {"time": …, output name: …}. `on_sample(t, outputs)`, if given, is called after each sample
    is stored (the benchmarks watch their budget through it; an exception it raises ends the
    run). A bad span or start raises ValueError before any work (arguments.check_run_times).
    Without on_sample, a SamplingStepper samples each piece of the input table into an array
    (`sampled_run`), the same numbers to the bit. The Result's `steps` are the stepper's
    `accepted_steps` over the run, where it counts them (the compiled one)."""
    check_run_times(scene, stop_time, output_interval, initial_pinion_angle)
    stop_time = scene.experiment.stop_time if stop_time is None else stop_time
    output_interval = scene.experiment.output_interval if output_interval is None \
        else output_interval
    times = output_times(stop_time, output_interval)
    before = getattr(stepper, "accepted_steps", None)
    if on_sample is None and isinstance(stepper, SamplingStepper):
        result = sampled_run(stepper, scene, stop_time, times, initial_pinion_angle)
    else:
        result = run_sampled_by_call(stepper, scene, stop_time, times, initial_pinion_angle,
                                     on_sample)
    after = getattr(stepper, "accepted_steps", None)
    if before is not None and after is not None:
        result.steps = after - before
    return result


def run_sampled_by_call(stepper: Stepper, scene, stop_time: float, times: np.ndarray,
                        initial_pinion_angle=0.0, on_sample=None) -> Result:
    """simulate_with's run through Stepper.advance (its arguments checked there): each sample
    handed over as a dict and stored, then to `on_sample(t, outputs)` where one is given."""
    model = stepper.model
    results = {name: np.empty(len(times)) for name in model.output_names}
    index = {t: i for i, t in enumerate(times)}

    def store(t, outputs):
        for name, value in outputs.items():
            results[name][index[t]] = value
        if on_sample is not None:
            on_sample(t, outputs)

    position = start_position(model, scene.inputs.at(0.0)[0], initial_pinion_angle)
    for start, end in input_pieces(scene, stop_time):
        position = stepper.advance(position, end, scene.inputs.at(start), times, store)
    store(times[-1], final_outputs(model, position))
    return Result(time=times, **results)


def input_pieces(scene, stop_time: float) -> list[tuple[float, float]]:
    """(start, end) of each piece of the scene's input table within [0, stop_time] (s): the
    torques hold over each."""
    changes = [t for t in scene.inputs.change_times() if 0.0 < t < stop_time]
    return list(zip([0.0] + changes, changes + [stop_time]))


def final_outputs(model, position: Position) -> dict[str, float]:
    """The outputs at the stop time itself, with the segment that holds from there on."""
    return model.outputs(position.state, position.segment.contact_set, position.segment.loaded)


def sampled_run(stepper: SamplingStepper, scene, stop_time: float, times: np.ndarray,
                initial_pinion_angle=0.0):
    """simulate_with's run through a SamplingStepper (its arguments checked there): each piece
    of the input table in one call of advance_sampled, every sample a row of one array, named
    at the end."""
    model = stepper.model
    rows = np.empty((len(times), model.output_layout_size))
    position = start_position(model, scene.inputs.at(0.0)[0], initial_pinion_angle)
    for start, end in input_pieces(scene, stop_time):
        first, after = np.searchsorted(times, [position.time, end])
        position = stepper.advance_sampled(position, end, scene.inputs.at(start),
                                           times[first:after], rows[first:after])
    slots = dict(model.output_layout)
    results = {name: np.ascontiguousarray(rows[:, slots[name]]) for name in model.output_names}
    for name, value in final_outputs(model, position).items():
        results[name][-1] = value
    return Result(time=times, **results)
