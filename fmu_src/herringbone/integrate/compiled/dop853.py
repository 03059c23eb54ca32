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
from numpy.typing import ArrayLike
from scipy.integrate._ivp.dop853_coefficients import E3, E5, N_STAGES, A, B

from ...model.equations import derivative

ERROR_EXPONENT = -1.0 / 8.0  # the step-size controller's exponent: −1/(order of E5 + 1)
# SAFETY below Hairer's 0.9: the error estimate swings 0.03-0.6 from step to step at one h while
# the fastest modes ring after a switch, and at 0.9 one step in nine was rejected; at 0.85, one
# in forty, for 6 % more accepted steps and 3 % fewer steps in all (staggered scene)
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.85, 0.2, 10.0
BETA = 0.04  # weight of the previous error in the step-size control
STAGE_ROWS = N_STAGES + 1
# The nonzero weights by Hairer's names (dop853.f): stage i is y + h·Σ a_ij·k_j, the result
# y + h·Σ b_j·k_j, the error estimates Σ e_j·k_j. Written out below as his code does: one loop
# per stage with its terms fixed lets the compiler keep them in registers (0.30 µs of sums a
# step against 0.52 µs for a loop over the table's nonzeros).
A21 = A[1, 0]
A31, A32 = A[2, 0], A[2, 1]
A41, A43 = A[3, 0], A[3, 2]
A51, A53, A54 = A[4, 0], A[4, 2], A[4, 3]
A61, A64, A65 = A[5, 0], A[5, 3], A[5, 4]
A71, A74, A75, A76 = A[6, 0], A[6, 3], A[6, 4], A[6, 5]
A81, A84, A85, A86, A87 = A[7, [0, *range(3, 7)]]
A91, A94, A95, A96, A97, A98 = A[8, [0, *range(3, 8)]]
A101, A104, A105, A106, A107, A108, A109 = A[9, [0, *range(3, 9)]]
A111, A114, A115, A116, A117, A118, A119, A1110 = A[10, [0, *range(3, 10)]]
A121, A124, A125, A126, A127, A128, A129, A1210, A1211 = A[11, [0, *range(3, 11)]]
B1, B6, B7, B8, B9, B10, B11, B12 = B[[0, *range(5, 12)]]
E51, E56, E57, E58, E59, E510, E511, E512 = E5[[0, *range(5, 12)]]
E31, E36, E37, E38, E39, E310, E311, E312 = E3[[0, *range(5, 12)]]
assert all(A[i, j] == 0.0 for i, j in ((3, 1), (4, 1), (5, 1), (5, 2)) + tuple(
    (i, j) for i in range(6, 12) for j in (1, 2))) and not B[1:5].any() \
    and not E5[1:5].any() and not E3[1:5].any() and E5[12] == E3[12] == 0.0


def stability_function(z: ArrayLike) -> np.ndarray:
    """R(z): the factor one step multiplies the mode y' = λ·y by, at z = h·λ (complex, any
    shape; the result has its shape). The exact factor is e^z; ln(R(z))/h is the eigenvalue
    the method integrates the mode with."""
    z = np.asarray(z, dtype=complex)
    stages = np.ones(z.shape + (N_STAGES,), dtype=complex)
    for i in range(1, N_STAGES):  # explicit: each stage from the ones before it
        stages[..., i] = 1.0 + z * (stages[..., :i] @ A[i, :i])
    return 1.0 + z * (stages @ B[:N_STAGES])


# No fastmath: with contraction and reassociation allowed, code compiled in the process and the
# same code loaded from numba's cache gave results that differ in the last bits (a sweep on
# Dask workers, which load it, against the same sweep in the process that compiled it).
# Without, every start of every host computes the same bits; the cost was within the noise.
@njit(cache=True, error_model="numpy")
def step(system, segment, state, rate, h, absolute_tolerance, relative_tolerance, stages, trial,
         new_state):
    """One DOP853 step of size h (s) from `state`, whose derivative is `rate`: see the module's
    docstring for the contract.

    `segment` holds the equations (walk.CompiledSegment: its points, point_count, loaded,
    motor_torque and load_torque, as equations.derivative takes them); `absolute_tolerance`
    is per entry of the state (its units), `relative_tolerance` a number. Work arrays:
    `stages`, STAGE_ROWS rows of the state's size (row k the stage k + 1 derivative, row
    N_STAGES the new state's), and `trial`, one state. Returns the error norm (≤ 1:
    acceptable)."""
    for j in range(rate.shape[0]):
        stages[0, j] = rate[j]
    # one call site of the (inlined) derivative: thirteen copies would crowd the code cache
    for stage in range(1, N_STAGES):
        _stage_state(stage, state, h, stages, trial)
        derivative(system, segment.points, segment.point_count, segment.loaded,
                   segment.motor_torque, segment.load_torque, trial, stages[stage])
    error = _solution_and_error(state, h, stages, absolute_tolerance, relative_tolerance,
                                new_state)
    derivative(system, segment.points, segment.point_count, segment.loaded,
               segment.motor_torque, segment.load_torque, new_state, stages[N_STAGES])
    return error


