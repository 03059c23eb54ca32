"""The variational equations of the gear train through its segments, compiled: a state and its
sensitivity Φ = ∂x(t)/∂x(0)·D to the initial state along directions D, over a fixed time.

Within a segment (contact set and loaded points fixed) the equations (model/equations.py) are smooth
and Φ obeys Φ' = J(x)·Φ, J = ∂f/∂x the Jacobian of equations.derivative (`sensitivity_rate`,
analytic: the contact points' forces F_i = c_i·(δ_i + η·δ̇_i) are sums of products of the state
with the points' stiffness c, lever arm ζ and lead error e, each linear in the pinion's travel).
The state and Φ are stepped together by DOP853's order-8 stages at a fixed step (no error
control: the caller sets the step, integrate/variational.multiplier_step), the stages of Φ
those of the linearized stages: Φ is the exact derivative of the discrete step map, and that
map is the flow to order 8.

At an event (walk.py's: φp at the end or start of its contact interval, a point's approach
δ + η·δ̇ crossing zero) the vector field changes from f⁻ to f⁺, and a perturbation that moves
the event's time moves the state after it: Φ jumps by the saltation matrix
S = I + (f⁺ − f⁻)·∇gᵀ/(∇g·f⁻), g the event function (φp − length, φp, or the point's approach).
At a phase event (∇g = e_φp) the points that enter (sharp face edges) take their force at
once, so f jumps; at a contact event the point's force c·(δ + η·δ̇) is zero at the crossing, f
is continuous and S = I exactly, but J changes from one segment to the next (a point that
grazes, ∇g·f⁻ → 0, so adds no spurious jump). Events are located by regula falsi
(Illinois) on trial steps of the state alone to EVENT_LOCATION of the step, and the segment
ends just past the crossing, as walk.py ends it; what follows is walk.next_segment's (every
point loaded by the sign of its approach).

Units: time in s, the state as model/equations.py lays it out, Φ in the state's units per unit of
the directions, torques in N·m.
"""
from __future__ import annotations

import math
from enum import IntEnum

import numpy as np
from numba import njit
from scipy.integrate._ivp.dop853_coefficients import N_STAGES, A, B

from ...compiling.counting import COUNTED
from ...model.equations import (
    LEAD_ERROR_SLOPE,
    LEVER_ARM_SLOPE,
    STIFFNESS_SLOPE,
    Event,
    PeriodTable,
    contact_motion,
    derivative,
    point_approach,
    point_at,
    unpack_system,
)
from .walk import event_values, first_crossing, next_segment, segment_of

# the steps of DOP853's tableau, as a dense table: stage i is x + h·Σ_j STAGE_WEIGHTS[i, j]·k_j
STAGE_WEIGHTS = np.ascontiguousarray(A[:N_STAGES, :N_STAGES])
SOLUTION_WEIGHTS = np.ascontiguousarray(B[:N_STAGES])
# an event is located to this fraction of the step it was crossed in (rounding allowing)
EVENT_LOCATION = 1e-13
MAX_LOCATION_TRIALS = 80
MAX_EVENTS = 100000  # events in one call beyond this: chatter, the call fails


class Status(IntEnum):
    """How `flow_sensitivity` ended."""

    OK = 0
    TOO_MANY_EVENTS = 1
    NOT_FINITE = 2


