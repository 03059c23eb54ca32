"""Radau IIA of order 5: the implicit, L-stable Runge-Kutta method of Hairer and Wanner.

For overdamped stiff trains (very stiff, strongly damped bearings on light bodies): its step
size is set by accuracy alone, and modes far above what the step resolves are damped, not
amplified (L-stability). The constants are scipy's (`solve_ivp(method="Radau")`); the algorithm
follows scipy's, which follows Hairer & Wanner's RADAU5: the collocation system is solved by
simplified Newton iterations on its real and complex blocks.

Contract of `step`: from `state`, whose derivative is `rate`, with `jacobian` the derivative's
Jacobian and `factors` the LU factors of (MU_REAL/h·I − J) and (MU_COMPLEX/h·I − J) for this h
(`factorize`), take one step of size h with the segment fixed. Write the result to `new_state`
and return (error norm, Newton iterations); the error norm is inf if Newton did not converge
(then retry with a fresh Jacobian or a smaller h). After a rejected step, an error norm over 1
is estimated again (`_second_estimate`). The next step's size is `step_factor`'s, with
`predicted_factor`'s prediction from the last accepted step. Within a segment the equations are
linear in every entry but the pinion angle, which only moves the contact points slowly, so
Newton converges in a few iterations on a Jacobian taken at the segment's start; it is taken to
rounding, which keeps the train's angular momentum (docs/integrator.md, Methods).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from scipy.integrate._ivp.radau import (
    MU_COMPLEX,
    MU_REAL,
    NEWTON_MAXITER,
    TI_COMPLEX,
    TI_REAL,
    E,
    T,
)

from ...compiling.counting import COUNTED
from ...model.equations import derivative

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
_TI_REAL, _TI_COMPLEX, _T, _E = (np.ascontiguousarray(a) for a in (TI_REAL, TI_COMPLEX, T, E))


@njit(**COUNTED)
def lu_factor(matrix, pivots):
    """In place: LU with partial pivoting (real or complex). The systems here are at most
    16 × 16, so a plain loop beats calling LAPACK through numba's allocating wrappers."""
    size = matrix.shape[0]
    for column in range(size):
        pivot = column
        for row in range(column + 1, size):
            if abs(matrix[row, column]) > abs(matrix[pivot, column]):
                pivot = row
        pivots[column] = pivot
        if pivot != column:
            for k in range(size):
                matrix[column, k], matrix[pivot, k] = matrix[pivot, k], matrix[column, k]
        if matrix[column, column] != 0.0:
            for row in range(column + 1, size):
                matrix[row, column] /= matrix[column, column]
                for k in range(column + 1, size):
                    matrix[row, k] -= matrix[row, column] * matrix[column, k]


@njit(**COUNTED)
def lu_solve(matrix, pivots, vector):
    """In place: `vector` becomes the solution x of A·x = vector, `matrix` and `pivots` being
    the factors lu_factor made of A."""
    size = matrix.shape[0]
    for i in range(size):
        vector[i], vector[pivots[i]] = vector[pivots[i]], vector[i]
        for k in range(i):
            vector[i] -= matrix[i, k] * vector[k]
    for i in range(size - 1, -1, -1):
        for k in range(i + 1, size):
            vector[i] -= matrix[i, k] * vector[k]
        vector[i] /= matrix[i, i]


@njit(**COUNTED)
def jacobian_of(system, segment, state, rate, absolute_tolerance, relative_tolerance, jacobian,
                trial, column):
    """The Jacobian ∂(derivative)/∂(state) of the segment (its equations as `step` takes them)
    at `state` (whose derivative is `rate`) into `jacobian`, by forward differences of size
    1e-7·max(|state_k|, typical_k) per column k, typical_k = absolute_tolerance_k /
    relative_tolerance being the entry's typical magnitude (GearTrainModel.state_scales, in
    its units); exact but for rounding in every entry the equations are linear in. Work
    arrays: `trial` and `column`, one state each."""
    size = state.shape[0]
    for k in range(size):
        trial[:] = state
        # not a tolerance-sized step: where an entry is near zero (the pinion's, re-expressed
        # from each set's start; a tilt at rest) it would be lost in the derivative's rounding
        delta = 1e-7 * max(abs(state[k]), absolute_tolerance[k] / relative_tolerance)
        trial[k] += delta
        derivative(system, segment.points, segment.point_count, segment.loaded,
                   segment.motor_torque, segment.load_torque, trial, column)
        for i in range(size):
            jacobian[i, k] = (column[i] - rate[i]) / delta


