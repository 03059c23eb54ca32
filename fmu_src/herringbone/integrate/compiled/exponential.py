"""The exponential method: a segment whose equations are linear and time-invariant, propagated
exactly by its modal solution.

Between two events the equations (equations.py) are linear in every coordinate but the pinion
angle, which moves the contact points: a point's stiffness, lever arm and lead error follow the
axial travel. Where none of that motion reaches the forces, the segment is x' = A·x + B·u with A
and B constant and the inputs u = (motor torque, load torque, 1) held, and its solution at any
time is exact. That holds for a contact set (and its loaded points) when (`exact_condition`):
- the loaded points' stiffness and lead error do not change along the face (no edge ramp, no
  lead error slope), so only the lever arms move;
- a lever arm multiplies only the tilt: Σ c·ζ, its slope Σ c·dζ, and Σ c·ζ·e vanish over the
  loaded points (the two halves mirror each other), and the tilt's motion is driven by nothing
  that acts on the state outside it (its observability rows annihilate B);
- and at the segment's start the state lies where the tilt stays zero (`tilt_free`): then it
  stays there, the lever arms drop out, and the frozen system is the true one.
The reference scene and the other symmetric scenes meet it; a segment that does not (a staggered
mesh, a lead error, edge ramps, half a train separated) is stepped by DOP853 in the same loop
(walk.py), with DOP853's step bound and error control.

Modal form (`modal_form`, once per contact set and loaded variant, cached: the mesh repeats). The
augmented matrix Â = [[A, B], [0, 0]] acting on X = [x; u] is split by a sorted real Schur form
and a Sylvester equation into its slow block (eigenvalues near zero: the pinion angle and speed
of the rigid rotation, the held inputs; nilpotent, a Jordan chain) and its fast block (the
vibration modes, diagonalized): X(t) = R·diag(exp(T_slow·t), e^{Λt})·L·X(0). The slow block is
a polynomial in t, summed as its series. A step evaluates that at one t (`propagate`), O(N²).

Error control. Nothing is approximated within a segment, so there is no error to estimate; the
steps serve the events only. A step is `certified` when, over all of it, the pinion speed keeps
its sign (each phase event function is monotone, so the step's ends show whether it crossed)
and, where contact can be lost, every point's approach keeps its sign: bounds from the modal
coefficients (the fast modes' sum of magnitudes, the slow polynomial's terms). An uncertified
step longer than DOP853's step bound is rejected (walk.py shortens it); at that bound the loop's
own checks for a step's ends and for grazing (a cubic through values and slopes) hold, as for
DOP853.

Units: time in s; the state as equations.py lays it out; torques in N·m.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import scipy.linalg
from numba import njit

from .counting import COUNTED
from .equations import (
    LEAD_ERROR0,
    LEAD_ERROR_SLOPE,
    LEVER_ARM0,
    LEVER_ARM_SLOPE,
    STIFFNESS0,
    STIFFNESS_SLOPE,
    System,
)

INPUTS = 3  # u = (motor torque, load torque, 1)
# An eigenvalue of Â below this fraction of the largest belongs to the slow block
SLOW_FRACTION = 1e-7
# Relative size below which a sum that the exact condition wants zero counts as zero (rounding)
ZERO = 1e-11
# Loaded variants of a contact set that the tables hold: every point loaded, none loaded (a
# symmetric train with no lead error loads or unloads all its points at once)
ALL_LOADED, NONE_LOADED = 0, 1
VARIANTS = 2
# The tilt a segment may start with, in units of the state scales times the step tolerance
TILT_FRACTION = 1e-3
# The slow block's series stops where a term falls below this fraction of the sum
SERIES_FLOOR = 1e-18
MAX_SERIES_TERMS = 40


class ExactTables(NamedTuple):
    """Modal forms of every contact set of the mesh period in each loaded variant, indexed
    [interval, variant]; M = N + INPUTS, N the state's size, S the widest slow block, C the
    most tilt rows. An entry whose `valid` is 0 is not exact (walk.py steps it by DOP853)."""

    valid: np.ndarray  # (I, V) int: 1 where the set and variant meet exact_condition
    right: np.ndarray  # (I, V, N, M) complex: R's rows of the state
    left: np.ndarray  # (I, V, M, M) complex: L
    rates: np.ndarray  # (I, V, M) complex: Λ (s⁻¹) in the fast places, 0 in the slow ones
    slow: np.ndarray  # (I, V, S, S) complex: the slow block T_slow (s⁻¹)
    slow_count: np.ndarray  # (I, V) int: its size
    tilt_rows: np.ndarray  # (I, V, C, N): rows whose product with the state must vanish
    tilt_count: np.ndarray  # (I, V) int
    tilt_bound: float  # how far from zero those products may be at a segment's start
    approach: np.ndarray  # (I, V, M) complex: (g_base + η·g_base on ẏ)·R, a point's approach
    pinion_rate: np.ndarray  # (I, V, M) complex: the pinion speed's row of R
    modal: np.ndarray  # (M,) complex: scratch for L·X
    augmented: np.ndarray  # (M,) float: scratch for X = [state; u]
    series: np.ndarray  # (2, S) complex: scratch for the slow block's series


# --- the tables (once per stepper, numpy) ------------------------------------------------------

def linear_system(system: System, points: np.ndarray, count: int,
                  loaded: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A (N×N, s⁻¹ and s⁻²) and B (N×INPUTS) of x' = A·x + B·u for the first `count` points of
    the table `points` with `loaded` (1.0/0.0 a point), each point's stiffness, lever arm and
    lead error frozen where the set begins (zero axial travel): equations.derivative's
    equations, which they equal wherever exact_condition holds."""
    n = system.mass.shape[0]
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    for row, column, elastic, damping in zip(system.coupling_row, system.coupling_column,
                                             system.elastic_acceleration,
                                             system.damping_acceleration):
        a[n + row, column] += elastic
        a[n + row, n + column] += damping
    stiffness = points[STIFFNESS0, :count] * loaded[:count]
    lever_arm, lead_error = points[LEVER_ARM0, :count], points[LEAD_ERROR0, :count]
    sums = [stiffness.sum(), (stiffness * lever_arm).sum(), (stiffness * lever_arm ** 2).sum()]
    base, tilt = system.contact_row_base_relative, system.contact_row_tilt_relative
    push_base, push_tilt = system.contact_base_acceleration, system.contact_tilt_acceleration
    contact = (sums[0] * np.outer(push_base, base) + sums[1] * np.outer(push_base, tilt)
               + sums[1] * np.outer(push_tilt, base) + sums[2] * np.outer(push_tilt, tilt))
    a[n:, :n] -= contact
    a[n:, n:] -= system.mesh_damping_factor * contact
    b = np.zeros((2 * n, INPUTS))
    b[n:, 0] = system.motor_acceleration
    b[n:, 1] = -system.load_acceleration
    b[n:, 2] = (-(stiffness * lead_error).sum() * push_base
                - (stiffness * lever_arm * lead_error).sum() * push_tilt)
    return a, b


