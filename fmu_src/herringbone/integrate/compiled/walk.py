"""The compiled loop: a run stepped through its segments (segments.py), one step method inside.

Contract of `advance`: from the run's position (time, state, contact interval and mesh cycle,
loaded points, step size to try), integrate to exactly `end` with the torques held, and leave
the new position in the same arrays, updated in place. The result depends on nothing but the
arguments, so a saved position re-runs identically.

Segments. Within one the contact set and its loaded points are fixed and the equations smooth;
a segment ends where an event function crosses zero (as segments.py defines them):
    0: φp reaches the end of the contact set's interval (rising), the next set begins;
    1: φp falls back below its start (falling), the previous set begins;
    2 + i: point i's approach δ + η·δ̇ crosses zero (falling while it is loaded, rising while it
       is not), only where contact can be lost.
The loop steps onto every crossing: when an accepted step ends past one, the crossing is located
by steps of the method itself taken from the step's start (aimed by Newton's method for a phase
event, whose slope φp's rate is in the state, by secants for a contact), and the segment ends
on the far side of the crossing, past it by at most `event_time_tolerance` seconds: a
switch misplaced by δt leaves a force error of about ω_max·δt times the force that switched,
and the caller keeps that to a hundredth of the relative tolerance. Every segment therefore
ends with a true step of the method, which keeps its order (a step across a switch would drop
it to first order). Where several events cross inside one step, the earliest is located
(trials are judged against the bracket's low end, where nothing has crossed yet, and a last
trial just before the located crossing makes sure no other came first). A point that lifts
off and lands again inside one step (or touches and leaves) is caught from the cubic through
its approach and approach rate at the step's ends (`grazing_fraction`).

What follows an event (`next_segment`): the loaded points of the segment are decided by the
sign of their approach, all of them, whatever the event was. So a point that crossed in the
same bracket as the located event (a whole train separating, or landing, at once) starts the
segment on its own side; and no segment starts with a loaded point in tension or an unloaded
one penetrating. A debug run (`contact_slack` >= 0) also looks inside every step for such a
point by other means (`contact_violated_inside`).

Two step-size rules serve the switches (DOP853 only for the first): a step that would pass the
next phase event is aimed to end just past its predicted crossing, so one trial step locates
it; and each contact interval starts with the step size its last entry settled on
(`first_steps`), since the vibration a switch sets off is one the step before it did not see.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import dop853, radau
from .equations import approach_rates, approaches, derivative, outputs, unpack_system

EXPLICIT, IMPLICIT = 0, 1  # DOP853, Radau IIA
OK, STALLED, STEP_TOO_SMALL, NOT_FINITE, CHATTER, CONTACT_VIOLATED, OVER_BUDGET = range(7)
# where a debug run looks inside each step for a point in tension or penetrating unloaded
INSIDE_FRACTIONS = (0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875)
# A cubic through a mode's values and slopes at the ends of a step of h·ω = y misses it by
# about y³/384 of the step's change h·|ġ|: 0.11 at the step bound's 3.5. A point whose cubic
# comes this close to zero is looked at inside the step (`grazing_suspect`), at its cubic's
# turning point and at PROBE_FRACTIONS.
GRAZING_MARGIN = 0.12
PROBE_FRACTIONS = (0.25, 0.5, 0.75)
MAX_EVENTS_WITHOUT_PROGRESS = 1000  # chattering contact (grazing) beyond this is an error
# trial steps to locate one event (a bisection alone halves the bracket 60 times)
MAX_LOCATION_TRIALS = 60
# A contact set that throws the pinion back into the previous one, and that one forward again:
# beyond this many reversals in a row the train is stuck on the switch (a point entering at
# full load with sharp face edges, at low speed), which an edge ramp resolves
MAX_PHASE_REVERSALS = 1000
# A step aimed at a predicted phase event ends this fraction of its length past the prediction,
# so that it crosses despite the prediction's error; it is aimed only when the event lies more
# than PREDICTION_FLOOR of the step ahead (a nearer one is crossed by the step as it is)
PREDICTION_MARGIN = 1e-4
PREDICTION_FLOOR = 1e-3

# The helpers the loop calls at every step are inlined (inline="always"): a compiled call hands
# over each array of the System by reference, which numba counts atomically on the way in and
# out, 15 arrays a call; inlined, the loop ran 9 % faster (staggered and reference scenes).


@njit(cache=True, error_model="numpy", inline="always")
def event_values(system, points, count, length, state, approach, out):
    out[0] = state[system.pinion] - length
    out[1] = state[system.pinion]
    if system.contact_loss:
        approaches(system, points, count, state, approach)
        for i in range(count):
            out[2 + i] = approach[i]


@njit(cache=True, error_model="numpy", inline="always")
def phase_event_ahead(system, state, rate, length):
    """When φp would reach the end of its interval (moving forward) or its start (moving
    back), from its rate and acceleration: the zero of the quadratic by one Newton step from
    the linear guess; inf if φp stands still."""
    n = state.shape[0] // 2
    angle, speed, acceleration = (state[system.pinion], state[n + system.pinion],
                                  rate[n + system.pinion])
    if speed == 0.0:
        return math.inf
    linear = ((length if speed > 0.0 else 0.0) - angle) / speed
    slope = speed + acceleration * linear
    if slope * speed <= 0.0:  # turning back before it gets there
        return math.inf
    ahead = linear - 0.5 * acceleration * linear * linear / slope
    return ahead if ahead > 0.0 else math.inf


@njit(cache=True, error_model="numpy", inline="always")
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


@njit(cache=True, error_model="numpy")
def crossings(before, after, number, loaded):
    """How many events cross zero between two states, each in its direction."""
    crossed = 0
    for event in range(number):
        rising = event == 0 or (event >= 2 and loaded[event - 2] == 0.0)
        if (rising and before[event] <= 0.0 < after[event]) or (
                not rising and before[event] >= 0.0 > after[event]):
            crossed += 1
    return crossed


@njit(cache=True, error_model="numpy")
def trial_step(method, system, points, count, loaded, motor_torque, load_torque, state, rate,
               h, absolute_tolerance, relative_tolerance, jacobian, real, real_pivots, complex_,
               complex_pivots, stages, work, out):
    """A step of the method to `out`, taken only to look where an event lies (its error is
    not checked: it is shorter than a step already accepted). Returns the step size the
    implicit method's factors now belong to."""
    if method == EXPLICIT:
        dop853.step(system, points, count, loaded, motor_torque, load_torque, state, rate, h,
                    absolute_tolerance, relative_tolerance, stages, work, out)
    else:
        radau.factorize(jacobian, h, real, real_pivots, complex_, complex_pivots)
        radau.step(system, points, count, loaded, motor_torque, load_torque, state, rate, h,
                   absolute_tolerance, relative_tolerance, real, real_pivots, complex_,
                   complex_pivots, stages, out)
    return h