@njit(cache=True, error_model="numpy", inline="always")
def _stage_state(stage, state, h, stages, trial):
    """The state stage number `stage` (1 to N_STAGES − 1) evaluates the derivative at, into
    `trial`: y + h·Σ a_ij·k_j over the stages before it (k_j: row j − 1 of `stages`)."""
    size = state.shape[0]
    k = stages  # indexed k[row, j]: a view of a row per stage would be counted, 121 a step
    if stage == 1:
        for j in range(size):
            trial[j] = state[j] + h * A21 * k[0, j]
    elif stage == 2:
        for j in range(size):
            trial[j] = state[j] + h * (A31 * k[0, j] + A32 * k[1, j])
    elif stage == 3:
        for j in range(size):
            trial[j] = state[j] + h * (A41 * k[0, j] + A43 * k[2, j])
    elif stage == 4:
        for j in range(size):
            trial[j] = state[j] + h * (A51 * k[0, j] + A53 * k[2, j] + A54 * k[3, j])
    elif stage == 5:
        for j in range(size):
            trial[j] = state[j] + h * (A61 * k[0, j] + A64 * k[3, j] + A65 * k[4, j])
    elif stage == 6:
        for j in range(size):
            trial[j] = state[j] + h * (A71 * k[0, j] + A74 * k[3, j] + A75 * k[4, j]
                                       + A76 * k[5, j])
    elif stage == 7:
        for j in range(size):
            trial[j] = state[j] + h * (A81 * k[0, j] + A84 * k[3, j] + A85 * k[4, j]
                                       + A86 * k[5, j] + A87 * k[6, j])
    elif stage == 8:
        for j in range(size):
            trial[j] = state[j] + h * (A91 * k[0, j] + A94 * k[3, j] + A95 * k[4, j]
                                       + A96 * k[5, j] + A97 * k[6, j] + A98 * k[7, j])
    elif stage == 9:
        for j in range(size):
            trial[j] = state[j] + h * (A101 * k[0, j] + A104 * k[3, j] + A105 * k[4, j]
                                       + A106 * k[5, j] + A107 * k[6, j] + A108 * k[7, j]
                                       + A109 * k[8, j])
    elif stage == 10:
        for j in range(size):
            trial[j] = state[j] + h * (A111 * k[0, j] + A114 * k[3, j] + A115 * k[4, j]
                                       + A116 * k[5, j] + A117 * k[6, j] + A118 * k[7, j]
                                       + A119 * k[8, j] + A1110 * k[9, j])
    else:
        for j in range(size):
            trial[j] = state[j] + h * (A121 * k[0, j] + A124 * k[3, j] + A125 * k[4, j]
                                       + A126 * k[5, j] + A127 * k[6, j] + A128 * k[7, j]
                                       + A129 * k[8, j] + A1210 * k[9, j] + A1211 * k[10, j])


@njit(cache=True, error_model="numpy", inline="always")
def _solution_and_error(state, h, stages, absolute_tolerance, relative_tolerance, new_state):
    """The 8th-order solution into `new_state`, and the error norm: the 5th- and 3rd-order
    estimates scaled entry by entry and combined as Hairer's code does."""
    size = state.shape[0]
    k1, k6, k7, k8 = stages[0], stages[5], stages[6], stages[7]
    k9, k10, k11, k12 = stages[8], stages[9], stages[10], stages[11]
    error5 = error3 = 0.0
    for j in range(size):
        new_state[j] = state[j] + h * (B1 * k1[j] + B6 * k6[j] + B7 * k7[j] + B8 * k8[j]
                                       + B9 * k9[j] + B10 * k10[j] + B11 * k11[j] + B12 * k12[j])
        estimate5 = (E51 * k1[j] + E56 * k6[j] + E57 * k7[j] + E58 * k8[j] + E59 * k9[j]
                     + E510 * k10[j] + E511 * k11[j] + E512 * k12[j])
        estimate3 = (E31 * k1[j] + E36 * k6[j] + E37 * k7[j] + E38 * k8[j] + E39 * k9[j]
                     + E310 * k10[j] + E311 * k11[j] + E312 * k12[j])
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
