"""A progress bar (progress_bar.py: simulated seconds done, time left) over any stepper's run.

`ProgressStepper` wraps a stepper (stepping.ScipyStepper, compiled_stepper.CompiledStepper) and only
watches the samples it hands out, so a run with it gives the same numbers to the bit;
`SampledProgressStepper` wraps the compiled one on herringbone.simulate's own way, samples into
an array, the bar moved after each compiled call.
"""
from __future__ import annotations

from ..arguments import check_compiled_run, check_reference_run
from ..integrate.contract import Result
from ..integrate.reference import DEFAULT_TOLERANCE as REFERENCE_TOLERANCE
from ..integrate.reference import checked_reference_run
from .progress_bar import progress_bar


class ProgressStepper:
    """The wrapped stepper's `model` and `advance`, moving a bar to each sample's time."""

    def __init__(self, stepper, bar):
        self.model = stepper.model
        self._stepper, self._bar = stepper, bar

    @property
    def accepted_steps(self) -> int | None:
        """The wrapped stepper's count of its steps, None where it keeps none."""
        return getattr(self._stepper, "accepted_steps", None)

    def advance(self, position, end, torques, sample_times=(), on_sample=None):
        """The wrapped stepper's advance, the bar moved on at every sample."""
        def watched(t, outputs):
            on_sample(t, outputs)
            self._bar.update(t - self._bar.n)

        return self._stepper.advance(position, end, torques, sample_times, watched)


class SampledProgressStepper(ProgressStepper):
    """A ProgressStepper over compiled_stepper.CompiledStepper that also samples into an array,
    so that simulate_with takes herringbone.simulate's way (the same numbers to the bit), the
    bar moved after each compiled call of SAMPLES_PER_CALL samples. Handing every sample to a
    callback as a dict cost 3.3 µs a sample: a simulated second of the reference scene at its
    output interval of 0.1 ms took 0.047 s that way, 0.014 s this way."""

    def advance_sampled(self, position, end, torques, times, rows):
        """The wrapped stepper's advance_sampled, the bar moved on after each compiled call."""
        return self._stepper.advance_sampled(position, end, torques, times, rows,
                                             on_progress=lambda t: self._bar.update(
                                                 t - self._bar.n))


def reference_simulate_with_progress(scene, stop_time=None, output_interval=None,
                                     tolerance=REFERENCE_TOLERANCE, progress=True):
    """reference.reference_simulate (DOP853) with a progress bar on stderr."""
    return simulate_with_progress(scene, stop_time, output_interval, tolerance, reference=True,
                                  progress=progress)


def simulate_with_progress(scene, stop_time=None, output_interval=None, tolerance=None,
                           reference=False, progress=True, on_ready=None,
                           method="auto") -> Result:
    """herringbone.simulate (or with `reference` reference_simulate) with a progress bar on
    stderr, and the integrator's compile announced there, as every compile is by default
    (compiling/announce.py): before it starts, every 10 s and at its end.

    Parameters
    ----------
    scene : Scene
    stop_time, output_interval : float or None
        Seconds; None: the scene's.
    tolerance : float or None
        Relative to the static mesh force: the compiled integrator's error per step, the
        reference's over the run; None: the integrator's default.
    reference : bool
        Run the scipy reference instead of the compiled integrator.
    progress : bool
        Show the bar.
    on_ready : callable or None
        Called once the integrator is ready to step, with the method that steps (the compiled
        integrator's: "auto" resolved; None for the reference) and what it does otherwise than
        its name says (CompiledStepper.method_note; "" for none): for the compiled one, the
        model's tables built and its compiled loop loaded (compiled the first time), and the
        bar up (importing tqdm takes milliseconds), so that a caller can tell that start from
        the stepping.
    method : str
        The compiled integrator's method (herringbone.simulate's `method`).

    Returns
    -------
    Result
        {"time": …, output name: …}, the same numbers to the bit as without the bar; its
        `steps`, the compiled integrator's internal steps (the warm-up's not counted).
    """
    from ..integrate.contract import simulate_with
    from ..model.assembly import GearTrainModel

    stop = scene.experiment.stop_time if stop_time is None else stop_time
    if reference:
        return _reference_with_progress(scene, stop_time, stop, output_interval, tolerance,
                                        progress, on_ready)
    from ..integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper, warm_up
    from ..integrate.contract import start_position

    tolerance = DEFAULT_TOLERANCE if tolerance is None else tolerance
    check_compiled_run(scene, stop_time, output_interval, tolerance, method)
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, tolerance, method)
    if on_ready is not None:
        warm_up(stepper, start_position(model, scene.inputs.at(0.0)[0]))
    with progress_bar(stop, f"run {scene.name}", progress) as bar:
        if on_ready is not None:
            on_ready(stepper.method, stepper.method_note)
        results = simulate_with(SampledProgressStepper(stepper, bar), scene, stop_time,
                                output_interval)
    return results


def _reference_with_progress(scene, stop_time, stop, output_interval, tolerance, progress,
                             on_ready) -> Result:
    """simulate_with_progress's run of the scipy reference (its arguments; `stop`: stop_time
    or the scene's, the bar's end)."""
    tolerance = REFERENCE_TOLERANCE if tolerance is None else tolerance
    check_reference_run(scene, stop_time, output_interval, tolerance)
    with progress_bar(stop, f"run {scene.name}", progress) as bar:
        if on_ready is not None:
            on_ready(None, "")
        return checked_reference_run(scene, stop_time, output_interval, tolerance,
                                     wrap=lambda stepper: _watched(stepper, bar, scene))[0]


def _watched(stepper, bar, scene) -> ProgressStepper:
    """The stepper of one of the reference's runs on the bar: a run that checks the first
    (integrate/global_error.py) starts the bar again, named as the check."""
    if bar.n > 0:
        bar.reset()
        bar.set_description(f"check {scene.name} (steps to {stepper.step_tolerance:.0e})")
    return ProgressStepper(stepper, bar)