@njit(cache=True, error_model="numpy")
def contact_gradients(system, points, count, loaded, state, total_row, moment_row):
    """The rows ∂(Σ F_i)/∂x and ∂(Σ ζ_i·F_i)/∂x (N and N·m per unit of each state entry) over
    the loaded points of the set at `state`: the contact part of J, which acts on the
    accelerations through System.contact_base_acceleration and contact_tilt_acceleration."""
    n = system.mass.shape[0]
    base_row, tilt_row = system.contact_row_base_relative, system.contact_row_tilt_relative
    eta, speed_of_travel = system.mesh_damping_factor, system.axial_travel_per_radian
    motion = contact_motion(system, state)
    _, tilt, _, tilt_rate, travel = motion
    stiffness_sum = lever_sum = lever_square_sum = 0.0  # Σ c, Σ c·ζ, Σ c·ζ²
    total_travel = moment_travel = 0.0  # ∂/∂(travel) of Σ F and Σ ζ·F
    for i in range(count):
        if loaded[i] == 0.0:
            continue
        stiffness, lever_arm, lead_error = point_at(points, i, travel)
        approach = point_approach(system, motion, lever_arm, lead_error)
        # ∂(approach)/∂(travel): the lever arm and lead error move with it
        approach_travel = (points[LEVER_ARM_SLOPE, i] * (tilt + eta * tilt_rate)
                           + points[LEAD_ERROR_SLOPE, i])
        force_travel = points[STIFFNESS_SLOPE, i] * approach + stiffness * approach_travel
        stiffness_sum += stiffness
        lever_sum += stiffness * lever_arm
        lever_square_sum += stiffness * lever_arm * lever_arm
        total_travel += force_travel
        moment_travel += (lever_arm * force_travel
                          + points[LEVER_ARM_SLOPE, i] * stiffness * approach)
    for j in range(n):
        total_row[j] = stiffness_sum * base_row[j] + lever_sum * tilt_row[j]
        moment_row[j] = lever_sum * base_row[j] + lever_square_sum * tilt_row[j]
        total_row[n + j] = eta * total_row[j]
        moment_row[n + j] = eta * moment_row[j]
    # the relative rows have no pinion entry: the pinion angle acts through the travel alone
    total_row[system.pinion] += speed_of_travel * total_travel
    moment_row[system.pinion] += speed_of_travel * moment_travel


@njit(cache=True, error_model="numpy")
def sensitivity_rate(system, points, count, loaded, state, sensitivity, rows, sums, out):
    """out = J(state)·sensitivity (each column a perturbation of the state), J = ∂f/∂x of
    equations.derivative with the segment's set and loaded points. rows: two rows of the
    state's size, sums two of the sensitivity's columns (scratch). The columns' loops are the
    innermost: their terms are independent and vectorize."""
    n = system.mass.shape[0]
    columns = sensitivity.shape[1]
    total_row, moment_row = rows[0], rows[1]
    totals, moments = sums[0], sums[1]
    contact_gradients(system, points, count, loaded, state, total_row, moment_row)
    totals[:] = 0.0
    moments[:] = 0.0
    for j in range(2 * n):
        to_total, to_moment = total_row[j], moment_row[j]
        for c in range(columns):
            totals[c] += to_total * sensitivity[j, c]
            moments[c] += to_moment * sensitivity[j, c]
    for j in range(n):
        base, tilt = system.contact_base_acceleration[j], system.contact_tilt_acceleration[j]
        for c in range(columns):
            out[j, c] = sensitivity[n + j, c]
            out[n + j, c] = -totals[c] * base - moments[c] * tilt
    for entry in range(system.coupling_row.shape[0]):
        k, row = system.coupling_column[entry], n + system.coupling_row[entry]
        elastic, damping = system.elastic_acceleration[entry], system.damping_acceleration[entry]
        for c in range(columns):
            out[row, c] += elastic * sensitivity[k, c] + damping * sensitivity[n + k, c]


@njit(cache=True, error_model="numpy", inline="always")
def weighted_sum(weights, stages, count, j):
    """Σ_k<count weights[k]·stages[k, j]: a stage's or the solution's sum of DOP853, in one
    order wherever it is formed, so that the state's steps end on the same bits."""
    total = 0.0
    for k in range(count):
        total += weights[k] * stages[k, j]
    return total


@njit(cache=True, error_model="numpy")
def dop853_step(system, segment, state, h, stages, stage_states, out):
    """One fixed DOP853 step of h (s) of the state alone into `out`; stages and stage_states
    (N_STAGES rows of the state's size) keep each stage's derivative and state, which
    variational_step then takes over for a step of the same h from the same state."""
    size = state.shape[0]
    for stage in range(N_STAGES):
        for j in range(size):
            stage_states[stage, j] = state[j] + h * weighted_sum(STAGE_WEIGHTS[stage], stages,
                                                                  stage, j)
        derivative(system, segment.points, segment.point_count, segment.loaded,
                   segment.motor_torque, segment.load_torque, stage_states[stage],
                   stages[stage])
    for j in range(size):
        out[j] = state[j] + h * weighted_sum(SOLUTION_WEIGHTS, stages, N_STAGES, j)


