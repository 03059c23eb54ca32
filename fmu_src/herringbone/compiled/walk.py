"""The compiled loop: a run stepped through its segments (segments.py), one step method inside.

Contract of `advance`: from the run's position (time, state, contact interval and mesh cycle,
loaded points, step size to try), integrate to exactly `end` with the torques held, and return
the new position; `state` and `loaded` are updated in place. The result depends on nothing but
the arguments, so a saved position re-runs identically.

Segments. Within one the contact set and its loaded points are fixed and the equations smooth;
a segment ends where an event function crosses zero (as segments.py defines them):
    0: φp reaches the end of the contact set's interval (rising), the next set begins;
    1: φp falls back below its start (falling), the previous set begins;
    2 + i: point i's approach δ + η·δ̇ crosses zero (falling while it is loaded, rising while it
       is not), only where contact can be lost.
The loop steps onto every crossing: when an accepted step ends past one, the crossing is located
by false position (Illinois) on steps of the method itself taken from the step's start, and the
segment ends on the far side of the crossing, at most 2e-13 of the step past it. Every segment therefore
ends with a true step of the method, which keeps its order (a step across a switch would drop
it to first order). An event that crosses and re-crosses inside one step is not seen; the
steps of both methods are short against the time a separated tooth takes to return.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import dop853, radau
from .equations import approaches, derivative, outputs

EXPLICIT, IMPLICIT = 0, 1  # DOP853, Radau IIA
OK, STALLED, STEP_TOO_SMALL = 0, 1, 2
LOCATION_TOLERANCE = 1e-13  # width of the last bracket of an event, relative to the step
MAX_EVENTS_WITHOUT_PROGRESS = 1000  # chattering contact (grazing) beyond this is an error


@njit(cache=True)
def event_values(system, points, count, length, state, approach, out):
    out[0] = state[system.pinion] - length
    out[1] = state[system.pinion]
    if system.contact_loss:
        approaches(system, points, count, state, approach)
        out[2:2 + count] = approach[:count]


@njit(cache=True)
def first_crossing(before, after, number, loaded):
    """The event whose function crosses zero first (by linear interpolation) between two
    states, in its direction, ending strictly past zero; −1 if none does."""
    first, first_fraction = -1, 2.0
    for event in range(number):
        rising = event == 0 or (event >= 2 and loaded[event - 2] == 0.0)
        if (rising and before[event] <= 0.0 < after[event]) or (
                not rising and before[event] >= 0.0 > after[event]):
            fraction = before[event] / (before[event] - after[event])
            if fraction < first_fraction:
                first, first_fraction = event, fraction
    return first


@njit(cache=True)
def advance(system, lengths, counts, tables, method, time, interval, cycle, h, state, loaded,
            end, motor_torque, load_torque, absolute_tolerance, relative_tolerance, max_step,
            outputs_at_end):
    """Returns (time, interval, cycle, next step size, status, accepted steps), and fills
    `outputs_at_end` (equations.outputs) at the position reached."""
    size = state.shape[0]
    max_points = tables.shape[2]
    rate, new_state, trial_state, work = (np.empty(size), np.empty(size), np.empty(size),
                                          np.empty(size))
    stages = np.empty((dop853.STAGE_ROWS, size))
    values_before, values_after = np.empty(2 + max_points), np.empty(2 + max_points)
    values_trial, values_low = np.empty(2 + max_points), np.empty(2 + max_points)
    approach = np.empty(max_points)
    jacobian = np.empty((size, size))
    real, complex_ = np.empty((size, size)), np.empty((size, size), dtype=np.complex128)
    real_pivots, complex_pivots = np.empty(size, np.int64), np.empty(size, np.int64)

    points, count, length = tables[interval], counts[interval], lengths[interval]
    events = 2 + (count if system.contact_loss else 0)
    derivative(system, points, count, loaded, motor_torque, load_torque, state, rate)
    event_values(system, points, count, length, state, approach, values_before)
    jacobian_fresh = False
    jacobian_state = -1  # the segment number the Jacobian belongs to (implicit method)
    segment_number = 0
    factored_h = 0.0
    steps = 0
    rejected = False
    stalled_events = 0

    while time < end:
        h_wanted = min(h, max_step)
        # stretch a step by a hair rather than leave a remainder of rounding size
        landing = end - time <= h_wanted * (1.0 + 1e-7)
        h_step = end - time if landing else h_wanted
        if not landing and h_step <= 1e-15 * max(abs(time), 1.0):
            return time, interval, cycle, h, STEP_TOO_SMALL, steps

        # --- one step of the method ------------------------------------------------------
        iterations = 0
        if method == EXPLICIT:
            error = dop853.step(system, points, count, loaded, motor_torque, load_torque, state,
                                rate, h_step, absolute_tolerance, relative_tolerance, stages,
                                work, new_state)
        else:
            if jacobian_state != segment_number:
                radau.jacobian_of(system, points, count, loaded, motor_torque, load_torque,
                                  state, rate, absolute_tolerance, jacobian, trial_state, work)
                jacobian_state, jacobian_fresh, factored_h = segment_number, True, 0.0
            if h_step != factored_h:
                radau.factorize(jacobian, h_step, real, real_pivots, complex_, complex_pivots)
                factored_h = h_step
            error, iterations = radau.step(system, points, count, loaded, motor_torque,
                                           load_torque, state, rate, h_step, absolute_tolerance,
                                           relative_tolerance, real, real_pivots, complex_,
                                           complex_pivots, stages, new_state)
            if math.isinf(error) and not jacobian_fresh:
                jacobian_state = -1  # Newton failed on an old Jacobian: refresh it first
                continue
        if not error <= 1.0:  # too large, or NaN
            factor = (dop853.step_factor(error, rejected) if method == EXPLICIT
                      else radau.step_factor(error, iterations, rejected))
            h = h_step * (factor if math.isfinite(error) else 0.5)
            rejected = True
            continue
        factor = (dop853.step_factor(error, rejected) if method == EXPLICIT
                  else radau.step_factor(error, iterations, rejected))
        if method == IMPLICIT and factor < 1.2:
            factor = 1.0  # keep the factorization (scipy's rule)
        rejected = False
        jacobian_fresh = False
        steps += 1
        h_next = h_step * factor
        if landing:  # a step cut short to land on `end` says little about the next one
            h_next = max(h_next, h_wanted)

        # --- did it cross an event? --------------------------------------------------------
        event_values(system, points, count, length, new_state, approach, values_after)
        event = first_crossing(values_before, values_after, events, loaded)
        if event < 0:
            state[:] = new_state
            if method == EXPLICIT:
                rate[:] = stages[dop853.N_STAGES]
            else:
                derivative(system, points, count, loaded, motor_torque, load_torque, state, rate)
            values_before[:] = values_after
            time = end if landing else time + h_step
            h = h_next
            stalled_events = 0
            continue

        # --- locate it: bracket [low, high] of step sizes, Illinois false position ----------
        low, high = 0.0, h_step
        values_low[:] = values_before
        low_value, high_value = values_low[event], values_after[event]
        last_side = 0
        tolerance = LOCATION_TOLERANCE * h_step
        for _ in range(60):
            estimate = low + (high - low) * low_value / (low_value - high_value)
            if high - estimate <= 2.0 * tolerance:
                break  # the crossing lies within the tolerance before `high`
            # aim just past the estimate, so that a good estimate ends the search at once
            trial_h = estimate + tolerance
            if not low < trial_h < high:
                trial_h = 0.5 * (low + high)
            if method == EXPLICIT:
                dop853.step(system, points, count, loaded, motor_torque, load_torque, state,
                            rate, trial_h, absolute_tolerance, relative_tolerance, stages, work,
                            trial_state)
            else:
                radau.factorize(jacobian, trial_h, real, real_pivots, complex_, complex_pivots)
                factored_h = trial_h
                radau.step(system, points, count, loaded, motor_torque, load_torque, state,
                           rate, trial_h, absolute_tolerance, relative_tolerance, real,
                           real_pivots, complex_, complex_pivots, stages, trial_state)
            event_values(system, points, count, length, trial_state, approach, values_trial)
            crossed = first_crossing(values_before, values_trial, events, loaded)
            if crossed >= 0:
                if crossed != event:
                    event, last_side = crossed, 0
                    low_value = values_low[event]
                high, high_value = trial_h, values_trial[event]
                new_state[:] = trial_state
                if last_side == 1:
                    low_value *= 0.5
                last_side = 1
            else:
                low, low_value = trial_h, values_trial[event]
                values_low[:] = values_trial
                if last_side == -1:
                    high_value *= 0.5
                last_side = -1

        # --- the next segment ----------------------------------------------------------------
        state[:] = new_state
        time = end if landing and high == h_step else time + high
        stalled_events = stalled_events + 1 if high <= LOCATION_TOLERANCE * h_step else 0
        if stalled_events > MAX_EVENTS_WITHOUT_PROGRESS:
            return time, interval, cycle, h_next, STALLED, steps
        if event >= 2:
            loaded[event - 2] = 1.0 - loaded[event - 2]
        else:
            if event == 0:
                state[system.pinion] -= length
                interval += 1
                if interval == lengths.shape[0]:
                    interval, cycle = 0, cycle + 1
            else:
                interval -= 1
                if interval < 0:
                    interval, cycle = lengths.shape[0] - 1, cycle - 1
                state[system.pinion] += lengths[interval]
            points, count, length = tables[interval], counts[interval], lengths[interval]
            events = 2 + (count if system.contact_loss else 0)
            set_loaded_by_sign(system, points, count, state, approach, loaded)
        segment_number += 1
        derivative(system, points, count, loaded, motor_torque, load_torque, state, rate)
        event_values(system, points, count, length, state, approach, values_before)
        h = h_next
    outputs(system, points, count, loaded, state, outputs_at_end)
    return time, interval, cycle, h, OK, steps


@njit(cache=True)
def set_loaded_by_sign(system, points, count, state, approach, loaded):
    """Which points of a new set carry load: all, or where contact can be lost, those whose
    approach δ + η·δ̇ is not negative (segments.py)."""
    loaded[:] = 0.0
    if not system.contact_loss:
        loaded[:count] = 1.0
        return
    approaches(system, points, count, state, approach)
    for i in range(count):
        loaded[i] = 1.0 if approach[i] >= 0.0 else 0.0
