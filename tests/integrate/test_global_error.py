"""The reference's check of its error over a run (integrate/global_error.py), on made-up runs
whose error is known: the estimate, the tightening rule, when the check runs and when it warns."""
from types import SimpleNamespace

import numpy as np
import pytest

from herringbone.integrate import global_error
from herringbone.integrate.contract import Result
from herringbone.integrate.global_error import (
    FINEST_STEP_TOLERANCE,
    ReferenceAccuracyWarning,
    checked_run,
    estimated_error,
    next_step_tolerance,
)

SCALE = 2.0e4  # N: the made-up train's force scale
MODEL = SimpleNamespace(force_scale=lambda: SCALE, scene=SimpleNamespace(name="made_up"))


def made_up_runs(error, landings=5):
    """run(step) for checked_run: F_mesh off the true 1 force scale by error(step) force scales
    at the last of three samples (the bearing force by half that), and the step tolerances
    asked for, in order."""
    asked = []

    def run(step):
        asked.append(step)
        off = np.array([0.0, 0.0, error(step)]) * SCALE
        return Result(time=np.array([0.0, 1.0, 2.0]), F_mesh=SCALE + off,
                      F_brg_pinion_left=-0.5 * (SCALE + off), w_pinion=1e6 * off), landings

    return run, asked


def test_the_estimate_is_the_tighter_runs_error_where_the_error_is_proportional():
    # runs whose errors are 3e4 times their step tolerance differ by 3e4·(1e-11 − 1e-12)
    difference = 3e4 * (1e-11 - 1e-12)
    assert estimated_error(difference, 1e-11, 1e-12) == pytest.approx(3e4 * 1e-12, rel=1e-12)
    assert estimated_error(difference, 1e-11, 1e-12) != pytest.approx(3e4 * 1e-11, rel=0.5)
    assert estimated_error(1e-9, 4e-12, 1e-12) == pytest.approx(1e-9 / 3, rel=1e-12)


def test_the_next_step_tolerance_aims_at_a_quarter_of_the_tolerance():
    # 4e-10 at 1e-11 with 1e-10 allowed: 1e-11 · 0.25 · 1e-10 / 4e-10
    assert next_step_tolerance(1e-11, 4e-10, 1e-10) == pytest.approx(6.25e-13, rel=1e-12)
    assert global_error.SAFETY == 0.25


def test_the_next_step_tolerance_stops_at_scipys_floor():
    assert next_step_tolerance(1e-12, 8e-9, 1e-10) == FINEST_STEP_TOLERANCE


def test_forces_only_are_compared_in_units_of_the_force_scale():
    run, _ = made_up_runs(lambda step: step * 1e3)
    a, b = run(1e-11)[0], run(1e-12)[0]
    # F_mesh differs by 9e-9 force scales; w_pinion by far more but is no force
    assert global_error.force_difference(a, b, MODEL) == pytest.approx(9e-9, rel=1e-9)


def test_a_run_without_a_landing_is_delivered_unchecked():
    run, asked = made_up_runs(lambda step: 1e3 * step, landings=0)
    result, check = checked_run(run, MODEL, 1e-10, 1e-11)
    assert asked == [1e-11] and check.estimate is None and check.runs == 1
    assert result["F_mesh"][-1] == SCALE * (1 + 1e-8)


def test_a_single_landing_is_enough_to_check_a_run():
    run, asked = made_up_runs(lambda step: 50.0 * step, landings=1)
    assert checked_run(run, MODEL, 1e-10, 1e-11)[1].runs == 2 and asked == [1e-11, 1e-12]


def test_one_tighter_run_where_it_holds_the_tolerance():
    """Errors 50 times the step tolerance: the run at 1e-12 is off by 5e-11, within 1e-10, and
    is the one delivered."""
    run, asked = made_up_runs(lambda step: 50.0 * step)
    result, check = checked_run(run, MODEL, 1e-10, 1e-11)
    assert asked == [1e-11, 1e-12] and check.runs == 2 and check.landings == 5
    assert check.step_tolerance == 1e-12
    assert check.estimate == pytest.approx(5e-11, rel=1e-6)
    assert result["F_mesh"][-1] == pytest.approx(SCALE * (1 + 5e-11), rel=1e-15)


