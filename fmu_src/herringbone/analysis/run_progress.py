"""A progress bar (tqdm: simulated seconds done, time left) over any stepper's run.

`ProgressStepper` wraps a stepper (stepping.ScipyStepper, integrator.CompiledStepper) and only
watches the samples it hands out, so a run with it gives the same numbers to the bit.
"""
from __future__ import annotations

import sys


class ProgressStepper:
    """The wrapped stepper's `model` and `advance`, moving a bar to each sample's time."""

    def __init__(self, stepper, bar):
        self.model = stepper.model
        self._stepper, self._bar = stepper, bar

    def advance(self, position, end, torques, sample_times=(), on_sample=None):
        """The wrapped stepper's advance, the bar moved on at every sample."""
        def watched(t, outputs):
            on_sample(t, outputs)
            self._bar.update(t - self._bar.n)

        return self._stepper.advance(position, end, torques, sample_times, watched)


def reference_simulate_with_progress(scene, stop_time=None, output_interval=None,
                                     tolerance=1e-10, progress=True):
    """reference.reference_simulate (DOP853) with a progress bar on stderr."""
    from tqdm import tqdm

    from ..integrate.contract import simulate_with
    from ..integrate.stepping import ScipyStepper
    from ..model.assembly import GearTrainModel

    stop = scene.experiment.stop_time if stop_time is None else stop_time
    with tqdm(total=stop, unit="s", unit_scale=False, desc=f"run {scene.name}",
              file=sys.stderr, disable=not progress,
              bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s simulated "
                         "[{elapsed}<{remaining}]") as bar:
        stepper = ProgressStepper(ScipyStepper(GearTrainModel(scene), tolerance, horizon=stop), bar)
        return simulate_with(stepper, scene, stop_time, output_interval)