def tilt_rows(system: System, a: np.ndarray) -> np.ndarray:
    """Orthonormal rows spanning the tilt's observability space of A: the state lies where
    the tilt stays zero (absent forcing) exactly when their products with it vanish."""
    n = system.mass.shape[0]
    tilt = system.contact_row_tilt_relative
    if not tilt.any():
        return np.zeros((0, 2 * n))
    rows = [np.concatenate([tilt, 0.0 * tilt]), np.concatenate([0.0 * tilt, tilt])]
    for _ in range(2 * n):
        rows.append(rows[-2] @ a)
    stacked = np.array(rows)
    stacked /= np.abs(stacked).max(axis=1, keepdims=True)
    _, values, vectors = np.linalg.svd(stacked, full_matrices=False)
    return vectors[:int((values > 1e-9 * values[0]).sum())]


def exact_condition(system: System, points: np.ndarray, count: int, loaded: np.ndarray,
                    b: np.ndarray, rows: np.ndarray) -> bool:
    """Whether the set's loaded points reach the forces only through the tilt, and nothing
    drives the tilt (the module's docstring): the frozen linear system is then exact where
    the tilt starts at zero."""
    on = loaded[:count] != 0.0
    stiffness = points[STIFFNESS0, :count][on]
    if not on.any() or not system.contact_row_tilt_relative.any():
        lever_arm = lever_slope = np.zeros(int(on.sum()))
    else:
        lever_arm, lever_slope = points[LEVER_ARM0, :count][on], points[LEVER_ARM_SLOPE, :count][on]
    lead_error = points[LEAD_ERROR0, :count][on]
    if np.any(points[STIFFNESS_SLOPE, :count][on] != 0.0) or np.any(
            points[LEAD_ERROR_SLOPE, :count][on] != 0.0):
        return False
    scale = max(stiffness.sum(), 1e-300)
    arm = max(np.abs(lever_arm).max(initial=0.0), 1e-300)
    slope = max(np.abs(lever_slope).max(initial=0.0), 1e-300)
    if (abs((stiffness * lever_arm).sum()) > ZERO * scale * arm
            or abs((stiffness * lever_slope).sum()) > ZERO * scale * slope
            or abs((stiffness * lever_arm * lead_error).sum())
            > ZERO * scale * arm * max(np.abs(lead_error).max(initial=0.0), 1e-300)):
        return False
    driven = np.abs(rows @ b) if len(rows) else np.zeros(1)
    return bool(np.all(driven <= ZERO * np.abs(b).max(axis=0)))