@njit(cache=True, error_model="numpy")
def variational_step(system, segment, state, sensitivity, h, work, stepped):
    """One fixed DOP853 step of h (s) of the state and its sensitivity together, in place: the
    sensitivity's stages are the linearized stages J(stage state)·(stage sensitivity).
    `stepped`: dop853_step has just made this step of the state (same h, same start) into
    work's stages and stage states, which are taken as they are."""
    stages, stage_states, sensitivity_stages, stage_sensitivity, rows, sums = work
    size, columns = sensitivity.shape
    for stage in range(N_STAGES):
        for j in range(size):
            if not stepped:
                stage_states[stage, j] = state[j] + h * weighted_sum(STAGE_WEIGHTS[stage],
                                                                      stages, stage, j)
            # the sensitivity's sums by columns, each term independent of the last: the
            # columns' loop is the innermost and vectorizes
            for c in range(columns):
                stage_sensitivity[j, c] = sensitivity[j, c]
            for k in range(stage):
                weight = h * STAGE_WEIGHTS[stage, k]
                if weight != 0.0:
                    for c in range(columns):
                        stage_sensitivity[j, c] += weight * sensitivity_stages[k, j, c]
        if not stepped:
            derivative(system, segment.points, segment.point_count, segment.loaded,
                       segment.motor_torque, segment.load_torque, stage_states[stage],
                       stages[stage])
        sensitivity_rate(system, segment.points, segment.point_count, segment.loaded,
                         stage_states[stage], stage_sensitivity, rows, sums,
                         sensitivity_stages[stage])
    for j in range(size):
        state[j] += h * weighted_sum(SOLUTION_WEIGHTS, stages, N_STAGES, j)
        for k in range(N_STAGES):
            weight = h * SOLUTION_WEIGHTS[k]
            if weight != 0.0:
                for c in range(columns):
                    sensitivity[j, c] += weight * sensitivity_stages[k, j, c]


@njit(cache=True, error_model="numpy")
def locate(system, segment, state, event, high, values_low, values_high, work):
    """The crossing of `event` inside a step of `high` (s) from `state` (event values at the
    step's ends in values_low, values_high), by regula falsi (Illinois) on trial steps of the
    state; another event found to cross first is located instead. Returns (the event, the
    bracket's high end, s: the event has crossed there)."""
    stages, stage_states, trial, trial_values, approach = work
    low = 0.0
    tolerance = EVENT_LOCATION * high
    low_value, high_value = values_low[event], values_high[event]
    side = 0  # which end the last two estimates kept (Illinois: halve the other's value)
    for _ in range(MAX_LOCATION_TRIALS):
        if high - low <= tolerance:
            break
        estimate = (low - low_value * (high - low) / (high_value - low_value)
                    if high_value != low_value else 0.5 * (low + high))
        if not low < estimate < high:
            estimate = 0.5 * (low + high)
        dop853_step(system, segment, state, estimate, stages, stage_states, trial)
        event_values(system, segment, trial, approach, trial_values)
        crossed = first_crossing(values_low, trial_values, segment.events, segment.loaded)
        if crossed < 0:
            low, low_value = estimate, trial_values[event]
            values_low[:] = trial_values
            high_value = 0.5 * high_value if side == -1 else high_value
            side = -1
        else:
            if crossed != event:
                event, low_value = crossed, values_low[crossed]
                side = 0
            elif side == 1:
                low_value *= 0.5
            else:
                side = 1
            high, high_value = estimate, trial_values[event]
            values_high[:] = trial_values
    return event, high


