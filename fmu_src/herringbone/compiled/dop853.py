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

import numpy as np
from numba import njit
from scipy.integrate._ivp.dop853_coefficients import A, B, E3, E5, N_STAGES

from .equations import derivative

ERROR_EXPONENT = -1.0 / 8.0  # the step-size controller's exponent: −1/(order of E5 + 1)
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
BETA = 0.04  # weight of the previous error in the step-size control
STAGE_ROWS = N_STAGES + 1
_A = A[:N_STAGES, :N_STAGES].copy()
_ERROR_STAGES = tuple(int(k) for k in np.flatnonzero((E5 != 0.0) | (E3 != 0.0)))


@njit(cache=True, error_model="numpy", fastmath={"contract", "reassoc"})
def step(system, points, count, loaded, motor_torque, load_torque, state, rate, h,
         absolute_tolerance, relative_tolerance, stages, trial, new_state):
    size = state.shape[0]
    stages[0, :] = rate
    # k outer, state entries inner: rows of `stages` are contiguous, and a zero of A is skipped
    for stage in range(1, N_STAGES):
        trial[:] = state
        for k in range(stage):
            weight = h * _A[stage, k]
            if weight != 0.0:
                for j in range(size):
                    trial[j] += weight * stages[k, j]
        derivative(system, points, count, loaded, motor_torque, load_torque, trial,
                   stages[stage])
    new_state[:] = state
    for k in range(N_STAGES):
        weight = h * B[k]
        if weight != 0.0:
            for j in range(size):
                new_state[j] += weight * stages[k, j]
    derivative(system, points, count, loaded, motor_torque, load_torque, new_state,
               stages[N_STAGES])
    # the 5th- and 3rd-order error estimates, scaled entry by entry
    error5 = error3 = 0.0
    for j in range(size):
        estimate5 = estimate3 = 0.0
        for k in _ERROR_STAGES:
            estimate5 += E5[k] * stages[k, j]
            estimate3 += E3[k] * stages[k, j]
        inverse_scale = 1.0 / (absolute_tolerance[j] + relative_tolerance
                               * max(abs(state[j]), abs(new_state[j])))
        error5 += (estimate5 * inverse_scale) ** 2
        error3 += (estimate3 * inverse_scale) ** 2
    if error5 == 0.0 and error3 == 0.0:
        return 0.0
    return abs(h) * error5 / math.sqrt((error5 + 0.01 * error3) * size)


@njit(cache=True, error_model="numpy")
def step_factor(error_norm, previous_error_norm, rejected):
    """By how much to scale h after a step with this error norm. Accepted steps take Hairer's
    stabilized controller (err^−(1/8 − 0.2β)·err_previous^β, β = 0.04, as his DOPRI5 code):
    at the stability bound, where the high modes set the step, plain control alternates
    between growing the step and rejecting it (measured: a quarter of all steps rejected)."""
    if error_norm > 1.0:
        return max(MIN_FACTOR, SAFETY * error_norm ** ERROR_EXPONENT)
    if error_norm == 0.0:
        return 1.0 if rejected else MAX_FACTOR
    factor = SAFETY * error_norm ** -(1.0 / 8.0 - 0.2 * BETA) * previous_error_norm ** BETA
    factor = min(MAX_FACTOR, max(MIN_FACTOR, factor))
    return min(1.0, factor) if rejected else factor