def modal_form(a: np.ndarray, b: np.ndarray, scales: np.ndarray):
    """The split of Â = [[A, B], [0, 0]] (module docstring): (R, L, Λ, T_slow) with
    Â = R·diag(T_slow, diag(Λ))·L, L = R⁻¹, the slow block first; Λ has zeros in its place.
    It is made on Â measured in `scales` (one an entry of X: the state's, then the inputs'),
    D⁻¹·Â·D with D = diag(scales): the pinion's speed and the torques are then no longer
    millions of times a deflection, and R's condition falls by as much (rounding in R·z
    scales with it)."""
    size = a.shape[0] + b.shape[1]
    augmented = np.zeros((size, size))
    augmented[:a.shape[0], :a.shape[0]] = a
    augmented[:a.shape[0], a.shape[0]:] = b
    augmented = augmented * scales[None, :] / scales[:, None]
    threshold = SLOW_FRACTION * np.abs(np.linalg.eigvals(augmented)).max()
    form, unitary, slow = scipy.linalg.schur(
        augmented, output="real", sort=lambda re, im: math.hypot(re, im) < threshold)
    slow_block, coupling, fast_block = form[:slow, :slow], form[:slow, slow:], form[slow:, slow:]
    # T_slow·X − X·T_fast = −T_coupling: the change of basis that decouples the two blocks
    decoupling = scipy.linalg.solve_sylvester(slow_block, -fast_block, -coupling)
    rates, vectors = np.linalg.eig(fast_block)
    right = np.zeros((size, size), dtype=complex)
    right[:slow, :slow] = np.eye(slow)
    right[:slow, slow:] = decoupling @ vectors
    right[slow:, slow:] = vectors
    right = unitary @ right
    left = np.linalg.inv(right) / scales[None, :]
    right = right * scales[:, None]
    all_rates = np.zeros(size, dtype=complex)
    all_rates[slow:] = rates
    return right, left, all_rates, slow_block.astype(complex)


def exact_sets(system: System, period_table) -> np.ndarray:
    """Per contact set of the mesh period (mesh.period_table's lengths, counts, tables) and
    loaded variant, 1 where it meets exact_condition, else 0: shape (intervals, VARIANTS)."""
    lengths, counts, tables = period_table
    valid = np.zeros((len(lengths), VARIANTS), dtype=np.int64)
    for interval in range(len(lengths)):
        count = int(counts[interval])
        for variant in range(VARIANTS):
            loaded = np.full(count, 1.0 if variant == ALL_LOADED else 0.0)
            a, b = linear_system(system, tables[interval], count, loaded)
            valid[interval, variant] = exact_condition(system, tables[interval], count, loaded,
                                                       b, tilt_rows(system, a))
    return valid


