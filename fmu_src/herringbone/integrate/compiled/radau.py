"""Radau IIA of order 5: the implicit, L-stable Runge-Kutta method of Hairer and Wanner.

For stiff scenes (very stiff bearings on light bodies): its step size is set by accuracy alone,
and modes far above what the step resolves are damped, not amplified (L-stability). The
constants are scipy's (`solve_ivp(method="Radau")`); the algorithm follows scipy's, which
follows Hairer & Wanner's RADAU5: the collocation system is solved by simplified Newton
iterations on its real and complex blocks.

Contract of `step`: from `state`, whose derivative is `rate`, with `jacobian` the derivative's
Jacobian and `factors` the LU factors of (MU_REAL/h·I − J) and (MU_COMPLEX/h·I − J) for this h
(`factorize`), take one step of size h with the segment fixed. Write the result to `new_state`
and return (error norm, Newton iterations); the error norm is inf if Newton did not converge
(then retry with a fresh Jacobian or a smaller h). Within a segment the equations are linear in
every entry but the pinion angle, which only moves the contact points slowly, so Newton
converges in one or two iterations on a Jacobian taken at the segment's start.
"""
from __future__ import annotations

import math

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

from .equations import derivative

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
_TI_REAL, _TI_COMPLEX, _T, _E = (np.ascontiguousarray(a) for a in (TI_REAL, TI_COMPLEX, T, E))


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def jacobian_of(system, points, count, loaded, motor_torque, load_torque, state, rate,
                scale, jacobian, trial, column):
    """The Jacobian ∂(derivative)/∂(state) of the segment at `state` (whose derivative is
    `rate`) into `jacobian`, by forward differences of size 1e-7·max(|state_k|, scale_k) per
    column k (`scale`: the state's typical magnitude per entry, in its units); exact but for
    rounding in every entry the equations are linear in. Work arrays: `trial` and `column`,
    one state each."""
    size = state.shape[0]
    for k in range(size):
        trial[:] = state
        delta = 1e-7 * max(abs(state[k]), scale[k])
        trial[k] += delta
        derivative(system, points, count, loaded, motor_torque, load_torque, trial, column)
        for i in range(size):
            jacobian[i, k] = (column[i] - rate[i]) / delta


@njit(cache=True, error_model="numpy")
def factorize(jacobian, h, real, real_pivots, complex_, complex_pivots):
    """The LU factors `step` takes for step size h (s): (MU_REAL/h·I − J) into `real` and
    `real_pivots`, (MU_COMPLEX/h·I − J) into `complex_` (complex128) and `complex_pivots`,
    each as lu_factor leaves them. `jacobian` is not changed."""
    size = jacobian.shape[0]
    for i in range(size):
        for k in range(size):
            real[i, k] = -jacobian[i, k]
            complex_[i, k] = -jacobian[i, k]
        real[i, i] += MU_REAL / h
        complex_[i, i] += MU_COMPLEX / h
    lu_factor(real, real_pivots)
    lu_factor(complex_, complex_pivots)


@njit(cache=True, error_model="numpy")
def step(system, points, count, loaded, motor_torque, load_torque, state, rate, h,
         absolute_tolerance, relative_tolerance, real, real_pivots, complex_, complex_pivots,
         stages, new_state):
    """One Radau IIA step of size h (s) from `state`, whose derivative is `rate`, with the
    factors `factorize` made for this h: see the module's docstring for the contract. The
    segment is (system, points, count, loaded, motor_torque, load_torque) as
    equations.derivative takes it; `absolute_tolerance` is per entry of the state (its units),
    `relative_tolerance` a number. `stages`: a 3 × size work array. Returns (error norm,
    Newton iterations); the norm is inf where Newton did not converge."""
    size = state.shape[0]
    newton_tolerance = max(10 * 2.220446049250313e-16 / relative_tolerance,
                           min(0.03, math.sqrt(relative_tolerance)))
    scale = absolute_tolerance + np.abs(state) * relative_tolerance
    increments = np.zeros((3, size))  # Z: the stages' states minus `state`
    transformed = np.zeros((3, size))  # W = TI·Z
    real_rhs = np.empty(size)
    complex_rhs = np.empty(size, dtype=np.complex128)
    previous_norm = -1.0
    converged = False
    iterations = 0
    for iterations in range(1, NEWTON_MAXITER + 1):
        for i in range(3):
            derivative(system, points, count, loaded, motor_torque, load_torque,
                       state + increments[i], stages[i])
        for j in range(size):
            real_rhs[j] = (_TI_REAL[0] * stages[0, j] + _TI_REAL[1] * stages[1, j]
                           + _TI_REAL[2] * stages[2, j]) - MU_REAL / h * transformed[0, j]
            complex_rhs[j] = (_TI_COMPLEX[0] * stages[0, j] + _TI_COMPLEX[1] * stages[1, j]
                              + _TI_COMPLEX[2] * stages[2, j]) - MU_COMPLEX / h * (
                transformed[1, j] + 1j * transformed[2, j])
        if not np.all(np.isfinite(real_rhs)):
            break
        lu_solve(real, real_pivots, real_rhs)
        lu_solve(complex_, complex_pivots, complex_rhs)
        norm = 0.0
        for j in range(size):
            norm += ((real_rhs[j] / scale[j]) ** 2 + (complex_rhs[j].real / scale[j]) ** 2
                     + (complex_rhs[j].imag / scale[j]) ** 2)
        norm = math.sqrt(norm / (3 * size))
        rate_of_convergence = norm / previous_norm if previous_norm > 0.0 else -1.0
        if rate_of_convergence >= 1.0 or (rate_of_convergence > 0.0 and rate_of_convergence
                                          ** (NEWTON_MAXITER - iterations + 1)
                                          / (1 - rate_of_convergence) * norm
                                          > newton_tolerance):
            break
        for j in range(size):
            transformed[0, j] += real_rhs[j]
            transformed[1, j] += complex_rhs[j].real
            transformed[2, j] += complex_rhs[j].imag
        for i in range(3):
            for j in range(size):
                increments[i, j] = (_T[i, 0] * transformed[0, j] + _T[i, 1] * transformed[1, j]
                                    + _T[i, 2] * transformed[2, j])
        if norm == 0.0 or (rate_of_convergence > 0.0 and rate_of_convergence
                           / (1 - rate_of_convergence) * norm < newton_tolerance):
            converged = True
            break
        previous_norm = norm
    if not converged:
        return math.inf, iterations
    error = np.empty(size)
    for j in range(size):
        new_state[j] = state[j] + increments[2, j]
        error[j] = rate[j] + (_E[0] * increments[0, j] + _E[1] * increments[1, j]
                              + _E[2] * increments[2, j]) / h
    lu_solve(real, real_pivots, error)
    norm = 0.0
    for j in range(size):
        scale_j = absolute_tolerance[j] + relative_tolerance * max(abs(state[j]),
                                                                   abs(new_state[j]))
        norm += (error[j] / scale_j) ** 2
    return math.sqrt(norm / size), iterations


@njit(cache=True, error_model="numpy")
def step_factor(error_norm, iterations, rejected):
    """By how much to scale h after a step with this error norm and Newton iterations (scipy's
    Radau controller without its two-step prediction); at most 1 after a rejected step."""
    safety = SAFETY * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + iterations)
    if error_norm > 1.0:
        return max(MIN_FACTOR, safety * error_norm ** -0.25)
    factor = MAX_FACTOR if error_norm == 0.0 else min(MAX_FACTOR, safety * error_norm ** -0.25)
    return min(1.0, factor) if rejected else factor