@njit(cache=True, error_model="numpy")
def contact_violated_inside(method, system, points, count, loaded, motor_torque, load_torque,
                            state, rate, h, absolute_tolerance, relative_tolerance, jacobian,
                            real, real_pivots, complex_, complex_pivots, stages, work, trial,
                            approach, slack):
    """Debug check of a step from `state` of size h, by trial steps to INSIDE_FRACTIONS of it:
    whether a loaded point's approach falls below −slack (tension) or an unloaded one's rises
    above slack (penetration without load) anywhere there. It looks for what the event
    search (crossings at step ends, the cubic for a dip within a step) would have missed,
    by other means, at seven times the cost of a step."""
    for fraction in INSIDE_FRACTIONS:
        trial_step(method, system, points, count, loaded, motor_torque, load_torque, state,
                   rate, fraction * h, absolute_tolerance, relative_tolerance, jacobian, real,
                   real_pivots, complex_, complex_pivots, stages, work, trial)
        approaches(system, points, count, trial, approach)
        for i in range(count):
            if (loaded[i] != 0.0 and approach[i] < -slack) or (
                    loaded[i] == 0.0 and approach[i] > slack):
                return True
    return False


@njit(cache=True, error_model="numpy", inline="always")
def grazing_suspect(before, after, slopes_before, slopes_after, h, count, loaded):
    """Where inside a step (a fraction of it) some point's approach may cross zero and come
    back though both ends lie on the same side: a lift-off and landing, or a touch, too brief
    for the ends to show. Each point's approach is modelled by the cubic through its values and
    slopes at the step's ends; a point is suspect where that cubic turns back towards zero and
    comes within GRAZING_MARGIN·h·(|ġ0| + |ġ1|) of it (the cubic's own error, for a step of
    up to h·|λ|max = 3.5 of the mode that moves the point). The earliest suspect turning point,
    or −1 if there is none."""
    earliest = -1.0
    for i in range(count):
        g0, g1 = before[2 + i], after[2 + i]
        d0, d1 = h * slopes_before[i], h * slopes_after[i]
        sign = 1.0 if loaded[i] != 0.0 else -1.0  # loaded: watch for a dip below zero
        if sign * g0 < 0.0 or sign * g1 < 0.0:
            continue
        margin = GRAZING_MARGIN * (abs(d0) + abs(d1))
        # the cubic's slope terms lift or lower it by at most 4/27 of |d0| + |d1|
        if min(sign * g0, sign * g1) > margin + 4.0 / 27.0 * (abs(d0) + abs(d1)):
            continue
        # Hermite cubic p(s) = g0 + d0·s + c2·s² + c3·s³ on [0, 1]
        c2 = 3.0 * (g1 - g0) - 2.0 * d0 - d1
        c3 = 2.0 * (g0 - g1) + d0 + d1
        # p'(s) = d0 + 2·c2·s + 3·c3·s² = 0
        a, b, c = 3.0 * c3, 2.0 * c2, d0
        first = second = -1.0
        if a == 0.0:
            if b != 0.0:
                first = -c / b
        else:
            discriminant = b * b - 4.0 * a * c
            if discriminant >= 0.0:
                root = math.sqrt(discriminant)
                first, second = (-b - root) / (2.0 * a), (-b + root) / (2.0 * a)
        for s in (first, second):
            if 0.0 < s < 1.0 and sign * (g0 + s * (d0 + s * (c2 + s * c3))) < margin:
                if earliest < 0.0 or s < earliest:
                    earliest = s
    return earliest


