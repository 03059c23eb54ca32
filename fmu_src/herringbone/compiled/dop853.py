"""DOP853: the explicit Runge-Kutta method of order 8 of Hairer, Nørsett and Wanner.

Used for the scenes whose highest natural frequency an explicit method can follow at a step size
set by accuracy (walk.py says when). The coefficients are scipy's (the same method as
`solve_ivp(method="DOP853")`), so the two differ only in where their loops run.

Contract of `step`: from `state` at the start of the step, whose derivative is `rate`, take one
step of size h with the segment (contact set, loaded points, torques) fixed. Write the 8th-order
result to `new_state` and its derivative to `stages[N_STAGES]` (first same as last: it is the
next step's `rate` if the step is accepted and the segment goes on). Return the error norm
(≤ 1: acceptable) measured as scipy measures it: the 5th- and 3rd-order error estimates combined,
scaled by absolute_tolerance + relative_tolerance·|state| entry by entry, root mean square.
Nothing else is touched, so a step can be retried from the same `state` with another h.
"""
from __future__ import annotations

import math

from numba import njit
from scipy.integrate._ivp.dop853_coefficients import A, B, C, E3, E5, N_STAGES  # noqa: F401

from .equations import derivative

ERROR_EXPONENT = -1.0 / 8.0  # the step-size controller's exponent: −1/(order of E5 + 1)
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
STAGE_ROWS = N_STAGES + 1
_A = A[:N_STAGES, :N_STAGES].copy()


@njit(cache=True)
def step(system, points, count, loaded, motor_torque, load_torque, state, rate, h,
         absolute_tolerance, relative_tolerance, stages, trial, new_state):
    size = state.shape[0]
    stages[0, :] = rate
    for stage in range(1, N_STAGES):
        for j in range(size):
            increment = 0.0
            for k in range(stage):
                increment += _A[stage, k] * stages[k, j]
            trial[j] = state[j] + h * increment
        derivative(system, points, count, loaded, motor_torque, load_torque, trial,
                   stages[stage])
    for j in range(size):
        increment = 0.0
        for k in range(N_STAGES):
            increment += B[k] * stages[k, j]
        new_state[j] = state[j] + h * increment
    derivative(system, points, count, loaded, motor_torque, load_torque, new_state,
               stages[N_STAGES])
    error5 = error3 = 0.0
    for j in range(size):
        scale = absolute_tolerance[j] + relative_tolerance * max(abs(state[j]),
                                                                 abs(new_state[j]))
        estimate5 = estimate3 = 0.0
        for k in range(STAGE_ROWS):
            estimate5 += E5[k] * stages[k, j]
            estimate3 += E3[k] * stages[k, j]
        error5 += (estimate5 / scale) ** 2
        error3 += (estimate3 / scale) ** 2
    if error5 == 0.0 and error3 == 0.0:
        return 0.0
    return abs(h) * error5 / math.sqrt((error5 + 0.01 * error3) * size)


@njit(cache=True)
def step_factor(error_norm, rejected):
    """By how much to scale h after a step with this error norm (scipy's controller)."""
    if error_norm > 1.0:
        return max(MIN_FACTOR, SAFETY * error_norm ** ERROR_EXPONENT)
    factor = MAX_FACTOR if error_norm == 0.0 else min(MAX_FACTOR,
                                                       SAFETY * error_norm ** ERROR_EXPONENT)
    return min(1.0, factor) if rejected else factor
