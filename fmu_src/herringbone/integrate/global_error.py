"""The scipy reference's check of its own error over a whole run, where the run shows that the
train may amplify errors: a mesh that lifts off entirely and lands again.

The step tolerance (stepping.step_tolerance) covers the step errors that ring on in the train's
modes; it is read off the train's matrices before the run. A train that rattles is beyond such a
rule: each landing's time, and so the flight and the landing that follow, depends on the state
the flight began with, and from landing to landing the train can multiply a small error of its
state many times over (measured on random scenes: a relative change of 1e-13 in the initial
pinion speed moves the forces by 2.5e-9 of the force scale on one, by 6e-6 on another;
docs/reference-accuracy.md). Only the run shows it.

So a run whose stepper recorded a landing (stepping.ScipyStepper.landings) is run again, each step
held TIGHTENING times tighter. Its error over the run is taken as proportional to the step
tolerance, so the difference of the two runs' forces estimates the error of each
(`estimated_error`; with more runs, the largest that any earlier run gives). Where the tighter
run's estimate exceeds the tolerance, the step tolerance is cut by the factor needed
(`next_step_tolerance`) and the run made again, down to scipy's floor
(stepping.FINEST_STEP_TOLERANCE), at most MAX_RUNS runs in all. The tightest run is the one
delivered; where its estimate still exceeds the tolerance, a ReferenceAccuracyWarning names the
scene and the estimate. A run without a landing is delivered as it is, at no extra cost.

This check is the reference's own: it reads nothing of the compiled integrator's error control.
"""
from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..model.assembly import GearTrainModel
from ..model.parameters import unit_of
from .contract import Result
from .stepping import FINEST_STEP_TOLERANCE

# A run with at least this many landings is checked: one landing already gave 1.3e-8 of the
# force scale at the default tolerance on a random scene (seed 1035), while runs without any
# stayed within 5e-9 on seeds 1000-1299 (docs/reference-accuracy.md).
LANDINGS_CHECKED = 1
# The second run's steps are held this many times tighter than the first's: far enough apart
# that the difference is the first run's error rather than the noise of both (their errors
# stand 9 to 1), near enough that the second run costs little more (DOP853's steps grow as the
# eighth root of the tolerance: 10 times tighter, 1.3 times the steps).
TIGHTENING = 10.0
# A tightened run aims at this fraction of the tolerance: the error is proportional to the
# step tolerance only on average (measured on seed 1029: runs a factor 3 apart in step
# tolerance differed by up to 10 times less than proportionality says).
SAFETY = 0.25
# Runs in all, the first included: the cut by the estimated factor (a third run) lands within
# the tolerance or on the floor but where the error is far from proportional; a fourth is the
# last, so that a check costs at most four runs.
MAX_RUNS = 4
# A reference run can judge another against a bound where its own estimated error over the run
# is within this share of the bound (the random-scene benchmark, the drawn property tests)
TRUTH_SHARE = 0.1


class ReferenceAccuracyWarning(UserWarning):
    """The scipy reference could not bring its estimated error over the run within its
    tolerance, even at scipy's finest step tolerance (the message names the scene and the
    estimate)."""


@dataclass(frozen=True)
class Check:
    """What the check found: the step tolerance of the run delivered, its estimated error over
    the run (a fraction of the force scale; None where the run was not checked), how many
    runs were made and how many landings the first met."""

    step_tolerance: float
    estimate: float | None
    runs: int
    landings: int


def can_judge(estimate: float | None, bound: float) -> bool:
    """Whether a reference run whose check estimated its error over the run at `estimate` (a
    fraction of the force scale; None where the run was not checked) is good enough to judge
    another run against `bound`: within TRUTH_SHARE of it."""
    return estimate is None or estimate <= TRUTH_SHARE * bound


def force_difference(a: Result, b: Result, model: GearTrainModel) -> float:
    """max |a − b| over every force output (unit N) and every sample of two runs of the same
    grid, as a fraction of the force scale (GearTrainModel.force_scale)."""
    forces = [name for name in a if name != "time" and unit_of(name) == "N"]
    return max(float(np.abs(a[name] - b[name]).max()) for name in forces) / model.force_scale()


def estimated_error(difference: float, looser: float, tighter: float) -> float:
    """The error over the run (fraction of the force scale) of the run at step tolerance
    `tighter`, from `difference` (force_difference) between it and the run at `looser`, the
    error being proportional to the step tolerance: C·tighter with C = difference /
    (looser − tighter). looser > tighter > 0."""
    return difference * tighter / (looser - tighter)


def next_step_tolerance(step: float, estimate: float, tolerance: float) -> float:
    """The step tolerance that brings a run whose estimated error is `estimate` at step
    tolerance `step` to SAFETY times `tolerance` (the error proportional to the step
    tolerance), never below scipy's floor FINEST_STEP_TOLERANCE. estimate > tolerance."""
    return max(step * SAFETY * tolerance / estimate, FINEST_STEP_TOLERANCE)


def checked_run(run: Callable[[float], tuple[Result, int]], model: GearTrainModel,
                tolerance: float, step: float) -> tuple[Result, Check]:
    """The run at step tolerance `step`, checked as this module says where it met a landing.

    Parameters
    ----------
    run : callable
        run(step_tolerance) -> (Result, landings): the whole run with each step held to that
        tolerance (dimensionless, of GearTrainModel.state_scales) and the landings it met.
    model : GearTrainModel
        The train (its force scale, and its scene's name for the warning).
    tolerance : float
        The error allowed in the forces over the run, a fraction of the force scale.
    step : float
        The step tolerance of the first run (stepping.step_tolerance).

    Returns
    -------
    (Result, Check)
        The run delivered (the tightest made) and what the check found.

    Warns
    -----
    ReferenceAccuracyWarning
        The estimate of the run delivered exceeds `tolerance` at scipy's floor, or after
        MAX_RUNS runs.
    """
    result, landings = run(step)
    if landings < LANDINGS_CHECKED:
        return result, Check(float(step), None, 1, landings)
    if step / TIGHTENING >= FINEST_STEP_TOLERANCE:
        runs = [(step, result), (step / TIGHTENING, run(step / TIGHTENING)[0])]
    else:  # scipy takes no steps that much tighter: the estimate needs a looser run
        runs = [(step * TIGHTENING, run(step * TIGHTENING)[0]), (step, result)]
    while True:
        estimate = _estimate(runs, model)
        tightest = runs[-1][0]
        if estimate <= tolerance or tightest <= FINEST_STEP_TOLERANCE or len(runs) == MAX_RUNS:
            break
        step = next_step_tolerance(tightest, estimate, tolerance)
        runs.append((step, run(step)[0]))
    if estimate > tolerance:
        warnings.warn(ReferenceAccuracyWarning(
            f"scene {model.scene.name}: the scipy reference's error over the run is estimated "
            f"at {estimate:.1e} of the force scale, beyond its tolerance {tolerance:.0e}, at "
            f"step tolerance {tightest:.1e} (the train lifts off and lands {landings} times, "
            "and amplifies small errors from landing to landing)"), stacklevel=3)
    return runs[-1][1], Check(float(tightest), estimate, len(runs), landings)


def _estimate(runs: list[tuple[float, Result]], model: GearTrainModel) -> float:
    """The estimated error of the last of `runs` ((step tolerance, result), step tolerances
    falling): the largest that its difference from any earlier run gives (estimated_error),
    since the error follows the step tolerance only on average."""
    step, result = runs[-1]
    return float(max(estimated_error(force_difference(other, result, model), looser, step)
                     for looser, other in runs[:-1]))