@njit(cache=True, error_model="numpy")
def probe_inside(suspect, method, system, points, count, length, events, loaded, motor_torque,
                 load_torque, state, rate, h, absolute_tolerance, relative_tolerance, jacobian,
                 real, real_pivots, complex_, complex_pivots, stages, work, trial, approach,
                 values_before, values_trial):
    """Trial steps from `state` to fractions of the step h, in increasing order, the suspect
    turning point among PROBE_FRACTIONS, until one shows an event crossed. Returns (the event,
    or −1; the trial's step size, whose state is in `trial` and event values in
    `values_trial`; the step size the implicit method's factors now belong to)."""
    done = 0.0
    trial_h = 0.0
    for k in range(len(PROBE_FRACTIONS) + 1):
        fraction = 2.0
        for candidate in PROBE_FRACTIONS:  # the next fraction after `done`, the suspect's too
            if done < candidate < fraction:
                fraction = candidate
        if done < suspect < fraction:
            fraction = suspect
        if fraction >= 1.0:
            break
        done = fraction
        trial_h = fraction * h
        trial_step(method, system, points, count, loaded, motor_torque, load_torque, state, rate,
                   trial_h, absolute_tolerance, relative_tolerance, jacobian, real, real_pivots,
                   complex_, complex_pivots, stages, work, trial)
        event_values(system, points, count, length, trial, approach, values_trial)
        event = first_crossing(values_before, values_trial, events, loaded)
        if event >= 0:
            return event, trial_h, trial_h
    return -1, trial_h, trial_h


@njit(cache=True, error_model="numpy")
def hermite_root(g0, g1, d0, d1):
    """The zero in [0, 1] of the cubic with values g0, g1 and slopes d0, d1 at 0 and 1 (g0, g1
    of opposite signs), by Newton's method from the chord's zero; −1 if it does not settle."""
    c2 = 3.0 * (g1 - g0) - 2.0 * d0 - d1
    c3 = 2.0 * (g0 - g1) + d0 + d1
    s = g0 / (g0 - g1)
    for _ in range(4):
        slope = d0 + s * (2.0 * c2 + 3.0 * s * c3)
        if slope == 0.0:
            return -1.0
        s -= (g0 + s * (d0 + s * (c2 + s * c3))) / slope
    return s if 0.0 < s < 1.0 else -1.0