def build_tables(system: System, period_table, state_scales: np.ndarray,
                 torque_scales: tuple[float, float], step_tolerance: float) -> ExactTables:
    """The ExactTables of a mesh period (mesh.period_table's lengths, counts, tables) for the
    stepper's state scales (GearTrainModel.state_scales), the torques' scales (N·m: motor,
    load) and the step tolerance."""
    scales = np.concatenate([state_scales, torque_scales, [1.0]])
    # The pinion angle runs over a whole contact interval, hundreds of its error scale, and the
    # rounding of the modal round trip grows with the largest scaled entry: it is measured by
    # the longest interval instead.
    scales[system.pinion] = max(scales[system.pinion], float(np.max(period_table[0])))
    lengths, counts, tables = period_table
    intervals, size = len(lengths), 2 * system.mass.shape[0]
    width = size + INPUTS
    forms, valid = {}, np.zeros((intervals, VARIANTS), dtype=np.int64)
    rows_of = {}
    for interval in range(intervals):
        count = int(counts[interval])
        for variant in range(VARIANTS):
            loaded = np.full(count, 1.0 if variant == ALL_LOADED else 0.0)
            a, b = linear_system(system, tables[interval], count, loaded)
            rows = tilt_rows(system, a)
            if exact_condition(system, tables[interval], count, loaded, b, rows):
                forms[interval, variant] = modal_form(a, b, scales)
                rows_of[interval, variant] = rows
                valid[interval, variant] = 1
    slow_width = max([len(form[3]) for form in forms.values()], default=1)
    tilt_width = max([len(rows) for rows in rows_of.values()], default=1)
    right = np.zeros((intervals, VARIANTS, size, width), dtype=complex)
    left = np.zeros((intervals, VARIANTS, width, width), dtype=complex)
    rates = np.zeros((intervals, VARIANTS, width), dtype=complex)
    slow = np.zeros((intervals, VARIANTS, slow_width, slow_width), dtype=complex)
    slow_count = np.zeros((intervals, VARIANTS), dtype=np.int64)
    tilt = np.zeros((intervals, VARIANTS, max(tilt_width, 1), size))
    tilt_count = np.zeros((intervals, VARIANTS), dtype=np.int64)
    approach = np.zeros((intervals, VARIANTS, width), dtype=complex)
    pinion_rate = np.zeros((intervals, VARIANTS, width), dtype=complex)
    n = system.mass.shape[0]
    base = np.concatenate([system.contact_row_base_relative,
                           system.mesh_damping_factor * system.contact_row_base_relative])
    for (interval, variant), (r, inverse, lam, t_slow) in forms.items():
        right[interval, variant] = r[:size]
        left[interval, variant] = inverse
        rates[interval, variant] = lam
        slow[interval, variant, :len(t_slow), :len(t_slow)] = t_slow
        slow_count[interval, variant] = len(t_slow)
        rows = rows_of[interval, variant]
        # measured in the state's scales: a row's product is then a relative tilt
        scaled = rows * state_scales[None, :]
        norms = np.maximum(np.linalg.norm(scaled, axis=1), 1e-300)
        tilt[interval, variant, :len(rows)] = rows / norms[:, None]
        tilt_count[interval, variant] = len(rows)
        approach[interval, variant] = base @ r[:size]
        pinion_rate[interval, variant] = r[n + system.pinion]
    return ExactTables(valid, right, left, rates, slow, slow_count, tilt, tilt_count,
                       float(TILT_FRACTION * step_tolerance), approach, pinion_rate,
                       np.zeros(width, dtype=complex), np.zeros(width),
                       np.zeros((2, slow_width), dtype=complex))


def pack_tables(tables: ExactTables) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The tables as three flat arrays (complex, float, int) that `unpack_tables` takes apart in
    compiled code: numba types each array of a call's arguments at every call, and the
    fourteen of ExactTables cost the FMU's communication step more than the exact steps it
    takes. The ints open with the sizes (I, V, N, M, S, C)."""
    intervals, variants, size, width = tables.right.shape
    header = [intervals, variants, size, width, tables.slow.shape[2], tables.tilt_rows.shape[2]]
    complexes = np.concatenate([array.ravel() for array in (
        tables.right, tables.left, tables.rates, tables.slow, tables.approach,
        tables.pinion_rate, tables.modal, tables.series)])
    floats = np.concatenate([tables.tilt_rows.ravel(), tables.augmented, [tables.tilt_bound]])
    ints = np.concatenate([header, tables.valid.ravel(), tables.slow_count.ravel(),
                           tables.tilt_count.ravel()]).astype(np.int64)
    return complexes, floats, ints


# --- the kernels ---------------------------------------------------------------------------------

@njit(**COUNTED)
def unpack_tables(complexes, floats, ints):
    """pack_tables' inverse: ExactTables whose arrays are views of the three buffers."""
    intervals, variants, size, width, slow, tilt = ints[0], ints[1], ints[2], ints[3], ints[4], \
        ints[5]
    pairs = intervals * variants
    at = 0
    right = complexes[at:at + pairs * size * width].reshape((intervals, variants, size, width))
    at += pairs * size * width
    left = complexes[at:at + pairs * width * width].reshape((intervals, variants, width, width))
    at += pairs * width * width
    rates = complexes[at:at + pairs * width].reshape((intervals, variants, width))
    at += pairs * width
    slow_block = complexes[at:at + pairs * slow * slow].reshape((intervals, variants, slow,
                                                                  slow))
    at += pairs * slow * slow
    approach = complexes[at:at + pairs * width].reshape((intervals, variants, width))
    at += pairs * width
    pinion_rate = complexes[at:at + pairs * width].reshape((intervals, variants, width))
    at += pairs * width
    modal = complexes[at:at + width]
    series = complexes[at + width:at + width + 2 * slow].reshape((2, slow))
    rows = floats[:pairs * tilt * size].reshape((intervals, variants, tilt, size))
    augmented = floats[pairs * tilt * size:pairs * tilt * size + width]
    valid = ints[6:6 + pairs].reshape((intervals, variants))
    slow_count = ints[6 + pairs:6 + 2 * pairs].reshape((intervals, variants))
    tilt_count = ints[6 + 2 * pairs:6 + 3 * pairs].reshape((intervals, variants))
    return ExactTables(valid, right, left, rates, slow_block, slow_count, rows, tilt_count,
                       floats[floats.shape[0] - 1], approach, pinion_rate, modal, augmented,
                       series)