class Factors(NamedTuple):
    """The LU factors `step` solves with, as lu_factor leaves them (`factorize` makes them for
    one step size)."""

    real: np.ndarray  # of MU_REAL/h·I − J
    real_pivots: np.ndarray
    complex: np.ndarray  # of MU_COMPLEX/h·I − J (complex128)
    complex_pivots: np.ndarray


@njit(**COUNTED)
def factorize(jacobian, h, factors):
    """The LU factors `step` takes for step size h (s) into `factors` (a Factors record):
    (MU_REAL/h·I − J) and (MU_COMPLEX/h·I − J). `jacobian` is not changed."""
    size = jacobian.shape[0]
    real, complex_ = factors.real, factors.complex
    for i in range(size):
        for k in range(size):
            real[i, k] = -jacobian[i, k]
            complex_[i, k] = -jacobian[i, k]
        real[i, i] += MU_REAL / h
        complex_[i, i] += MU_COMPLEX / h
    lu_factor(real, factors.real_pivots)
    lu_factor(complex_, factors.complex_pivots)


@njit(**COUNTED)
def step(system, segment, state, rate, h, absolute_tolerance, relative_tolerance, factors,
         stages, new_state, rejected):
    """One Radau IIA step of size h (s) from `state`, whose derivative is `rate`, with the
    `factors` that `factorize` made for this h: see the module's docstring for the contract.

    `segment` holds the equations (walk.CompiledSegment: its points, point_count, loaded,
    motor_torque and load_torque, as equations.derivative takes them); `absolute_tolerance`
    is per entry of the state (its units), `relative_tolerance` a number. `stages`: a
    3 × size work array. `rejected`: whether the step before this one (of this h or longer)
    was rejected. Returns (error norm, Newton iterations); the norm is inf where Newton did
    not converge."""
    size = state.shape[0]
    # Newton goes on to rounding (scipy's floor in the error's scales), not to scipy's
    # √tolerance: only the collocation solution itself keeps a linear invariant, and stages
    # short of it let the angular momentum drift and the contact switches move over a run.
    newton_tolerance = 10 * 2.220446049250313e-16 / relative_tolerance
    scale = absolute_tolerance + np.abs(state) * relative_tolerance
    increments = np.zeros((3, size))  # Z: the stages' states minus `state`
    transformed = np.zeros((3, size))  # W = TI·Z
    real_rhs = np.empty(size)
    complex_rhs = np.empty(size, dtype=np.complex128)
    previous_norm = -1.0
    iterations = 0
    for iterations in range(1, NEWTON_MAXITER + 1):
        norm = _newton_correction(system, segment, state, h, factors, scale, increments,
                                  transformed, stages, real_rhs, complex_rhs)
        rate_of_convergence = norm / previous_norm if previous_norm > 0.0 else -1.0
        if not norm < math.inf or rate_of_convergence >= 1.0 or (
                rate_of_convergence > 0.0 and rate_of_convergence
                ** (NEWTON_MAXITER - iterations + 1) / (1 - rate_of_convergence) * norm
                > newton_tolerance):
            break
        _apply_correction(real_rhs, complex_rhs, transformed, increments)
        if norm == 0.0 or (rate_of_convergence > 0.0 and rate_of_convergence
                           / (1 - rate_of_convergence) * norm < newton_tolerance):
            error = _error_estimate(state, rate, h, increments, factors, new_state)
            norm = _scaled_norm(error, state, new_state, absolute_tolerance, relative_tolerance)
            if rejected and norm > 1.0:
                _second_estimate(system, segment, state, h, increments, factors, stages, error)
                norm = _scaled_norm(error, state, new_state, absolute_tolerance,
                                    relative_tolerance)
            return norm, iterations
        previous_norm = norm
    return math.inf, iterations


@njit(cache=True, error_model="numpy", inline="always")
def _newton_correction(system, segment, state, h, factors, scale, increments, transformed,
                       stages, real_rhs, complex_rhs):
    """A simplified Newton iteration's correction of W (`transformed`) from the stages'
    derivatives at `state` + `increments` (into `stages`): its real block into `real_rhs`,
    its complex block into `complex_rhs`. Returns the correction's scaled RMS norm, inf where
    a derivative is not finite."""
    size = state.shape[0]
    for i in range(3):
        derivative(system, segment.points, segment.point_count, segment.loaded,
                   segment.motor_torque, segment.load_torque, state + increments[i], stages[i])
    for j in range(size):
        real_rhs[j] = (_TI_REAL[0] * stages[0, j] + _TI_REAL[1] * stages[1, j]
                       + _TI_REAL[2] * stages[2, j]) - MU_REAL / h * transformed[0, j]
        complex_rhs[j] = (_TI_COMPLEX[0] * stages[0, j] + _TI_COMPLEX[1] * stages[1, j]
                          + _TI_COMPLEX[2] * stages[2, j]) - MU_COMPLEX / h * (
            transformed[1, j] + 1j * transformed[2, j])
    if not np.all(np.isfinite(real_rhs)):
        return math.inf
    lu_solve(factors.real, factors.real_pivots, real_rhs)
    lu_solve(factors.complex, factors.complex_pivots, complex_rhs)
    norm = 0.0
    for j in range(size):
        norm += ((real_rhs[j] / scale[j]) ** 2 + (complex_rhs[j].real / scale[j]) ** 2
                 + (complex_rhs[j].imag / scale[j]) ** 2)
    return math.sqrt(norm / (3 * size))