@njit(cache=True, error_model="numpy")
def advance(system_floats, system_ints, lengths, counts, tables, method, clock, place, state,
            loaded, first_steps, end, motor_torque, load_torque, absolute_tolerance,
            relative_tolerance, max_step, event_time_tolerance, contact_slack, outputs_at_end,
            max_steps):
    """Returns (status, accepted steps). At most `max_steps` steps are taken: beyond them the
    run stops where it is with OVER_BUDGET (a runaway that would hold its caller for ever).
    The position is read from and written back to
    clock = [time, step size to try], place = [contact interval, mesh cycle], `state`,
    `loaded` and `first_steps` (per contact interval, the step size to start it with; 0:
    none yet), also where the run fails; `outputs_at_end` gets equations.outputs there. The
    system comes packed (equations.pack_system). contact_slack >= 0 (m) turns on the debug
    check of `contact_violated_inside` on every step; < 0 leaves it off."""
    system = unpack_system(system_floats, system_ints)
    time, interval, cycle, h, status, steps = _advance(
        system, lengths, counts, tables, method, clock[0], place[0], place[1], clock[1], state,
        loaded, first_steps, end, motor_torque, load_torque, absolute_tolerance,
        relative_tolerance, max_step, event_time_tolerance, contact_slack, max_steps)
    clock[0], clock[1] = time, h
    place[0], place[1] = interval, cycle
    outputs(system, tables[interval], counts[interval], loaded, state, outputs_at_end)
    return status, steps