@njit(cache=True, error_model="numpy")
def variant_of(tables, interval, count, loaded, state):
    """The index interval·VARIANTS + variant of the segment's exact form, or −1 where it has
    none: its loaded points are neither all nor none, the set's variant is not exact, or the
    state does not start where the tilt stays zero."""
    loaded_points = 0
    for i in range(count):
        if loaded[i] != 0.0:
            loaded_points += 1
    if loaded_points == count:
        variant = ALL_LOADED
    elif loaded_points == 0:
        variant = NONE_LOADED
    else:
        return -1
    if tables.valid[interval, variant] == 0:
        return -1
    rows = tables.tilt_rows[interval, variant]
    for k in range(tables.tilt_count[interval, variant]):
        product = 0.0
        for j in range(state.shape[0]):
            product += rows[k, j] * state[j]
        if abs(product) > tables.tilt_bound:
            return -1
    return interval * VARIANTS + variant


@njit(cache=True, error_model="numpy", inline="always")
def _to_modal(tables, interval, variant, state, motor_torque, load_torque):
    """L·[state; u] into tables.modal. (Here and below the tables are indexed entry by entry,
    not through views such as left[interval, variant]: a view is a record built at every step,
    and where this is compiled with numba's reference counts, two atomic counts.)"""
    size = state.shape[0]
    augmented, modal, left = tables.augmented, tables.modal, tables.left
    for j in range(size):
        augmented[j] = state[j]
    augmented[size] = motor_torque
    augmented[size + 1] = load_torque
    augmented[size + 2] = 1.0
    width = augmented.shape[0]
    for i in range(width):
        total = 0.0j
        for j in range(width):
            total += left[interval, variant, i, j] * augmented[j]
        modal[i] = total


@njit(cache=True, error_model="numpy", inline="always")
def magnitude(z):
    """|z| without hypot's guard against overflow, which these sizes never come near: libm's
    hypot took a tenth of the method's time."""
    return math.sqrt(z.real * z.real + z.imag * z.imag)


@njit(cache=True, error_model="numpy", inline="always")
def _momentum(system, state):
    """Σ m·r·q̇ and Σ m·r·q over the coordinates (q from the contact set's start): the train's
    momentum and its integral along the rigid rotation r, which only the external torques
    change (every element's row is orthogonal to r)."""
    n = system.mass.shape[0]
    pinion = system.pinion
    momentum = moment = 0.0
    for j in range(n):
        weight = system.mass[j] * system.rigid_rotation[j]
        if j == pinion:
            momentum += weight * state[n + j]
            moment += weight * state[j]
        else:
            momentum += weight * (state[n + j] + system.rigid_rotation[j] * state[n + pinion])
            moment += weight * (state[j] + system.rigid_rotation[j] * state[pinion])
    return momentum, moment