@njit(cache=True, error_model="numpy", inline="always")
def _apply_correction(real_rhs, complex_rhs, transformed, increments):
    """W += the correction (_newton_correction's), and the increments Z = T·W."""
    size = transformed.shape[1]
    for j in range(size):
        transformed[0, j] += real_rhs[j]
        transformed[1, j] += complex_rhs[j].real
        transformed[2, j] += complex_rhs[j].imag
    for i in range(3):
        for j in range(size):
            increments[i, j] = (_T[i, 0] * transformed[0, j] + _T[i, 1] * transformed[1, j]
                                + _T[i, 2] * transformed[2, j])


@njit(cache=True, error_model="numpy", inline="always")
def _error_estimate(state, rate, h, increments, factors, new_state):
    """The converged step's result into `new_state`, and its error estimate (a new array):
    scipy's, E·Z/h + rate filtered through the real factors."""
    size = state.shape[0]
    error = np.empty(size)
    for j in range(size):
        new_state[j] = state[j] + increments[2, j]
        error[j] = rate[j] + (_E[0] * increments[0, j] + _E[1] * increments[1, j]
                              + _E[2] * increments[2, j]) / h
    lu_solve(factors.real, factors.real_pivots, error)
    return error


@njit(cache=True, error_model="numpy", inline="always")
def _second_estimate(system, segment, state, h, increments, factors, stages, error):
    """In place: `error` estimated again with the derivative at `state` + `error` in place of
    the step's starting rate (Hairer & Wanner's estimate after a rejected step, as scipy's):
    the first one overstates a stiff component's error, and a step retried on it alone may be
    rejected again and again. `stages`' first two rows are scratch."""
    size = state.shape[0]
    for j in range(size):
        stages[0, j] = state[j] + error[j]
    derivative(system, segment.points, segment.point_count, segment.loaded,
               segment.motor_torque, segment.load_torque, stages[0], stages[1])
    for j in range(size):
        error[j] = stages[1, j] + (_E[0] * increments[0, j] + _E[1] * increments[1, j]
                                   + _E[2] * increments[2, j]) / h
    lu_solve(factors.real, factors.real_pivots, error)


@njit(cache=True, error_model="numpy", inline="always")
def _scaled_norm(error, state, new_state, absolute_tolerance, relative_tolerance):
    """The error's RMS norm, entry j scaled by absolute_tolerance_j + relative_tolerance ·
    max(|state_j|, |new_state_j|)."""
    size = state.shape[0]
    norm = 0.0
    for j in range(size):
        scale_j = absolute_tolerance[j] + relative_tolerance * max(abs(state[j]),
                                                                   abs(new_state[j]))
        norm += (error[j] / scale_j) ** 2
    return math.sqrt(norm / size)


@njit(cache=True, error_model="numpy")
def step_factor(error_norm, iterations, rejected, prediction):
    """By how much to scale h after a step with this error norm and Newton iterations, times
    the `prediction` (`predicted_factor`'s, at most 1), as scipy's Radau; at most 1 after a
    rejected step."""
    safety = SAFETY * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + iterations)
    if error_norm > 1.0:
        return max(MIN_FACTOR, safety * prediction * error_norm ** -0.25)
    factor = MAX_FACTOR if error_norm == 0.0 else min(MAX_FACTOR, safety * prediction
                                                      * error_norm ** -0.25)
    return min(1.0, factor) if rejected else factor


@njit(cache=True, error_model="numpy")
def predicted_factor(h, error_norm, previous_h, previous_error_norm):
    """Gustafsson's predictive factor of a step of h (s) with this error norm after an
    accepted one of previous_h (0: none) with previous_error_norm, as scipy's Radau takes it:
    h/previous_h·(previous_error_norm/error_norm)^¼, never above 1. Where the error grew
    faster than the step, it holds the next step back further than the error alone says: the
    error estimate of a step too long for a stiff component falls short of its true error."""
    if previous_h <= 0.0 or not 0.0 < error_norm < math.inf:
        return 1.0
    return min(1.0, h / previous_h * (previous_error_norm / error_norm) ** 0.25)