@njit(cache=True, error_model="numpy")
def _advance(system, lengths, counts, tables, method, time, interval, cycle, h, state, loaded,
             first_steps, end, motor_torque, load_torque, absolute_tolerance,
             relative_tolerance, max_step, event_time_tolerance, contact_slack, max_steps):
    size = state.shape[0]
    max_points = tables.shape[2]
    rate, new_state, trial_state, work = (np.empty(size), np.empty(size), np.empty(size),
                                          np.empty(size))
    stages = np.empty((dop853.STAGE_ROWS, size))
    values_before, values_after = np.empty(2 + max_points), np.empty(2 + max_points)
    values_trial, values_low = np.empty(2 + max_points), np.empty(2 + max_points)
    values_high = np.empty(2 + max_points)
    approach = np.empty(max_points)
    rate_after = np.empty(size)
    slopes_before, slopes_after = np.zeros(max_points), np.zeros(max_points)
    jacobian = np.empty((size, size))
    real, complex_ = np.empty((size, size)), np.empty((size, size), dtype=np.complex128)
    real_pivots, complex_pivots = np.empty(size, np.int64), np.empty(size, np.int64)

    points, count, length = tables[interval], counts[interval], lengths[interval]
    events = 2 + (count if system.contact_loss else 0)
    derivative(system, points, count, loaded, motor_torque, load_torque, state, rate)
    event_values(system, points, count, length, state, approach, values_before)
    if system.contact_loss:
        approach_rates(system, points, count, state, rate, slopes_before)
    jacobian_fresh = False
    jacobian_state = -1  # the segment number the Jacobian belongs to (implicit method)
    segment_number = 0
    factored_h = 0.0
    steps = 0
    previous_error = 1e-4  # of the last accepted step (explicit method's controller)
    rejected = False
    stalled_events = 0
    reversals, last_phase_event = 0, -1  # of the phase events: 0 forward, 1 backward
    opening = -1  # the contact interval whose first step is being taken (forward entry)

    while time < end:
        if steps >= max_steps:  # checked here, where the position is a consistent one
            return time, interval, cycle, h, OVER_BUDGET, steps
        h_wanted = min(h, max_step)
        # stretch a step by a hair rather than leave a remainder of rounding size
        landing = end - time <= h_wanted * (1.0 + 1e-7)
        h_step = end - time if landing else h_wanted
        # a step that would pass the next phase event ends just past it instead: the event is
        # then located by a single trial step, and nothing of the step past it is thrown away.
        # Radau IIA's steps are not aimed: with them its error stopped falling with the step
        # size in the order test (tests/test_integrator.py), and it steps to few events.
        aimed = False
        if method == EXPLICIT:
            passing = (1.0 + PREDICTION_MARGIN) * phase_event_ahead(system, state, rate, length)
            if PREDICTION_FLOOR * h_step < passing < h_step:
                h_step, landing, aimed = passing, False, True
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
            factor = (dop853.step_factor(error, previous_error, rejected) if method == EXPLICIT
                      else radau.step_factor(error, iterations, rejected))
            h = h_step * (factor if math.isfinite(error) else 0.5)
            rejected = True
            continue
        if method == EXPLICIT:
            factor = dop853.step_factor(error, previous_error, rejected)
            if not (landing or aimed):  # a cut step's small error would hold the next one back
                previous_error = max(error, 1e-4)
        else:
            factor = radau.step_factor(error, iterations, rejected)
            if factor < 1.2:
                factor = 1.0  # keep the factorization (scipy's rule)
        rejected = False
        jacobian_fresh = False
        steps += 1
        h_next = h_step * factor
        if landing or aimed:  # a step cut short says little about the next one
            h_next = max(h_next, h_wanted)
        elif opening >= 0:
            first_steps[opening] = h_next
        opening = -1

        # --- did it cross an event? --------------------------------------------------------
        event_values(system, points, count, length, new_state, approach, values_after)
        event = first_crossing(values_before, values_after, events, loaded)
        high = h_step
        if method == EXPLICIT:
            rate_after[:] = stages[dop853.N_STAGES]
        else:
            derivative(system, points, count, loaded, motor_torque, load_torque, new_state,
                       rate_after)
        if system.contact_loss:
            approach_rates(system, points, count, new_state, rate_after, slopes_after)
            # a point may lift off and land again (or touch and leave) inside the step, also
            # before an event the step's end shows (a dip inside a short contact interval)
            suspect = grazing_suspect(values_before, values_after, slopes_before, slopes_after,
                                      h_step, count, loaded)
            if suspect > 0.0:
                found, trial_h, factored_h = probe_inside(
                    suspect, method, system, points, count, length, events, loaded,
                    motor_torque, load_torque, state, rate, h_step, absolute_tolerance,
                    relative_tolerance, jacobian, real, real_pivots, complex_, complex_pivots,
                    stages, work, trial_state, approach, values_before, values_trial)
                if found >= 0:  # crossed by then: the bracket shrinks to the probe
                    event, high = found, trial_h
                    new_state[:] = trial_state
                    values_after[:] = values_trial
        if event < 0:
            if contact_slack >= 0.0 and system.contact_loss:
                factored_h = 0.0  # the check's trial steps factorize for their own sizes
                if contact_violated_inside(
                        method, system, points, count, loaded, motor_torque, load_torque, state,
                        rate, h_step, absolute_tolerance, relative_tolerance, jacobian, real,
                        real_pivots, complex_, complex_pivots, stages, work, trial_state,
                        approach, contact_slack):
                    return time, interval, cycle, h, CONTACT_VIOLATED, steps
            state[:] = new_state
            rate[:] = rate_after
            values_before[:] = values_after
            slopes_before[:] = slopes_after
            time = end if landing else time + h_step
            h = h_next
            stalled_events = 0
            continue

        # --- locate it: steps of the method inside the bracket [low, high] of step sizes -----
        # A phase event's function is φp less a constant, and its slope, φp's rate, is part of
        # the state: the first estimate is the zero of the cubic through values and slopes at
        # the step's ends (fifty times closer than the chord's), the next ones Newton's from the
        # latest trial. A contact event is found by secant steps.
        low = 0.0
        values_low[:] = values_before
        values_high[:] = values_after
        older_h, older_value = low, values_low[event]  # the two latest points, for the secant
        newer_h, newer_value = high, values_after[event]
        pinion_rate = size // 2 + system.pinion
        newer_slope = new_state[pinion_rate]
        tolerance = max(event_time_tolerance, 1e-14 * h_step)  # not below rounding
        first_estimate = -1.0
        if event < 2 and high == h_step:
            first_estimate = high * hermite_root(values_low[event], values_after[event],
                                                 high * state[pinion_rate],
                                                 high * newer_slope)
        for _ in range(MAX_LOCATION_TRIALS):
            if high - low <= 2.0 * tolerance:
                break  # whatever crossed in between crossed together, to the tolerance
            estimate = first_estimate
            first_estimate = -1.0
            if estimate < 0.0:
                if event < 2 and newer_slope != 0.0:
                    estimate = newer_h - newer_value / newer_slope
                elif newer_value != older_value:
                    estimate = newer_h - newer_value * (newer_h - older_h) / (
                        newer_value - older_value)
            if not low <= estimate < high:
                estimate = 0.5 * (low + high)
            if high - estimate <= 2.0 * tolerance:
                # located, unless another event that had also crossed by `high` crossed
                # earlier: then a trial just before this crossing says which
                if crossings(values_low, values_high, events, loaded) == 1:
                    break
                trial_h = high - 2.0 * tolerance
            else:
                # aim just past the estimate, so that a good estimate ends the search at once
                trial_h = estimate + tolerance
            factored_h = trial_step(method, system, points, count, loaded, motor_torque,
                                    load_torque, state, rate, trial_h, absolute_tolerance,
                                    relative_tolerance, jacobian, real, real_pivots, complex_,
                                    complex_pivots, stages, work, trial_state)
            event_values(system, points, count, length, trial_state, approach, values_trial)
            # against the bracket's low end, where nothing has crossed yet: of several events
            # crossed by the trial, the earliest is taken
            crossed = first_crossing(values_low, values_trial, events, loaded)
            if crossed >= 0:
                if crossed != event:  # another event crosses first: locate that one
                    event = crossed
                    older_h, older_value = low, values_low[event]
                else:
                    older_h, older_value = newer_h, newer_value
                high = trial_h
                new_state[:] = trial_state
                values_high[:] = values_trial
            else:
                older_h, older_value = newer_h, newer_value
                low = trial_h
                values_low[:] = values_trial
            newer_h, newer_value = trial_h, values_trial[event]
            newer_slope = trial_state[pinion_rate]

        # --- the next segment ----------------------------------------------------------------
        # (a debug run looks inside the step to the event, where no other point may have
        # crossed unseen; the event's own crossing lies within 2·tolerance of its end)
        if contact_slack >= 0.0 and system.contact_loss and high > 16.0 * tolerance:
            factored_h = 0.0
            if contact_violated_inside(
                    method, system, points, count, loaded, motor_torque, load_torque, state,
                    rate, high, absolute_tolerance, relative_tolerance, jacobian, real,
                    real_pivots, complex_, complex_pivots, stages, work, trial_state, approach,
                    contact_slack):
                return time, interval, cycle, h, CONTACT_VIOLATED, steps
        state[:] = new_state
        time = end if landing and high == h_step else time + high
        stalled_events = stalled_events + 1 if high <= 1e-12 * h_step else 0
        if stalled_events > MAX_EVENTS_WITHOUT_PROGRESS:
            return time, interval, cycle, h_next, STALLED, steps
        if event < 2:
            reversals = reversals + 1 if event != last_phase_event else 0
            last_phase_event = event
            if reversals > MAX_PHASE_REVERSALS:
                return time, interval, cycle, h_next, CHATTER, steps
        interval, cycle = next_segment(system, lengths, counts, tables, event, interval, cycle,
                                       state, loaded, approach)
        points, count, length = tables[interval], counts[interval], lengths[interval]
        events = 2 + (count if system.contact_loss else 0)
        segment_number += 1
        derivative(system, points, count, loaded, motor_torque, load_torque, state, rate)
        event_values(system, points, count, length, state, approach, values_before)
        if system.contact_loss:
            approach_rates(system, points, count, state, rate, slopes_before)

        h = h_next
        if event == 0:
            # The switch sets off vibration that the step before it did not see: start the
            # set as the step taken after the last entry into it proposed (the mesh repeats).
            if first_steps[interval] > 0.0:
                h = min(h, first_steps[interval])
            opening = interval
    for j in range(size):
        if not math.isfinite(state[j]):
            return time, interval, cycle, h, NOT_FINITE, steps
    return time, interval, cycle, h, OK, steps


@njit(cache=True, error_model="numpy")
def next_segment(system, lengths, counts, tables, event, interval, cycle, state, loaded,
                 approach):
    """What follows an event: a phase event moves to the next (or previous) contact set and
    re-expresses the pinion entry of `state` from the new set's start (by lengths, not
    absolute angles, so it stays exact however far the train has turned); then every point
    of the set is loaded by the sign of its approach. That rule, not a flip of the point
    whose event fired, is what keeps the loaded set true to the state: a point that crossed
    zero in the same bracket as the located event (a whole train separating or landing at
    once) starts the segment on its own side, with its own event ahead of it. Updates state
    and loaded; returns the new (interval, cycle)."""
    if event == 0:
        state[system.pinion] -= lengths[interval]
        interval += 1
        if interval == lengths.shape[0]:
            interval, cycle = 0, cycle + 1
    elif event == 1:
        interval -= 1
        if interval < 0:
            interval, cycle = lengths.shape[0] - 1, cycle - 1
        state[system.pinion] += lengths[interval]
    set_loaded_by_sign(system, tables[interval], counts[interval], state, approach, loaded)
    return interval, cycle


@njit(cache=True, error_model="numpy")
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