@njit(cache=True, error_model="numpy")
def step(system, tables, exact, state, motor_torque, load_torque, h, contact_loss,
         loaded_variant_sign, out):
    """The exact state after h (s) from `state` in the segment of exact form `exact`
    (variant_of's index) of the train `system` with the torques (N·m) held, into `out`, its
    momentum along the rigid rotation kept exact; returns whether the step is
    certified (module docstring): the pinion speed keeps its sign over it, and where
    `contact_loss`, the points' approach keeps the sign `loaded_variant_sign` (+1 loaded, −1
    unloaded) over it."""
    interval, variant = exact // VARIANTS, exact % VARIANTS
    _to_modal(tables, interval, variant, state, motor_torque, load_torque)
    modal, rates = tables.modal, tables.rates
    slow_count = tables.slow_count[interval, variant]
    # bounds: each function is its slow polynomial plus the fast modes' sum
    speed_row, approach_row = tables.pinion_rate, tables.approach
    speed_swing = approach_swing = 0.0
    for k in range(slow_count, modal.shape[0]):
        size = magnitude(modal[k])
        speed_swing += magnitude(speed_row[interval, variant, k]) * size
        approach_swing += magnitude(approach_row[interval, variant, k]) * size
        modal[k] *= np.exp(rates[interval, variant, k] * h)
    speed0, approach0, speed_drift, approach_drift = _slow_series(
        tables, interval, variant, modal, h)
    momentum, moment = _momentum(system, state)
    _from_modal(tables, interval, variant, out)
    # The rounding of the modal round trip, about 1e-13 of Â, leaves the rigid rotation a bias
    # where the torques' large accelerations cancel (9e-9 rad/s² on the reference scene: the
    # switches drift, 2e-8 of the force scale after 0.3 s). The momentum along r changes by
    # the net torque alone, exactly: the step's end is put back on it, and on its integral.
    net = motor_torque - load_torque * system.rigid_rotation[system.wheel]
    inertia = 0.0
    for j in range(system.mass.shape[0]):
        inertia += system.mass[j] * system.rigid_rotation[j] ** 2
    momentum_after, moment_after = _momentum(system, out)
    n = system.mass.shape[0]
    out[n + system.pinion] += (momentum + net * h - momentum_after) / inertia
    out[system.pinion] += (moment + momentum * h + 0.5 * net * h * h - moment_after) / inertia
    certified = abs(speed0) > speed_drift + speed_swing
    if contact_loss:
        certified = certified and (loaded_variant_sign * approach0
                                   > approach_drift + approach_swing)
    return certified


@njit(cache=True, error_model="numpy", inline="always")
def _slow_series(tables, interval, variant, modal, h):
    """Propagate the slow block of `modal` over h by its series (exp(T_slow·h) applied term by
    term; the block is nilpotent but for rounding, so the series ends after a few terms).
    Returns the slow parts of the pinion speed and of the approach at the step's start, and
    bounds of how far each moves over the step (the sum of its terms' magnitudes)."""
    slow_count = tables.slow_count[interval, variant]
    block, series = tables.slow, tables.series
    speed_row, approach_row = tables.pinion_rate, tables.approach
    speed0 = approach0 = 0.0
    largest = 0.0
    for k in range(slow_count):
        speed0 += (speed_row[interval, variant, k] * modal[k]).real
        approach0 += (approach_row[interval, variant, k] * modal[k]).real
        series[0, k] = modal[k]
        largest = max(largest, magnitude(modal[k]))
    speed_drift = approach_drift = 0.0
    for order in range(1, MAX_SERIES_TERMS):  # series[0]: the term, series[1]: the next
        size = 0.0
        for i in range(slow_count):
            total = 0.0j
            for j in range(slow_count):
                total += block[interval, variant, i, j] * series[0, j]
            series[1, i] = total * (h / order)
        speed_change = approach_change = 0.0j
        for i in range(slow_count):
            following = series[1, i]
            series[0, i] = following
            modal[i] += following
            speed_change += speed_row[interval, variant, i] * following
            approach_change += approach_row[interval, variant, i] * following
            size = max(size, magnitude(following))
        speed_drift += magnitude(speed_change)
        approach_drift += magnitude(approach_change)
        if size <= SERIES_FLOOR * largest:
            break
    return speed0, approach0, speed_drift, approach_drift


@njit(cache=True, error_model="numpy", inline="always")
def _from_modal(tables, interval, variant, out):
    """out = Re(R·modal)."""
    right, modal = tables.right, tables.modal
    for i in range(out.shape[0]):
        total = 0.0
        for k in range(modal.shape[0]):
            entry = right[interval, variant, i, k]
            total += entry.real * modal[k].real - entry.imag * modal[k].imag
        out[i] = total