@njit(cache=True, error_model="numpy")
def saltation(system, mesh, event, interval, cycle, state, loaded, torques, sensitivity, rates,
              approach):
    """Φ ← S·Φ at an event, S = I + (f⁺ − f⁻)·∇gᵀ/(∇g·f⁻), and the state and loaded points
    moved into the segment that follows (walk.next_segment). `state` is just past the
    crossing in the old segment (contact interval `interval` of mesh cycle `cycle`). rates:
    two rows of the state's size, approach one a point (scratch). Returns the new (interval,
    cycle)."""
    n2 = state.shape[0]
    if event >= Event.CONTACT:
        # the point's force c·(δ + η·δ̇) is zero where its approach crosses zero: f⁺ = f⁻
        # there and S = I. (Taken past the crossing, f⁺ − f⁻ is c times the overshoot, and
        # ∇g·f⁻ goes to zero where the point grazes: their ratio is the location's error.)
        return next_segment(system, mesh, event, interval, cycle, state, loaded, approach)
    points, count = mesh.tables[interval], mesh.counts[interval]
    before, after = rates[0], rates[1]
    derivative(system, points, count, loaded, torques[0], torques[1], state, before)
    # ∇g = e_φp for both phase events: ∇g·f⁻ = φp's rate
    slope = before[system.pinion]
    interval, cycle = next_segment(system, mesh, event, interval, cycle, state, loaded,
                                   approach)
    derivative(system, mesh.tables[interval], mesh.counts[interval], loaded, torques[0],
               torques[1], state, after)
    if slope != 0.0:
        for c in range(sensitivity.shape[1]):
            moved = sensitivity[system.pinion, c] / slope
            for j in range(n2):
                sensitivity[j, c] += (after[j] - before[j]) * moved
    return interval, cycle


@njit(**COUNTED)
def flow_sensitivity(floats, ints, mesh_arrays, interval, cycle, loaded_in, state_in,
                     duration, torques, max_step, directions):
    """The state after `duration` (s) from `state_in` in contact interval `interval` of mesh
    cycle `cycle` with the points `loaded_in` (1.0/0.0, padded to the widest set), and its
    sensitivity ∂x(duration)/∂x(0)·directions; steps of at most `max_step` (s), the segments
    ended at every event (module docstring). Returns (status, state, sensitivity, interval,
    cycle, loaded, events)."""
    system = unpack_system(floats, ints)
    mesh = PeriodTable(*mesh_arrays)
    size, columns = directions.shape
    state, sensitivity = state_in.copy(), directions.copy()
    loaded = loaded_in.copy()
    width = Event.CONTACT + loaded.shape[0]
    stages, stage_states = np.empty((N_STAGES, size)), np.empty((N_STAGES, size))
    work = (stages, stage_states, np.empty((N_STAGES, size, columns)),
            np.empty((size, columns)), np.empty((2, size)), np.empty((2, columns)))
    trial, values = np.empty(size), np.empty((4, width))
    location = (stages, stage_states, trial, values[2], np.empty(loaded.shape[0]))
    rates = np.empty((2, size))
    time, events, status = 0.0, 0, Status.OK
    while time < duration and status == Status.OK:
        segment = segment_of(system, mesh, interval, loaded, torques, -1)
        h = min(max_step, duration - time)
        if duration - time - h <= 1e-12 * duration:
            h = duration - time
        event_values(system, segment, state, location[4], values[0])
        dop853_step(system, segment, state, h, stages, stage_states, trial)
        event_values(system, segment, trial, location[4], values[1])
        event = first_crossing(values[0], values[1], segment.events, loaded)
        if event >= 0:
            event, h = locate(system, segment, state, event, h, values[0], values[1],
                              location)
        # without an event the trial was this very step: its stages are taken over
        variational_step(system, segment, state, sensitivity, h, work, event < 0)
        time = duration if h == duration - time else time + h
        if event >= 0:
            events += 1
            interval, cycle = saltation(system, mesh, event, interval, cycle, state, loaded,
                                        torques, sensitivity, rates, location[4])
            if events > MAX_EVENTS:
                status = Status.TOO_MANY_EVENTS
        for j in range(size):
            if not math.isfinite(state[j]):
                status = Status.NOT_FINITE
    return status.value, state, sensitivity, interval, cycle, loaded, events