def test_the_step_tolerance_is_cut_by_the_factor_the_estimate_asks():
    """Errors 1e3 times the step tolerance: 1e-9 at 1e-12 asks for 1e-12·0.25·1e-10/1e-9 =
    2.5e-14, whose run is off by 2.5e-11 and is delivered without a warning."""
    run, asked = made_up_runs(lambda step: 1e3 * step)
    with np.testing.assert_no_warnings():
        result, check = checked_run(run, MODEL, 1e-10, 1e-11)
    assert asked[:2] == [1e-11, 1e-12] and asked[2] == pytest.approx(2.5e-14, rel=1e-9)
    assert check.runs == 3 and check.estimate == pytest.approx(2.5e-11, rel=1e-6)
    assert result["F_mesh"][-1] == pytest.approx(SCALE * (1 + 2.5e-11), rel=1e-15)


def test_a_train_the_floor_cannot_hold_is_named_with_its_estimate():
    """Errors 1e5 times the step tolerance: at scipy's floor 2.2e-9, beyond 1e-10."""
    run, asked = made_up_runs(lambda step: 1e5 * step)
    with pytest.warns(ReferenceAccuracyWarning, match=r"made_up.* 2\.2e-09 .*1e-10"):
        _, check = checked_run(run, MODEL, 1e-10, 1e-11)
    assert asked[-1] == FINEST_STEP_TOLERANCE and check.runs == 3
    assert check.estimate == pytest.approx(1e5 * FINEST_STEP_TOLERANCE, rel=1e-6)


def test_a_first_run_on_the_floor_is_checked_against_a_looser_one():
    run, asked = made_up_runs(lambda step: 1e3 * step)
    result, check = checked_run(run, MODEL, 1e-10, FINEST_STEP_TOLERANCE)
    assert asked == [FINEST_STEP_TOLERANCE, 10 * FINEST_STEP_TOLERANCE]
    assert check.step_tolerance == FINEST_STEP_TOLERANCE and check.runs == 2
    assert check.estimate == pytest.approx(1e3 * FINEST_STEP_TOLERANCE, rel=1e-6)


def test_the_check_stops_after_its_last_run_and_says_so():
    """Runs off by 1e-4 whatever their step tolerance, on alternate sides: every cut falls
    short, and after MAX_RUNS runs, still above the floor, the estimate is reported."""
    sides = iter([1.0, -1.0] * global_error.MAX_RUNS)
    run, asked = made_up_runs(lambda step: 1e-4 * next(sides))
    with pytest.warns(ReferenceAccuracyWarning, match="made_up"):
        _, check = checked_run(run, MODEL, 1e-5, 1e-6)
    assert len(asked) == global_error.MAX_RUNS == check.runs
    assert asked == sorted(asked, reverse=True) and asked[-1] > 1e3 * FINEST_STEP_TOLERANCE
    assert check.estimate > 1e-5


def test_the_estimate_is_the_largest_that_any_earlier_run_gives():
    """The run at the floor hardly differs from the one at 1e-12 (by 1e-12), but by 4.9e-8
    from the one at 1e-11: 4.9e-8 · 2.2e-14 / (1e-11 − 2.2e-14) = 1.08e-10, beyond 1e-10.
    The last pair alone would say 2.2e-14."""
    errors = {1e-11: 5e-8, 1e-12: 1e-9, FINEST_STEP_TOLERANCE: 1e-9 - 1e-12}
    run, asked = made_up_runs(errors.get)
    with pytest.warns(ReferenceAccuracyWarning, match=r"1\.1e-10"):
        _, check = checked_run(run, MODEL, 1e-10, 1e-11)
    assert asked == list(errors)
    expected = (5e-8 - errors[FINEST_STEP_TOLERANCE]) * FINEST_STEP_TOLERANCE / (
        1e-11 - FINEST_STEP_TOLERANCE)
    assert check.estimate == pytest.approx(expected, rel=1e-6)
