"""The exponential method: a segment whose equations are linear and time-invariant, propagated
exactly by its modal solution.

Between two events the equations (model/equations.py) are linear in every coordinate but the pinion
angle, which moves the contact points: a point's stiffness, lever arm and lead error follow the
axial travel. Where none of that motion reaches the forces, the segment is x' = A·x + B·u with A
and B constant and the inputs u = (motor torque, load torque, 1) held, and its solution at any
time is exact. That holds for a contact set (and its loaded points) when (`exact_condition`):
- the loaded points' stiffness and lead error do not change along the face (no edge ramp, no
  lead error slope), so only the lever arms move; and where contact can be lost, no point
  has a lead error (each point's approach is an event function, found on one approach);
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
a polynomial in t, summed as its series. Where nothing elastic acts (the gear pair alone in
flight: two free bodies) Â is nilpotent and the slow block is all of it. A step evaluates that
at one t (`step`), O(N²): the slow block in real arithmetic, one mode of each conjugate pair
(ExactTables says why). The coordinates L·X(0) of a step's start are kept, so the trial steps
of an event's location, which all start there, pay only for e^{Λt} and R (`state_after`: the
state alone, where a step's certificate is not asked for).

Error control. Nothing is approximated within a segment, so there is no error to estimate; the
steps serve the events only. A step is `certified` when, over all of it, its phase events are
sure: the pinion speed keeps its sign (each phase event function is then monotone, so the step's
ends show whether it crossed) or the pinion angle stays inside its contact interval; and, where
contact can be lost, every point's approach keeps its sign (`keeps_sign`): bounds from the modal
coefficients, either the fast modes' sum of magnitudes and the slow polynomial's terms, or the
values at the step's ends less how far the function can bow below their chord (the modes'
curvature; a mode that turns through much of a period, its magnitude); where the approach's sign
is not certified, its rate's sign may be (`approach_monotone`: the approach crosses at most
once, as its ends show). An uncertified step longer than h·|λ|max = 3.5 is rejected (walk.py
shortens it); at that bound (walk's exact floor: DOP853's stability bound, without the
tightening DOP853's own error needs) the loop's own checks for a step's ends and for grazing (a
cubic through values and slopes) see a point's approach cross, as for DOP853. Where the phase
events are not sure (a torsional mode swinging the speed through zero near a switch), those
checks do not see the pinion turn back across an end of its interval and return, and the step is
shortened further (walk.TURN_BACK_FLOOR). The first step after a segment's entry or a call's
start is aimed where the angle's modal solution leaves its interval (`modal_phase_event_ahead`),
and where that cannot be found, where the slow motion carries it out, or no later.

The kernels the loop calls take the train as an ExactTrain (`train`: the few fields of its
System they read), since a call's records are handed over word by word.

Units: time in s; the state as model/equations.py lays it out; torques in N·m.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import scipy.linalg
from numba import njit

from ...arguments import COMPILED_DEFAULT_TOLERANCE
from ...compiling.counting import COUNTED, NUMBERS_ONLY
from ...model.equations import (
    LEAD_ERROR0,
    LEAD_ERROR_SLOPE,
    LEVER_ARM0,
    LEVER_ARM_SLOPE,
    STIFFNESS0,
    STIFFNESS_SLOPE,
    System,
    contact_motion,
    point_approach,
)
from .buffers import cube_view as _cube
from .buffers import matrix_view as _matrix

INPUTS = 3  # u = (motor torque, load torque, 1)
# An eigenvalue of Â below this fraction of the largest belongs to the slow block
SLOW_FRACTION = 1e-7
# A modal form's own error, over the force scale, grows as the square of its worst fast
# eigenvalue's condition number κ (rounding in the eigenvectors, then in R·L): runs of the
# reference scene with its mesh stiffened (c_point 2.5e8 to 1e12 N/m, κ 53 to 7.3e4) settled at
# 1.7e-16·κ² to 2.7e-16·κ² off scipy's DOP853 at 1e-12 where κ passed 1e3, whatever their own
# tolerance (docs/exponential-integrator.md, "The modal form's rounding").
ROUNDING_PER_CONDITION_SQUARED = 2.7e-16
# A form is taken where that error stays within the run's tolerance (the error a run at that
# tolerance is allowed anyway: DOP853 at 1e-12 lands 2e-12 off), and where κ stays within
# this, whatever the tolerance. Free bodies (a train without bearings, its points unloaded:
# the pinion alone, the wheel with its load) have zero eigenvalues on chains that rounding
# splits into small ones with nearly parallel eigenvectors (±9.3e-3 s⁻¹ beside 2.2e5 s⁻¹, κ 5e4
# to 5e5 on the regression scenes): their coordinates cancel in R·z, and an exact step moved
# the wheel 1e-4 rad off scipy's expm. The sets of the shipped scenes have κ of 2 to 195, those
# of the regression scenes' trains up to 580, those of the seeded random test scenes 18.5.
CONDITION_CEILING = 1e4
# Relative size below which a sum that the exact condition wants zero counts as zero (rounding)
ZERO = 1e-11
# Loaded variants of a contact set that the tables hold: every point loaded, none loaded (a
# symmetric train with no lead error loads or unloads all its points at once)
ALL_LOADED, NONE_LOADED = 0, 1
VARIANTS = 2
# The tilt a segment may start with, in units of the state scales times the step tolerance,
# and at least TILT_ROUNDING (in the state scales): the modal round trip leaves a relative
# tilt of some 5e-15 in an undamped train, which a bound of 1e-3 of a step tolerance of 3e-12
# (undamped at 1e-10) would refuse, stepping its exact segments by DOP853
TILT_FRACTION = 1e-3
TILT_ROUNDING = 1e-13
# A mode's largest cosine with the tilt rows above which the tilt sees it (unseen_by_tilt)
TILT_SEEN = 1e-6
# The phase event's time from the slow polynomial (modal_phase_event_ahead): Newton's
# iterations, the relative change at which they stop, and the largest swing of the angle by
# the fast modes, as a fraction of the way to go, at which the prediction is made
PREDICTION_ITERATIONS = 8
PREDICTION_PRECISION = 1e-9
PREDICTION_SPREAD = 0.01
# Iterations on the whole modal solution of the pinion angle or an approach
# (_modal_crossing), and the relative change at which they stop. The step is aimed past the
# crossing by the event location's tolerance, some 1e-10 of the time to it
# (walk.first_estimate); the error of a Newton step squares (on the reference scene 3e-2,
# 2e-5, 1e-11 of the time), so the iteration after a change below 1e-10 is good to rounding.
# Halley's error cubes (the angle's): where _cubed_error, its bound, is below
# CROSSING_ROUNDING of the time, the iterate is the root to rounding without another
# evaluation (two in all on the shipped scenes, against Newton's three)
CROSSING_ITERATIONS = 30
CROSSING_PRECISION = 1e-10
CROSSING_ROUNDING = 1e-20
# What modal_phase_event_ahead's time is: where the modal solution crosses the interval's end
# (CROSSING), near it (NEAR: the slow part's time with the fast swing no more than
# PREDICTION_SPREAD of the way), or only a time by which it has surely crossed (BOUND)
BOUND, NEAR, CROSSING = 0, 1, 2
NO_AIM = -1  # (walk: no time predicted)
# The slow block's series stops where a term falls below this fraction of the sum
SERIES_FLOOR = 1e-18
MAX_SERIES_TERMS = 40
# tables.start's entry that holds the time of aimed_fast (s; NaN: none since the start was
# prepared)
AIMED_AT = -1


class ExactTables(NamedTuple):
    """Modal forms of every contact set of the mesh period in each loaded variant, indexed by
    the exact form's index interval·VARIANTS + variant (P of them); N the state's size,
    M = N + INPUTS, S the widest slow block, F the most fast modes kept (one of each pair,
    none that the tilt sees: unseen_by_tilt), C the most tilt rows.
    An entry whose `valid` is 0 is not exact (walk.py steps it by DOP853). The system is real,
    so its fast modes come in complex conjugate pairs whose coordinates are conjugates of each
    other: one mode of each pair is kept, its column of R counted twice, and Re(R·z) is the
    same sum at half the products. The slow block and its rows of L and R are real."""

    valid: np.ndarray  # (P,) int: 1 where the set and variant meet exact_condition
    slow_count: np.ndarray  # (P,) int: the slow block's size
    fast_count: np.ndarray  # (P,) int: the fast modes kept
    tilt_count: np.ndarray  # (P,) int
    slow_left: np.ndarray  # (P, S, M): L's rows of the slow block
    slow_right: np.ndarray  # (P, N, S): R's columns of the slow block, the state's rows
    slow: np.ndarray  # (P, S, S): the slow block T_slow (s⁻¹)
    # (P, S, S + 1) int: per row of T_slow, how many of its entries are not zero, then their
    # columns, rising: the block is sparse (3 to 14 of 25 to 49 entries on the shipped
    # scenes), and its series is in every exact step
    slow_columns: np.ndarray
    # (P, S, S): the pinion angle's and a point's approach's rows of the slow columns times
    # T_slow^n/n!, n < S: their slow part's coefficient of t^n is the n-th row · L_slow·X(0)
    angle_polynomial: np.ndarray
    approach_polynomial: np.ndarray
    fast_left: np.ndarray  # (P, F, M) complex: L's rows of the fast modes kept
    fast_right: np.ndarray  # (P, N, F) complex: their columns of R, twice for a pair
    rates: np.ndarray  # (P, F) complex: their eigenvalues Λ (s⁻¹)
    tilt_rows: np.ndarray  # (P, C, N): rows whose product with the state must vanish
    speed_slow: np.ndarray  # (P, S): the pinion speed's row of the slow columns
    approach_slow: np.ndarray  # (P, S): (g_base + η·g_base on ẏ)·R, a point's approach
    speed_size: np.ndarray  # (P, F): |the pinion speed's row of fast_right|
    approach_size: np.ndarray  # (P, F): |the approach's row of fast_right|
    angle_size: np.ndarray  # (P, F): |the pinion angle's row of fast_right|
    speed_fast: np.ndarray  # (P, F) complex: the pinion speed's row of fast_right
    approach_fast: np.ndarray  # (P, F) complex: the approach's row of fast_right
    tilt_bound: float  # how far from zero the tilt rows' products may be at a segment's start
    inertia: float  # Σ m·r² along the rigid rotation r
    # Scratch. `start`: the augmented X = [state; u] of the last step's start, then the
    # exact form's index + 1 (0: none yet), the momentum and moment (`_momentum`) there, and
    # the time of aimed_fast (AIMED_AT); start_slow, start_fast,
    # start_size: its modal coordinates and the fast ones' magnitudes
    start: np.ndarray  # (M + 4,)
    start_slow: np.ndarray  # (S,)
    start_fast: np.ndarray  # (F,) complex
    start_size: np.ndarray  # (F,)
    modal_slow: np.ndarray  # (S,): the coordinates at the step's end (or the polynomial of
    #                         modal_phase_event_ahead, approach_crossing)
    modal_fast: np.ndarray  # (F,) complex
    grid_fast: np.ndarray  # (F,) complex: e^{λ·t} at a point of inside_on_grid's grid
    aimed_fast: np.ndarray  # (F,) complex: e^{λ·t} where the angle's aim last evaluated
    series: np.ndarray  # (2, S): the slow block's series


class ExactTrain(NamedTuple):
    """What the kernels of exact segments read of a train's System (equations.System: the
    same fields, the same units), handed to them in its place (exact_train). A call hands
    its records over field by field, on the stack where the registers run out: the System
    is 113 words, this a third of it, and the words pushed before the chain's calls were
    most of its own time (docs/exponential-measurements.md, "A call's records")."""

    pinion: int
    wheel: int
    mass: np.ndarray
    rigid_rotation: np.ndarray
    contact_row_base_relative: np.ndarray
    contact_row_tilt_relative: np.ndarray
    axial_travel_per_radian: float
    mesh_damping_factor: float
    contact_loss: bool


@njit(**COUNTED, inline="always")
def exact_train(system):
    """The ExactTrain of a System: views of its arrays, nothing copied."""
    return ExactTrain(system.pinion, system.wheel, system.mass, system.rigid_rotation,
                      system.contact_row_base_relative, system.contact_row_tilt_relative,
                      system.axial_travel_per_radian, system.mesh_damping_factor,
                      system.contact_loss)


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
    the tilt stays zero (absent forcing) exactly when their products with it vanish. A
    coordinate that none of the rows it is spanned by involves gets an exact zero, not the
    SVD's rounding: the pinion angle runs to hundreds of its scale within an interval, so a
    rounding entry of 4e-15 on it would read as a tilt of 1e-12 mid-way, beyond the bound
    (variant_of) at tight tolerances."""
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
    spanning = vectors[:int((values > 1e-9 * values[0]).sum())]
    spanning[:, ~stacked.any(axis=0)] = 0.0
    return spanning


def exact_condition(system: System, points: np.ndarray, count: int, loaded: np.ndarray,
                    b: np.ndarray, rows: np.ndarray) -> bool:
    """Whether the set's loaded points reach the forces only through the tilt, and nothing
    drives the tilt (the module's docstring): the frozen linear system is then exact where
    the tilt starts at zero. Where contact can be lost every point's approach is also an
    event function, and an exact segment finds and certifies its crossings on one approach
    without lead error (_approach): so no point of the set, loaded or not, may have one. A
    flight of tests/regression/found_79a4848a80.toml (a lead error on both halves) went on
    past a landing that way, 0.88 of the force scale off DOP853."""
    if system.contact_loss and (np.any(points[LEAD_ERROR0, :count] != 0.0)
                                or np.any(points[LEAD_ERROR_SLOPE, :count] != 0.0)):
        return False
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


def modal_form(a: np.ndarray, b: np.ndarray, scales: np.ndarray,
               tolerance: float = COMPILED_DEFAULT_TOLERANCE):
    """The split of Â = [[A, B], [0, 0]] (module docstring): (R, L, Λ, T_slow) with
    Â = R·diag(T_slow, diag(Λ))·L, L = R⁻¹, the slow block first; Λ has zeros in its place.
    It is made on Â measured in `scales` (one an entry of X: the state's, then the inputs'),
    D⁻¹·Â·D with D = diag(scales): the pinion's speed and the torques are then no longer
    millions of times a deflection, and R's condition falls by as much (rounding in R·z
    scales with it). A nilpotent Â (every eigenvalue exactly zero: free bodies with nothing
    elastic between them) is its slow block alone, with no fast mode. A fast block too
    ill-conditioned for a run at `tolerance` (condition_limit) raises np.linalg.LinAlgError."""
    size = a.shape[0] + b.shape[1]
    augmented = np.zeros((size, size))
    augmented[:a.shape[0], :a.shape[0]] = a
    augmented[:a.shape[0], a.shape[0]:] = b
    augmented = augmented * scales[None, :] / scales[:, None]
    threshold = SLOW_FRACTION * np.abs(np.linalg.eigvals(augmented)).max()
    form, unitary, slow = scipy.linalg.schur(
        augmented, output="real", sort=lambda re, im: math.hypot(re, im) <= threshold)
    slow_block, coupling, fast_block = form[:slow, :slow], form[:slow, slow:], form[slow:, slow:]
    # T_slow·X − X·T_fast = −T_coupling: the change of basis that decouples the two blocks
    decoupling = scipy.linalg.solve_sylvester(slow_block, -fast_block, -coupling)
    rates, vectors = np.linalg.eig(fast_block)
    _require_conditioned(vectors, tolerance)
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


def condition_limit(tolerance: float) -> float:
    """The largest condition number κ of a fast eigenvalue that a modal form may have in a run
    at `tolerance` (relative to the force scale): its rounding, ROUNDING_PER_CONDITION_SQUARED·κ²,
    within the tolerance, and κ within CONDITION_CEILING.

    Examples
    --------
    >>> [round(condition_limit(tolerance)) for tolerance in (1e-2, 1e-7, 1e-10, 1e-12)]
    [10000, 10000, 609, 61]
    """
    return min(CONDITION_CEILING, math.sqrt(tolerance / ROUNDING_PER_CONDITION_SQUARED))


def _require_conditioned(vectors: np.ndarray, tolerance: float) -> None:
    """Raise np.linalg.LinAlgError where the eigenvectors `vectors` (columns) of the fast
    block leave an eigenvalue's condition number ‖v‖·‖w‖ (w its row of the inverse) above
    condition_limit(tolerance): a defective system that rounding has made diagonalizable,
    or one so ill-conditioned that its modal form's rounding would be seen at that tolerance.
    It is refused as numpy refuses one whose eigenvectors rounding left singular (the inverse
    raises the same error), and build_tables treats both alike."""
    condition = np.linalg.norm(vectors, axis=0) * np.linalg.norm(np.linalg.inv(vectors), axis=1)
    worst, limit = condition.max(initial=0.0), condition_limit(tolerance)
    if worst <= limit:
        return
    if limit == CONDITION_CEILING:
        raise np.linalg.LinAlgError(
            f"a fast eigenvalue's condition number is {worst:.3g}, over {limit:g}: the system "
            "is defective but for rounding")
    raise np.linalg.LinAlgError(
        f"a fast eigenvalue's condition number is {worst:.3g}, over {limit:.3g} at the "
        f"tolerance {tolerance:g}: the modal form's rounding, about "
        f"{ROUNDING_PER_CONDITION_SQUARED * worst**2:.2g} of the force scale, would pass it")


def exact_sets(system: System, period_table) -> np.ndarray:
    """Per contact set of the mesh period (mesh.period_table's lengths, counts, tables) and
    loaded variant, 1 where it meets exact_condition, else 0: shape (intervals, VARIANTS)
    (ExactTables.valid, reshaped)."""
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


def kept_modes(rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Of the fast eigenvalues `rates` of a real matrix (numpy's eig gives conjugate pairs
    as exact conjugates), the places of those kept, one of each pair (the one of positive
    imaginary part) and every real one, and their weights (2 for a pair, 1 for a real one)."""
    upper = np.flatnonzero(rates.imag > 0.0)
    lower = rates[rates.imag < 0.0]
    if len(lower) != len(upper) or not np.all(np.isin(rates[upper].conj(), lower)):
        raise np.linalg.LinAlgError("the fast modes do not come in conjugate pairs")
    kept = np.flatnonzero(rates.imag >= 0.0)
    return kept, np.where(rates[kept].imag > 0.0, 2.0, 1.0)


def unseen_by_tilt(rows: np.ndarray, columns: np.ndarray, scales: np.ndarray) -> np.ndarray:
    """Which of the modes whose state columns of R are `columns` (N×F, complex) the tilt rows
    `rows` (C×N, tilt_rows) do not see. The space where the rows' products vanish is invariant
    (the rows span the tilt's observability space, and nothing drives the tilt), and a
    segment is exact only where the state starts in it (variant_of): there the modes the tilt
    sees have zero coordinates and keep them, so an exact step need not propagate them (two
    of the reference scene's seven pairs: a fifth of a step's products and exponentials).
    Measured in `scales` (the state's first), by the largest cosine of a column with a row:
    a mode the tilt sees comes out at 0.1 to 0.7, one it does not at 1e-15."""
    if len(rows) == 0:
        return np.ones(columns.shape[1], dtype=bool)
    scaled_rows = _unit_rows(rows * scales[None, :rows.shape[1]])
    scaled_columns = _unit_rows((columns / scales[:columns.shape[0], None]).T)
    cosines = np.abs(scaled_rows @ scaled_columns.T)
    return cosines.max(axis=0) <= TILT_SEEN


def _unit_rows(matrix: np.ndarray) -> np.ndarray:
    """`matrix`'s rows each divided by its Euclidean norm (a zero row left zero), taken after
    its largest entry, so that scales of a huge input (a torque of 1e300 N·m) do not overflow
    the squares."""
    largest = np.abs(matrix).max(axis=1, keepdims=True)
    shrunk = matrix / np.where(largest > 0.0, largest, 1.0)
    norms = np.linalg.norm(shrunk, axis=1, keepdims=True)
    return shrunk / np.where(norms > 0.0, norms, 1.0)


def build_tables(system: System, period_table, state_scales: np.ndarray,
                 torque_scales: tuple[float, float], step_tolerance: float, tolerance: float,
                 skip_defective: bool = False) -> ExactTables:
    """The ExactTables of a mesh period (mesh.period_table's lengths, counts, tables) for the
    stepper's state scales (GearTrainModel.state_scales), the torques' scales (N·m: motor,
    load), the step tolerance and the run's `tolerance`, which bounds the modal forms'
    conditioning (condition_limit). A set and variant whose linear system has no modal form
    raises np.linalg.LinAlgError, or with `skip_defective` is left out of the exact ones (its
    segments are stepped by DOP853)."""
    scales = np.concatenate([state_scales, torque_scales, [1.0]])
    # The pinion angle runs over a whole contact interval, hundreds of its error scale, and the
    # rounding of the modal round trip grows with the largest scaled entry: it is measured by
    # the longest interval instead.
    scales[system.pinion] = max(scales[system.pinion], float(np.max(period_table[0])))
    valid, forms, rows_of = _exact_forms(system, period_table, scales, skip_defective,
                                         tolerance)
    size = 2 * system.mass.shape[0]
    width = size + INPUTS
    slow_width = max([len(form[3]) for form in forms.values()], default=1)
    fast_width = max([len(form[4]) for form in forms.values()], default=1)
    tilt_width = max([len(rows) for rows in rows_of.values()] + [1])
    arrays = _empty_arrays(len(valid), size, width, slow_width, fast_width, tilt_width)
    for place, form in forms.items():
        _fill_place(arrays, place, form, rows_of[place], system, state_scales)
    inertia = float(np.sum(system.mass * system.rigid_rotation ** 2))
    return ExactTables(
        valid=valid, **arrays, tilt_bound=max(TILT_FRACTION * step_tolerance, TILT_ROUNDING),
        inertia=inertia, start=np.zeros(width + 4), start_slow=np.zeros(slow_width),
        start_fast=np.zeros(fast_width, dtype=complex), start_size=np.zeros(fast_width),
        modal_slow=np.zeros(slow_width), modal_fast=np.zeros(fast_width, dtype=complex),
        grid_fast=np.zeros(fast_width, dtype=complex),
        aimed_fast=np.zeros(fast_width, dtype=complex), series=np.zeros((2, slow_width)))


def _exact_forms(system: System, period_table, scales: np.ndarray, skip_defective: bool,
                 tolerance: float):
    """(valid, forms, rows): per exact form's index interval·VARIANTS + variant, 1 where the
    set and variant meet exact_condition and have a modal form; for those, (R, L, Λ, T_slow,
    the places of the fast modes kept, their weights) and the tilt rows. A set without a modal
    form (for a run at `tolerance`: condition_limit) raises np.linalg.LinAlgError unless
    `skip_defective`."""
    lengths, counts, tables = period_table
    forms, rows_of = {}, {}
    valid = np.zeros(len(lengths) * VARIANTS, dtype=np.int64)
    for interval in range(len(lengths)):
        count = int(counts[interval])
        for variant in range(VARIANTS):
            loaded = np.full(count, 1.0 if variant == ALL_LOADED else 0.0)
            a, b = linear_system(system, tables[interval], count, loaded)
            rows = tilt_rows(system, a)
            if not exact_condition(system, tables[interval], count, loaded, b, rows):
                continue
            try:
                right, left, rates, slow = modal_form(a, b, scales, tolerance)
                kept, weights = kept_modes(rates[len(slow):])
            except np.linalg.LinAlgError:
                if not skip_defective:
                    raise
                continue
            free = unseen_by_tilt(rows, right[:a.shape[0], len(slow) + kept], scales)
            kept, weights = kept[free], weights[free]
            place = interval * VARIANTS + variant
            forms[place] = (right, left, rates, slow, len(slow) + kept, weights)
            rows_of[place] = rows
            valid[place] = 1
    return valid, forms, rows_of


def _empty_arrays(places: int, size: int, width: int, slow_width: int, fast_width: int,
                  tilt_width: int) -> dict[str, np.ndarray]:
    """ExactTables' arrays (but `valid` and the scratch), zero, by field name."""
    shape: tuple[int, ...] = (places,)
    return {
        "slow_count": np.zeros(shape, dtype=np.int64),
        "fast_count": np.zeros(shape, dtype=np.int64),
        "tilt_count": np.zeros(shape, dtype=np.int64),
        "slow_left": np.zeros(shape + (slow_width, width)),
        "slow_right": np.zeros(shape + (size, slow_width)),
        "slow": np.zeros(shape + (slow_width, slow_width)),
        "slow_columns": np.zeros(shape + (slow_width, slow_width + 1), dtype=np.int64),
        "angle_polynomial": np.zeros(shape + (slow_width, slow_width)),
        "approach_polynomial": np.zeros(shape + (slow_width, slow_width)),
        "fast_left": np.zeros(shape + (fast_width, width), dtype=complex),
        "fast_right": np.zeros(shape + (size, fast_width), dtype=complex),
        "rates": np.zeros(shape + (fast_width,), dtype=complex),
        "tilt_rows": np.zeros(shape + (tilt_width, size)),
        "speed_slow": np.zeros(shape + (slow_width,)),
        "approach_slow": np.zeros(shape + (slow_width,)),
        "speed_size": np.zeros(shape + (fast_width,)),
        "approach_size": np.zeros(shape + (fast_width,)),
        "angle_size": np.zeros(shape + (fast_width,)),
        "speed_fast": np.zeros(shape + (fast_width,), dtype=complex),
        "approach_fast": np.zeros(shape + (fast_width,), dtype=complex)}


def _fill_place(arrays: dict[str, np.ndarray], place: int, form, rows: np.ndarray,
                system: System, state_scales: np.ndarray) -> None:
    """Write one exact form (_exact_forms' entry) and its tilt rows into `arrays` at `place`."""
    right, left, rates, t_slow, kept, weights = form
    n = system.mass.shape[0]
    size = 2 * n
    base = np.concatenate([system.contact_row_base_relative,
                           system.mesh_damping_factor * system.contact_row_base_relative])
    slow, fast = len(t_slow), len(kept)
    fast_right = right[:size, kept] * weights[None, :]
    entries = {"slow_left": left[:slow].real, "slow_right": right[:size, :slow].real,
               "slow": t_slow.real, "fast_left": left[kept], "fast_right": fast_right,
               "rates": rates[kept]}
    for name, value in entries.items():
        arrays[name][place][tuple(slice(0, extent) for extent in value.shape)] = value
    arrays["slow_count"][place], arrays["fast_count"][place] = slow, fast
    for i, row in enumerate(t_slow.real):
        columns = np.flatnonzero(row)
        arrays["slow_columns"][place][i, :len(columns) + 1] = [len(columns), *columns]
    arrays["speed_slow"][place][:slow] = right[n + system.pinion, :slow].real
    arrays["approach_slow"][place][:slow] = base @ right[:size, :slow].real
    # tabulated, since the mesh repeats: the aim at every switch then takes its polynomial
    # in S² products, not the series' S³
    arrays["angle_polynomial"][place][:slow, :slow] = _polynomial_rows(
        right[system.pinion, :slow].real, t_slow.real)
    arrays["approach_polynomial"][place][:slow, :slow] = _polynomial_rows(
        arrays["approach_slow"][place][:slow], t_slow.real)
    speed_fast, approach_fast = fast_right[n + system.pinion], base @ fast_right
    arrays["speed_fast"][place][:fast], arrays["approach_fast"][place][:fast] = (speed_fast,
                                                                              approach_fast)
    # their magnitudes kept beside them: the certificate of every exact step sums them
    arrays["speed_size"][place][:fast] = np.abs(speed_fast)
    arrays["approach_size"][place][:fast] = np.abs(approach_fast)
    arrays["angle_size"][place][:fast] = np.abs(fast_right[system.pinion])
    arrays["tilt_rows"][place][:len(rows)] = scaled_basis(rows, state_scales)
    arrays["tilt_count"][place] = len(rows)


def scaled_basis(rows: np.ndarray, scales: np.ndarray) -> np.ndarray:
    """Rows spanning the space `rows` span (tilt_rows: orthonormal in the state's own units),
    orthonormal in the state measured in `scales`, and applied to the state itself: their
    products with a state are the coordinates, in its scales, of its part in that space
    (variant_of's relative tilt). The rows as given, each merely scaled, are nearly parallel
    there (the scales span eight decades): on regain_after_separation's flight a wheel
    swinging on its bearings at 1e-3 of its scales read 8e-10 on every one of them, below
    the bound at 1e-6, and the segment went on exact without that swing. Columns no row
    involves stay exact zeros (tilt_rows says why)."""
    if len(rows) == 0:
        return rows
    basis = np.linalg.svd(_unit_rows(rows * scales[None, :]), full_matrices=False)[2]
    basis[:, ~rows.any(axis=0)] = 0.0
    return basis / scales[None, :]


def _polynomial_rows(row: np.ndarray, block: np.ndarray) -> np.ndarray:
    """row·block^n/n! for n < the block's size, by rows: the coefficients of a function's
    slow part as a polynomial in t, given its `row` of the slow columns and T_slow."""
    rows = [row]
    for power in range(1, block.shape[0]):
        rows.append(rows[-1] @ block / power)
    return np.array(rows)


# pack_tables' buffers, each in this order (ExactTables' fields of that dtype)
COMPLEX_FIELDS = ("fast_left", "fast_right", "rates", "speed_fast", "approach_fast",
                  "start_fast", "modal_fast", "grid_fast", "aimed_fast")
FLOAT_FIELDS = ("slow_left", "slow_right", "slow", "angle_polynomial", "approach_polynomial",
                "tilt_rows", "speed_slow", "approach_slow",
                "speed_size", "approach_size", "angle_size", "start", "start_slow", "start_size",
                "modal_slow", "series")
INT_FIELDS = ("valid", "slow_count", "fast_count", "tilt_count", "slow_columns")


def pack_tables(tables: ExactTables) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The tables as three flat arrays (complex, float, int) that `unpack_tables` takes apart in
    compiled code: numba types each array of a call's arguments at every call, and the
    twenty-six of ExactTables would cost the FMU's communication step more than the exact
    steps it takes. The ints open with the sizes (P, N, M, S, F, C); the floats end with
    tilt_bound and inertia."""
    places, size, fast = tables.fast_right.shape
    header = [places, size, tables.fast_left.shape[2], tables.slow.shape[1], fast,
              tables.tilt_rows.shape[1]]
    complexes = np.concatenate([getattr(tables, name).ravel() for name in COMPLEX_FIELDS])
    floats = np.concatenate([getattr(tables, name).ravel() for name in FLOAT_FIELDS]
                            + [[tables.tilt_bound, tables.inertia]])
    ints = np.concatenate([header] + [getattr(tables, name).ravel() for name in INT_FIELDS])
    return complexes, floats, ints.astype(np.int64)


# --- the kernels ---------------------------------------------------------------------------------

@njit(cache=True, error_model="numpy", inline="always")
def unpack_tables(buffers):
    """pack_tables' inverse: ExactTables whose arrays are views of its three buffers
    (complex, float, int). Each kernel is handed the buffers and unpacks them at its start,
    inlined: a call copies every array of its records onto the stack entry by entry (seven
    to eleven words an array), and three arrays are a tenth of the twenty-six."""
    complexes, floats, ints = buffers
    places, size, width, slow, fast, tilt = ints[0], ints[1], ints[2], ints[3], ints[4], ints[5]
    fast_left = _cube(complexes, 0, places, fast, width)
    at = places * fast * width
    fast_right = _cube(complexes, at, places, size, fast)
    at += places * size * fast
    rates = _matrix(complexes, at, places, fast)
    at += places * fast
    rows_of_fast_complex = _cube(complexes, at, 2, places, fast)
    at += 2 * places * fast
    start_fast, modal_fast = complexes[at:at + fast], complexes[at + fast:at + 2 * fast]
    grid_fast = complexes[at + 2 * fast:at + 3 * fast]
    aimed_fast = complexes[at + 3 * fast:at + 4 * fast]
    slow_left = _cube(floats, 0, places, slow, width)
    at = places * slow * width
    slow_right = _cube(floats, at, places, size, slow)
    at += places * size * slow
    slow_block = _cube(floats, at, places, slow, slow)
    at += places * slow * slow
    polynomials = _cube(floats, at, 2 * places, slow, slow)
    at += 2 * places * slow * slow
    rows = _cube(floats, at, places, tilt, size)
    at += places * tilt * size
    rows_of_slow = _cube(floats, at, 2, places, slow)
    at += 2 * places * slow
    rows_of_fast = _cube(floats, at, 3, places, fast)
    at += 3 * places * fast
    start = floats[at:at + width + 4]
    at += width + 4
    start_slow, start_size = floats[at:at + slow], floats[at + slow:at + slow + fast]
    at += slow + fast
    modal_slow = floats[at:at + slow]
    series = _matrix(floats, at + slow, 2, slow)
    header = 6
    slow_columns = _cube(ints, header + 4 * places, places, slow, slow + 1)
    return ExactTables(
        ints[header:header + places], ints[header + places:header + 2 * places],
        ints[header + 2 * places:header + 3 * places],
        ints[header + 3 * places:header + 4 * places], slow_left, slow_right, slow_block,
        slow_columns, polynomials[:places], polynomials[places:], fast_left, fast_right, rates,
        rows,
        rows_of_slow[0], rows_of_slow[1], rows_of_fast[0], rows_of_fast[1], rows_of_fast[2],
        rows_of_fast_complex[0], rows_of_fast_complex[1],
        floats[floats.shape[0] - 2], floats[floats.shape[0] - 1], start,
        start_slow, start_fast, start_size, modal_slow, modal_fast, grid_fast, aimed_fast,
        series)


@njit(cache=True, error_model="numpy")
def variant_of(buffers, interval, count, loaded, state):
    """Of the tables packed in `buffers` (pack_tables), the index interval·VARIANTS + variant
    of the segment's exact form, or −1 where it has none: its loaded points are neither all
    nor none, the set's variant is not exact, or the state does not start where the tilt
    stays zero."""
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
    exact = interval * VARIANTS + variant
    tables = unpack_tables(buffers)
    if tables.valid[exact] == 0:
        return -1
    rows = tables.tilt_rows
    for k in range(tables.tilt_count[exact]):
        product = 0.0
        for j in range(state.shape[0]):
            product += rows[exact, k, j] * state[j]
        if abs(product) > tables.tilt_bound:
            return -1
    return exact


@njit(cache=True, error_model="numpy", inline="always")
def _start_from(train, tables, exact, state, motor_torque, load_torque):
    """Make `state` the start whose modal coordinates tables.start_* hold (_prepare), unless
    they hold it already (_prepared)."""
    if not _prepared(tables, exact, state, motor_torque, load_torque):
        _prepare(train, tables, exact, state, motor_torque, load_torque)


@njit(cache=True, error_model="numpy", inline="always")
def _prepared(tables, exact, state, motor_torque, load_torque):
    """Whether tables.start holds this step's start already: the event location's trial
    steps all start where the step that crossed started, and its modal coordinates serve
    them all."""
    start, size = tables.start, state.shape[0]
    if (start[size + INPUTS] != exact + 1 or start[size] != motor_torque
            or start[size + 1] != load_torque):
        return False
    for j in range(size):
        if start[j] != state[j]:
            return False
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _prepare(train, tables, exact, state, motor_torque, load_torque):
    """The step's start into tables.start (X = [state; u], the exact form's index + 1, the
    momentum and moment, no aimed_fast yet), and L·X into start_slow and start_fast, the fast
    coordinates' magnitudes into start_size."""
    size = state.shape[0]
    start = tables.start
    for j in range(size):
        start[j] = state[j]
    start[size], start[size + 1], start[size + 2] = motor_torque, load_torque, 1.0
    width = size + INPUTS
    slow_left, fast_left = tables.slow_left, tables.fast_left
    for i in range(tables.slow_count[exact]):
        total = 0.0
        for j in range(width):
            total += slow_left[exact, i, j] * start[j]
        tables.start_slow[i] = total
    for k in range(tables.fast_count[exact]):
        real = imaginary = 0.0
        for j in range(width):
            entry = fast_left[exact, k, j]
            real += entry.real * start[j]
            imaginary += entry.imag * start[j]
        tables.start_fast[k] = complex(real, imaginary)
        tables.start_size[k] = math.sqrt(real * real + imaginary * imaginary)
    momentum, moment = _momentum(train, state)
    start[width], start[width + 1], start[width + 2] = exact + 1, momentum, moment
    start[AIMED_AT] = math.nan


@njit(cache=True, error_model="numpy", inline="always")
def _momentum(train, state):
    """Σ m·r·q̇ and Σ m·r·q over the coordinates (q from the contact set's start): the train's
    momentum and its integral along the rigid rotation r, which only the external torques
    change (every element's row is orthogonal to r)."""
    n = train.mass.shape[0]
    pinion = train.pinion
    momentum = moment = 0.0
    for j in range(n):
        weight = train.mass[j] * train.rigid_rotation[j]
        if j == pinion:
            momentum += weight * state[n + j]
            moment += weight * state[j]
        else:
            momentum += weight * (state[n + j] + train.rigid_rotation[j] * state[n + pinion])
            moment += weight * (state[j] + train.rigid_rotation[j] * state[pinion])
    return momentum, moment


# exp(λ·h) of a mode whose decay exponent Re(λ)·h is below this is taken as 0: it is below
# 1e-304, and libm's exp would reach its underflow path (errno) on the way to 0
UNDERFLOW_EXPONENT = -700.0


@njit(cache=True, error_model="numpy", inline="always")
def _exponential(rate, t):
    """e^{rate·t} of a mode of complex `rate` (1/s) after t (s); 0 where its decay exponent
    is below UNDERFLOW_EXPONENT."""
    exponent = rate.real * t
    if exponent < UNDERFLOW_EXPONENT:
        return complex(0.0, 0.0)
    decay, angle = math.exp(exponent), rate.imag * t
    return complex(decay * math.cos(angle), decay * math.sin(angle))


# The largest |Re| + |Im| of λ·(h − t) for which a step of h takes e^{λ·h} from the aim's
# e^{λ·t} (_fast_modes): the series to x³ then errs by x⁴/24 < 1e-17, and an aimed step lies
# well within it (docs/exponential-measurements.md, "The aimed step's exponentials from the
# aim's"); a larger one takes exp.
NEAR_EXPONENT = 1e-4

# What an exact step's certificate says (`step`; walk.control_exact_step acts on it)
CERTIFIED = 0  # no event function can cross zero inside the step unseen by its ends
PHASE_SURE = 1  # no phase event function can; a point's approach may (a landing, a lift-off)
UNSURE = 2  # the pinion may turn back across an end of its contact interval and return


@njit(**NUMBERS_ONLY)
def step(train, buffers, exact, state, motor_torque, load_torque, h, contact_loss,
         loaded_variant_sign, length, out):
    """The exact state after h (s) from `state` in the segment of exact form `exact`
    (variant_of's index) of the train (`train`, its ExactTrain) with the torques (N·m) held,
    into `out`, its momentum along the rigid rotation kept exact; returns what the step's
    certificate says (module docstring): CERTIFIED, PHASE_SURE or UNSURE. The phase events
    are sure where over the whole step the pinion speed keeps its sign (each phase event
    function is then monotone) or the pinion angle stays inside its contact interval of
    `length` (rad); and where `contact_loss`, the step is certified where also the points'
    approach keeps the sign `loaded_variant_sign` (+1 loaded, −1 unloaded). `buffers`: the
    tables as pack_tables packs them."""
    tables = unpack_tables(buffers)
    _start_from(train, tables, exact, state, motor_torque, load_torque)
    speed_swing, approach_swing = _fast_modes(tables, exact, h)
    speed_slow, approach_slow = _slow_series(tables, exact, h)
    _from_modal(tables, exact, out)
    _keep_momentum(train, tables, state, motor_torque, load_torque, h, out)
    if not _phase_sure(train, buffers, tables, exact, h, state, out, speed_slow, speed_swing,
                       length) and not _standing(speed_slow, speed_swing):
        return UNSURE
    if contact_loss and not keeps_sign(tables, exact, h, tables.approach_size,
                                       tables.approach_fast, approach_slow, approach_swing,
                                       loaded_variant_sign, _approach(train, state),
                                       _approach(train, out)) \
            and not _standing(approach_slow, approach_swing):
        return PHASE_SURE
    return CERTIFIED


@njit(cache=True, error_model="numpy", inline="always")
def _standing(slow, swing):
    """Whether a function of the state (its SlowBound `slow` and its fast modes' Σ|a_k|
    `swing`) is zero over the whole step: nothing moves it. A train at rest with no torque,
    its pinion on an end of its interval and its points touching unloaded, stands there: no
    bound can say the angle stays inside or the approach keeps a sign, since both are zero,
    and the steps would shrink to TURN_BACK_FLOOR of the floor (1.5e6 a second); standing, the
    speed cannot carry the angle across an end, nor the approach cross zero."""
    return slow.start == 0.0 and slow.drift == 0.0 and swing == 0.0


@njit(**NUMBERS_ONLY)
def state_after(train, buffers, exact, state, motor_torque, load_torque, h, out):
    """The exact state after h (s) from `state`, into `out`, as `step` computes it, without
    the certificate: for what lies inside a step already taken (the event location's trial
    steps, the samples), where only the state is asked for. `buffers`: the tables as
    pack_tables packs them."""
    tables = unpack_tables(buffers)
    _start_from(train, tables, exact, state, motor_torque, load_torque)
    _fast_modes(tables, exact, h)
    _slow_series(tables, exact, h)
    _from_modal(tables, exact, out)
    _keep_momentum(train, tables, state, motor_torque, load_torque, h, out)


@njit(cache=True, error_model="numpy", inline="always")
def _phase_sure(train, buffers, tables, exact, h, state, out, speed_slow, speed_swing,
                length):
    """Whether no phase event function can cross zero unseen within the step from `state` to
    `out` just taken: the pinion speed keeps its sign over it (its SlowBound and fast swing
    given; keeps_sign), or else its angle stays inside its interval (angle_inside)."""
    speed = train.mass.shape[0] + train.pinion
    if keeps_sign(tables, exact, h, tables.speed_size, tables.speed_fast, speed_slow,
                  speed_swing, 1.0 if state[speed] >= 0.0 else -1.0, state[speed], out[speed]):
        return True
    return angle_inside(train, buffers, exact, h, state[train.pinion], out[train.pinion],
                        length)


# a call of its own, not inlined: it runs only where the speed's sign is not certified, and
# inlined into every step it cost separation and high_speed 4 to 7 % of their time, as a
# call 2 to 4 %
@njit(**NUMBERS_ONLY)
def angle_inside(train, buffers, exact, h, at_start, at_end, length):
    """Whether over the step of h (s) just taken (the tables' start and its modal state at
    the end) the pinion angle, `at_start` and `at_end` (rad) at its ends, stays above 0 and
    below `length` (rad): keeps_sign's bounds for φp and for φp − length, or where they
    cannot tell, the finer bounds of a grid over the step (inside_on_grid). `buffers`: the
    tables as pack_tables packs them."""
    tables = unpack_tables(buffers)
    pinion = train.pinion
    swing = _angle_swing(tables, exact)
    slow = _angle_bound(tables, exact, h)
    rows = tables.fast_right[:, pinion, :]
    to_end = SlowBound(slow.start - length, slow.drift, slow.curve)
    if keeps_sign(tables, exact, h, tables.angle_size, rows, slow, swing, 1.0, at_start,
                  at_end) and keeps_sign(tables, exact, h, tables.angle_size, rows, to_end,
                                         swing, -1.0, at_start - length, at_end - length):
        return True
    return inside_on_grid(buffers, exact, h, pinion, length)


# angle_inside's grid: its first interval turns the fastest mode by at most this (|λ|·δ),
# and it halves the step at most this many times (each halving squares e^{λ·t} once more on
# the way back out, doubling its rounding: 2^16 of it is 1e-11 of a mode's magnitude)
GRID_FIRST_TURN = 1.0
GRID_LEVELS = 16


# a call of its own, not inlined into angle_inside: inlined, its code cost high_speed and the
# reference scene 10 to 16 % of their time, though it never runs there
@njit(**NUMBERS_ONLY)
def inside_on_grid(buffers, exact, h, pinion, length):
    """Whether the pinion angle stays above 0 and below `length` (rad) over the step of h (s)
    just taken, judged on the grid 0, δ, 2δ, 4δ, ..., h (δ = h/2^K, K the fewest halvings
    that bring |λ|max·δ to GRID_FIRST_TURN): on each interval, from the angle's values and
    rates at its ends (the modes' phases, not only their magnitudes), by
    _interval_low. Right after a switch the angle starts at its interval's start and the
    fast modes may swing the speed through zero: the fine intervals near the start see the
    speed carry the angle in before the modes turn; the coarse ones further on need only
    the angle's margin to exceed what the modes can swing. (tables.modal_slow holds the
    angle's slow polynomial: _angle_bound.) `buffers`: the tables as pack_tables packs
    them."""
    tables = unpack_tables(buffers)
    count = tables.fast_count[exact]
    fastest = 0.0
    for k in range(count):
        fastest = max(fastest, abs(tables.rates[exact, k]))
    first, levels = h, 0
    while first * fastest > GRID_FIRST_TURN and levels < GRID_LEVELS:
        first *= 0.5
        levels += 1
    grid = tables.grid_fast
    for k in range(count):
        grid[k] = 1.0
    start, end = 0.0, first
    for _ in range(levels + 1):
        if not _interval_inside(tables, exact, pinion, length, start, end, grid):
            return False
        start, end = end, 2.0 * end
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _interval_inside(tables, exact, pinion, length, start, end, grid):
    """inside_on_grid on one interval [start, end] (s) of it: whether the angle stays above
    0 and below `length` there. `grid` holds each mode's e^{λ·start} and is moved on to
    e^{λ·end} (its square where end = 2·start). A mode that turns through much of a period
    within the interval (|λ|·δ ≥ √8) is taken out of the ends' values and rates and counted
    at its magnitude; the others and the slow polynomial bound the curvature."""
    width = end - start
    polynomial, degree = tables.modal_slow, tables.slow_count[exact] - 1
    value0, rate0 = _polynomial_at(polynomial, degree, start)
    value1, rate1 = _polynomial_at(polynomial, degree, end)
    curve = _polynomial_curve(polynomial, degree, end)
    swing = 0.0
    for k in range(tables.fast_count[exact]):
        rate = tables.rates[exact, k]
        at_start = grid[k]
        at_end = at_start * at_start if end == 2.0 * start else _exponential(rate, end)
        grid[k] = at_end
        largest = tables.angle_size[exact, k] * tables.start_size[k] * math.sqrt(max(
            at_start.real * at_start.real + at_start.imag * at_start.imag,
            at_end.real * at_end.real + at_end.imag * at_end.imag))
        size_squared = rate.real * rate.real + rate.imag * rate.imag
        if size_squared * width * width >= 8.0:
            swing += largest
            continue
        curve += largest * size_squared
        coefficient = tables.fast_right[exact, pinion, k] * tables.start_fast[k]
        term0, term1 = coefficient * at_start, coefficient * at_end
        value0, value1 = value0 + term0.real, value1 + term1.real
        rate0, rate1 = rate0 + (term0 * rate).real, rate1 + (term1 * rate).real
    return (_interval_low(value0, rate0, value1, rate1, curve, width) > swing
            and _interval_low(length - value0, -rate0, length - value1, -rate1, curve,
                              width) > swing)


# approach_dip's march: an interval turns the fastest mode by at most DIP_TURN (|λ|·δ); one
# its bound cannot clear is halved, down to DIP_HALVINGS halvings, and passed there: what it
# leaves is a touch within that interval's parabola of zero, at most 5e-7 of the modes' swing
# (right after a contact event, where the approach starts at zero, every step has one). An
# approach that hovers at zero through the step (a mesh in contact without load) would take
# it down to its narrowest intervals all the way: past DIP_EVALUATIONS evaluations it gives
# up, and the step has the cubic's check as a step of DOP853 has
DIP_TURN = 0.5
DIP_HALVINGS = 8
DIP_EVALUATIONS = 256
# approach_first_crossing's march gives up sooner, at its first touch too: it only saves the
# loop its own steps, and where the approach comes near zero without crossing (separation's
# loaded points) marches to DIP_EVALUATIONS cost a quarter of the scene's time for no event
FIRST_CROSSING_EVALUATIONS = 48


@njit(**NUMBERS_ONLY)
def approach_dip(train, buffers, exact, state, motor_torque, load_torque, h, sign):
    """Where (s) inside the step of h (s) from `state` the approach of the segment's points
    (one function: the tilt is zero, they have no lead error) first lies past zero, on the
    side opposite to `sign` (+1: loaded, a lift-off; −1: unloaded, a landing), where the
    step's ends do not show it: where its end lies on the side `sign`, or where it does not
    but the approach comes back before it (a flight, or a touch, before the crossing the end
    shows); −1 where there is none; NaN where the march gives up (DIP_EVALUATIONS). Judged
    on its modal solution by _first_past_zero. A step
    the certificate cannot clear is taken at the exact floor, h·|λ|max = 3.5, where a
    lift-off and a landing a tenth as long can lie between its ends unseen by the cubic
    through their values and slopes (tests/regression/found_e759bc9542.toml). `buffers`: the
    tables as pack_tables packs them."""
    tables, degree, curve, widest = _dip_march(train, buffers, exact, state, motor_torque,
                                               load_torque, h)
    past = _first_past_zero(tables, exact, degree, sign, curve, 0.0, h, widest,
                            DIP_EVALUATIONS, True)
    if not past > 0.0 or _approach_at(tables, exact, degree, sign, h)[0] >= 0.0:
        return past
    back = _first_past_zero(tables, exact, degree, -sign, curve, past, h, widest,
                            DIP_EVALUATIONS, True)
    return back if math.isnan(back) else (past if back > 0.0 else -1.0)


@njit(**NUMBERS_ONLY)
def approach_first_crossing(train, buffers, exact, state, motor_torque, load_torque, h,
                            sign):
    """Where (s from `state`) the approach of the segment's points (one function, as
    approach_dip takes it) first crosses zero from the side `sign` (+1: loaded, a lift-off;
    −1: unloaded, a landing) within h (s), whatever the step's end shows: approach_dip's march
    from the start brackets the first time it lies past zero, and Newton's method on its modal
    solution finds the crossing inside that bracket (_modal_crossing). −1 where it stays on its
    side over all of h; NaN where the march gives up or Newton does not converge. A step aimed
    just past the crossing then ends on the event (walk.aimed_contact). `buffers`: the tables
    as pack_tables packs them."""
    tables, degree, curve, widest = _dip_march(train, buffers, exact, state, motor_torque,
                                               load_torque, h)
    past = _first_past_zero(tables, exact, degree, sign, curve, 0.0, h, widest,
                            FIRST_CROSSING_EVALUATIONS, False)
    if not past > 0.0:
        return past
    crossing = _modal_crossing(tables, exact, tables.approach_fast[exact], degree, 0.0,
                               sign < 0.0, past, past, False)
    return crossing if crossing > 0.0 else math.nan


@njit(cache=True, error_model="numpy", inline="always")
def _dip_march(train, buffers, exact, state, motor_torque, load_torque, h):
    """What approach_dip's march over a step of h (s) from `state` needs: (the tables, their
    modal start and the approach's slow polynomial made; its degree; the bound on the
    approach's curvature over the step; the widest interval, s, one that turns the fastest
    mode by DIP_TURN)."""
    tables = unpack_tables(buffers)
    _start_from(train, tables, exact, state, motor_torque, load_torque)
    degree = _slow_polynomial(tables, exact, tables.approach_polynomial[exact])
    fastest = curve = 0.0
    for k in range(tables.fast_count[exact]):
        size = abs(tables.rates[exact, k])
        fastest = max(fastest, size)
        curve += tables.approach_size[exact, k] * tables.start_size[k] * size * size
    curve += _polynomial_curve(tables.modal_slow, degree, h)
    return tables, degree, curve, h / max(1.0, math.ceil(h * fastest / DIP_TURN))


@njit(cache=True, error_model="numpy", inline="always")
def _first_past_zero(tables, exact, degree, sign, curve, start, end, widest, most, touches):
    """The first time (s) in (start, end] at which sign times the approach is negative,
    marching from `start` by intervals at most `widest` (s) long on which _interval_low
    bounds it from its values and rates at their ends and its curvature bound `curve`, an
    interval that bound cannot clear halved (DIP_HALVINGS times at most) and passed there as
    a touch where `touches` (else it ends the march: approach_first_crossing's, for which
    the loop's own steps look closer); −1 where there is none, NaN past `most` evaluations
    or at a touch that ends it."""
    narrowest = widest / 2.0 ** DIP_HALVINGS
    width = widest
    value0, rate0 = _approach_at(tables, exact, degree, sign, start)
    for _ in range(most):
        if start >= end:
            return -1.0
        stop = min(end, start + width)
        value1, rate1 = _approach_at(tables, exact, degree, sign, stop)
        if value1 < 0.0:
            return stop
        cleared = _interval_low(value0, rate0, value1, rate1, curve, stop - start) > 0.0
        if not cleared and width <= narrowest and not touches:
            return math.nan
        if cleared or width <= narrowest:
            start, value0, rate0 = stop, value1, rate1
            width = min(widest, 2.0 * width) if cleared else width
        else:
            width *= 0.5
    return -1.0 if start >= end else math.nan


@njit(cache=True, error_model="numpy", inline="always")
def _approach_at(tables, exact, degree, sign, t):
    """sign times the approach and its rate t s into the step (approach_dip's: its slow
    polynomial in tables.modal_slow, of `degree`)."""
    value, rate = _polynomial_at(tables.modal_slow, degree, t)
    for k in range(tables.fast_count[exact]):
        rate_k = tables.rates[exact, k]
        mode = tables.approach_fast[exact, k] * tables.start_fast[k] * _exponential(rate_k, t)
        value += mode.real
        rate += (mode * rate_k).real
    return sign * value, sign * rate


@njit(cache=True, error_model="numpy", inline="always")
def _polynomial_curve(terms, degree, end):
    """A bound on |p''| over [0, end] of the polynomial Σ terms[n]·t^n of `degree`:
    Σ n·(n − 1)·|terms[n]|·end^(n−2)."""
    curve, power = 0.0, 1.0
    for order in range(2, degree + 1):
        curve += order * (order - 1) * abs(terms[order]) * power
        power *= end
    return curve


@njit(cache=True, error_model="numpy", inline="always")
def _interval_low(value0, rate0, value1, rate1, curve, width):
    """The least a function can be over an interval of `width` with these values and rates
    at its ends and |f''| ≤ `curve` there: it lies above both parabolas f(a) + f'(a)·s −
    curve·s²/2 and f(b) − f'(b)·(width − s) − curve·(width − s)²/2, whose difference is linear
    in s, so the larger of the two is least at an end or where they cross."""
    lowest = min(value0, value1)
    slope = rate0 - rate1 - curve * width
    if slope != 0.0:
        crossing = -(value0 - value1 + rate1 * width + 0.5 * curve * width * width) / slope
        if 0.0 < crossing < width:
            lowest = min(lowest, value0 + (rate0 - 0.5 * curve * crossing) * crossing)
    return lowest


@njit(**NUMBERS_ONLY)
def modal_phase_event_ahead(train, buffers, exact, state, motor_torque, load_torque, length,
                            horizon):
    """When (s from `state`) the pinion angle leaves its contact interval of `length` (rad) in
    the segment of exact form `exact` with the torques (N·m) held, and what kind of time that
    is. First a time by which it has surely left: where the slow part of its motion (a
    polynomial in t, no exponentials) reaches `length` plus the fast modes' swing of the
    angle (moving forward), or minus it below zero (moving back), by Newton's method; inf
    where it stands still or turns back first, or where it surely stays inside until
    `horizon` (s: the call's end, which the step will not pass). From there Halley's method
    on the angle's whole modal solution (_modal_crossing) finds the crossing itself
    (CROSSING); where it does not converge, the time found first is returned as NEAR where
    the swing is no more than PREDICTION_SPREAD of the way, else as a BOUND only (a
    torsional mode swinging the angle, as in torque_step, makes a step aimed there overshoot
    the event by much). The instantaneous speed and acceleration, which
    walk.phase_event_ahead extrapolates, carry the fast modes' ringing (a switch sets the
    pinion accelerating at 1e6 rad/s² and more), and neither the slow part nor the whole
    solution is misled by it. `buffers`: the tables as pack_tables packs them."""
    tables = unpack_tables(buffers)
    _start_from(train, tables, exact, state, motor_torque, load_torque)
    pinion = train.pinion
    swing = _angle_swing(tables, exact)
    degree = _slow_polynomial(tables, exact, tables.angle_polynomial[exact])
    terms = tables.modal_slow  # (scratch: the polynomial's coefficients, by power of t)
    reach = _polynomial_bound(terms, degree + 1, horizon)[0].drift + swing
    if terms[1] == 0.0 or (reach < terms[0] < length - reach):
        return math.inf, NEAR
    forward = terms[1] > 0.0
    target = length + swing if forward else -swing
    near = NEAR if swing <= PREDICTION_SPREAD * abs(target - terms[0]) else BOUND
    ahead = _polynomial_root(terms, degree, target)
    if ahead == math.inf:
        return ahead, near
    crossing = _modal_crossing(tables, exact, tables.fast_right[exact, pinion], degree,
                               length if forward else 0.0, forward, ahead, ahead, True)
    return (crossing, CROSSING) if crossing > 0.0 else (ahead, near)


@njit(**NUMBERS_ONLY)
def approach_crossing(train, buffers, exact, state, motor_torque, load_torque, high, rising,
                      guess):
    """Where (s from `state`) a point's approach crosses zero, `rising` (a landing) or falling
    (a lift-off), inside a step to `high` (s) that crossed it, in the segment of exact form
    `exact` with the torques (N·m) held: Newton's method on the approach's whole modal
    solution (_modal_crossing) from `guess` (s; from `high` where it lies outside the
    bracket), a few complex exponentials an iteration where a trial step of the location
    costs the whole state; −1 where it does not converge. The event location's first
    estimate (walk.locate_event): its first trial then ends the bracket just past the
    crossing. `buffers`: the tables as pack_tables packs them."""
    tables = unpack_tables(buffers)
    _start_from(train, tables, exact, state, motor_torque, load_torque)
    degree = _slow_polynomial(tables, exact, tables.approach_polynomial[exact])
    return _modal_crossing(tables, exact, tables.approach_fast[exact], degree, 0.0, rising,
                           high, guess if 0.0 < guess < high else high, False)


@njit(cache=True, error_model="numpy", inline="always")
def _polynomial_root(terms, degree, target):
    """Where the polynomial Σ terms[n]·t^n of `degree` first reaches `target`, by Newton's
    method from its tangent at 0 (s); inf where it turns back before it gets there."""
    ahead = (target - terms[0]) / terms[1]
    for _ in range(PREDICTION_ITERATIONS):
        value, slope = _polynomial_at(terms, degree, ahead)
        if ahead <= 0.0 or slope * terms[1] <= 0.0:  # turns back before it gets there
            return math.inf
        change = (value - target) / slope
        ahead -= change
        if abs(change) <= PREDICTION_PRECISION * ahead:
            break
    return ahead if ahead > 0.0 else math.inf


@njit(cache=True, error_model="numpy", inline="always")
def _polynomial_at(terms, degree, t):
    """The polynomial Σ terms[n]·t^n of `degree` and its derivative in t
    (_polynomial_derivatives; inlined, the higher derivatives are not computed)."""
    value, slope, _, _ = _polynomial_derivatives(terms, degree, t)
    return value, slope


@njit(cache=True, error_model="numpy", inline="always")
def _modal_crossing(tables, exact, rows, degree, end, forward, sure, guess, halley):
    """Where a function of the state's whole modal solution from the step's start (its slow
    polynomial of `degree` in tables.modal_slow, its row of the fast modes `rows`: the pinion
    angle's, a point's approach's) reaches `end`, rising (`forward`) or falling, by Halley's
    method (`halley`; it stops where _cubed_error puts the iterate at the root to rounding)
    or Newton's from `guess` (s) kept inside [0, `sure`] (s), the time by which it has surely
    passed it, bisecting where a step would leave that bracket; −1 where it does not
    converge within CROSSING_ITERATIONS (the function swung back and forth across `end`).
    An approach, which may cross zero more than once in the bracket, is taken by Newton's:
    Halley's, whose steps are longer, located jump_resonance's landings and lift-offs in a
    tenth more trials.
    Each iteration is the function's row of the modes alone, a few complex exponentials.
    The result is a smooth function of the start to rounding (a value found on `end` to the
    bit is the root, not a bracket's end to bisect from): the period map's forward
    differences read the angle's at 1e-13 of the state's scales."""
    low, high = 0.0, sure
    ahead = guess
    for _ in range(CROSSING_ITERATIONS):
        value, slope, curve, third = _modal_at(tables, exact, rows, degree, ahead, halley)
        value -= end
        if value == 0.0:
            return ahead
        if (value > 0.0) == forward:
            high = ahead
        else:
            low = ahead
        change = _halley_change(value, slope, curve) if halley else value / slope
        guess = ahead - change if slope != 0.0 else low
        if not low < guess < high:
            guess = 0.5 * (low + high)
        elif halley and _cubed_error(change, slope, curve, third) <= CROSSING_ROUNDING * guess:
            return guess
        if abs(guess - ahead) <= CROSSING_PRECISION * guess:
            return guess
        ahead = guess
    return -1.0


@njit(cache=True, error_model="numpy", inline="always")
def _cubed_error(change, slope, curve, third):
    """A bound on the error a Halley step of `change` leaves, from the function's first,
    second and third derivatives where it was taken: to leading order it is
    |f''²/(4·f'²) − f⁽³⁾/(6·f')|·|change|³, below (f''²/f'² + |f⁽³⁾/f'|)·|change|³."""
    return ((curve / slope) ** 2 + abs(third / slope)) * abs(change) ** 3


@njit(cache=True, error_model="numpy", inline="always")
def _halley_change(value, slope, curve):
    """Halley's step towards a function's zero from its value, slope and curvature there:
    Newton's step value/slope divided by 1 − (value/slope)·curve/(2·slope), or Newton's own
    where that divisor falls below one half (a turning point near)."""
    newton = value / slope
    divisor = 1.0 - 0.5 * newton * curve / slope
    return newton / divisor if divisor >= 0.5 else newton


@njit(cache=True, error_model="numpy", inline="always")
def _modal_at(tables, exact, rows, degree, t, keep):
    """A function of the state and its first three derivatives (per s, s², s³) t s after
    the step's start, from its slow polynomial (tables.modal_slow, of `degree`) and its
    row of the fast modes `rows`. With `keep` (a constant where it is inlined: the angle's
    aim), the modes' e^{λ·t} are kept in tables.aimed_fast, and t beside them, for the step
    aimed there (_fast_modes); an approach's Newton iterations, which no step follows, do
    not keep them (docs/exponential-measurements.md, "The aimed step's exponentials from the
    aim's")."""
    value, slope, curve, third = _polynomial_derivatives(tables.modal_slow, degree, t)
    aimed = tables.aimed_fast
    for k in range(tables.fast_count[exact]):
        rate = tables.rates[exact, k]
        propagator = _exponential(rate, t)
        if keep:
            aimed[k] = propagator
        mode = rows[k] * tables.start_fast[k] * propagator
        rated = mode * rate
        twice = rated * rate
        value += mode.real
        slope += rated.real
        curve += twice.real
        third += (twice * rate).real
    if keep:
        tables.start[AIMED_AT] = t
    return value, slope, curve, third


@njit(cache=True, error_model="numpy", inline="always")
def _polynomial_derivatives(terms, degree, t):
    """The polynomial Σ terms[n]·t^n of `degree` and its first three derivatives in t, by
    Horner's rule."""
    value, slope, curve, third = terms[degree], 0.0, 0.0, 0.0
    for power in range(degree - 1, -1, -1):
        third = third * t + 3.0 * curve
        curve = curve * t + 2.0 * slope
        slope = slope * t + value
        value = value * t + terms[power]
    return value, slope, curve, third


@njit(cache=True, error_model="numpy", inline="always")
def _slow_polynomial(tables, exact, rows):
    """The slow part of a function of the state from the step's start (tables.start_slow) as
    a polynomial in t, the function's `rows` given (angle_polynomial, approach_polynomial:
    its row of the slow columns times T_slow^n/n!, n < S; the block is nilpotent but for
    rounding): its coefficients into tables.modal_slow. Returns its degree."""
    slow_count = tables.slow_count[exact]
    start, terms = tables.start_slow, tables.modal_slow
    degree = 0
    for power in range(slow_count):
        total = 0.0
        for k in range(slow_count):
            total += rows[power, k] * start[k]
        terms[power] = total
        if total != 0.0:
            degree = power
    return max(degree, 1)


@njit(cache=True, error_model="numpy", inline="always")
def _next_term(tables, exact, slow_count, factor):
    """The slow block's series, one term on: tables.series[1] = T_slow·series[0]·factor (h/n
    for the n-th term of exp(T_slow·h)), over the block's entries that are not zero
    (slow_columns): each row's sum is the whole row's, in the same order, to the bit, since
    the entries left out add only zeros to it."""
    block, series, columns = tables.slow, tables.series, tables.slow_columns
    for i in range(slow_count):
        total = 0.0
        for k in range(1, columns[exact, i, 0] + 1):
            j = columns[exact, i, k]
            total += block[exact, i, j] * series[0, j]
        series[1, i] = total * factor


class SlowBound(NamedTuple):
    """Of a function of the state (the pinion speed, a point's approach) over an exact step
    [0, h]: what bounds its slow part, a polynomial in t. Units: the function's."""

    start: float  # its value at the step's start
    drift: float  # how far it can move over the step: its terms' magnitudes
    curve: float  # how far it can bow from its chord: its terms of order ≥ 2, as
    #               |t^n − t·h^(n−1)| ≤ h^n on [0, h]


@njit(cache=True, error_model="numpy", inline="always")
def keeps_sign(tables, exact, h, sizes, rows, slow, swing, sign, at_start, at_end):
    """Whether sign·f > 0 over the whole step just taken: _keeps_sign of f itself."""
    return _keeps_sign(tables, exact, h, sizes, rows, slow, swing, sign, at_start, at_end,
                       False)


@njit(cache=True, error_model="numpy", inline="always")
def _keeps_sign(tables, exact, h, sizes, rows, slow, swing, sign, at_start, at_end,
                derivative):
    """Whether sign·f > 0 over the whole step just taken (the tables' start_fast, modal_fast)
    for a function f of the state: its row of fast_right `rows` and their magnitudes `sizes`
    (ExactTables' speed_fast and speed_size, or approach_fast and approach_size), its slow
    part's SlowBound, its fast modes' Σ|a_k| `swing`, and its values at the step's ends.

    Either of two lower bounds of sign·f will do. The first: its slow part at the start less
    all that can move, for a step over which the modes ring through whole periods. The
    second, for a step short against the modes that swing most: the fast modes' sum
    Σ Re(a_k·e^{λ_k·t}) is split into the modes that turn through much of a period within
    the step (|λ|·h ≥ √8), each at least −|a|, and the others, whose curvature is at most
    |a|·|λ|²: f less the first kind lies above the chord of its ends less the parabola
    that curvature allows (chord_low), less the slow part's bow.

    With `derivative` (a constant where it is inlined) the function is f's rate instead:
    each mode's row is taken times its eigenvalue and its magnitude times |λ|; `slow`,
    `swing` and the ends are then the rate's."""
    if sign * slow.start > slow.drift + swing:
        return True
    bow = short_swing = short_start = short_end = 0.0
    for k in range(tables.fast_count[exact]):
        rate = tables.rates[exact, k]
        bend = (rate.real * rate.real + rate.imag * rate.imag) * h * h * 0.5
        size = sizes[exact, k] * tables.start_size[k] * (abs(rate) if derivative else 1.0)
        if bend >= 4.0:  # |λ|·h ≥ √8
            row = rows[exact, k] * (rate if derivative else 1.0)
            short_swing += size
            short_start += (row * tables.start_fast[k]).real
            short_end += (row * tables.modal_fast[k]).real
        else:
            bow += size * bend
    lowest = chord_low(sign * (at_start - short_start), sign * (at_end - short_end), bow)
    return lowest > slow.curve + short_swing


@njit(cache=True, error_model="numpy", inline="always")
def chord_low(start, end, bow):
    """The least, over s in [0, 1], of start + (end − start)·s − bow·s·(1 − s): the lowest a
    function with these values at a step's ends can go where its second derivative is at
    least −2·bow/h² (bow ≥ 0; h the step). Where the ends differ by at least `bow` the
    parabola is lowest at the lower end: a step over which the function falls steeply
    towards a root is judged by its end's value alone. With equal ends it is bow/4 below
    them."""
    fall = bow + start - end
    if 0.0 < fall < 2.0 * bow:
        return start - fall * fall / (4.0 * bow)
    return min(start, end)


@njit(**NUMBERS_ONLY)
def approach_monotone(buffers, exact, h):
    """Whether a point's approach is monotone over the step of h (s) just taken (the tables'
    start and its modal state at the end): its rate keeps its sign (_keeps_sign of the rate:
    the modes' rows times their eigenvalues, the slow polynomial's derivative). The approach
    then crosses zero at most once, and the step's ends show whether it did: walk.py takes
    such a step as certified where keeps_sign could not certify the approach itself (a step
    that closes in on a lift-off or a landing, or crosses it). A call of its own: it runs
    only there. `buffers`: the tables as pack_tables packs them."""
    tables = unpack_tables(buffers)
    _slow_polynomial(tables, exact, tables.approach_polynomial[exact])
    count, terms = tables.slow_count[exact], tables.modal_slow
    for order in range(1, count):  # the derivative's coefficients n·c_n, in place
        terms[order - 1] = order * terms[order]
    terms[count - 1] = 0.0
    slope, at_end = _polynomial_bound(terms, count, h)
    swing = at_start = 0.0
    for k in range(tables.fast_count[exact]):
        row, rate = tables.approach_fast[exact, k], tables.rates[exact, k]
        swing += tables.approach_size[exact, k] * abs(rate) * tables.start_size[k]
        at_start += (row * rate * tables.start_fast[k]).real
        at_end += (row * rate * tables.modal_fast[k]).real
    at_start += slope.start
    sign = 1.0 if at_start >= 0.0 else -1.0
    return _keeps_sign(tables, exact, h, tables.approach_size, tables.approach_fast, slope,
                       swing, sign, at_start, at_end, True)


@njit(cache=True, error_model="numpy", inline="always")
def _fast_modes(tables, exact, h):
    """Propagate the fast coordinates of the step's start over h into tables.modal_fast.
    Returns the Σ|a_k| of the pinion speed's fast modes and of a point's approach's.
    A step aimed at a crossing ends where the aim last evaluated the modes (_modal_at) but
    for its last change, tiny: e^{λ·h} is then e^{λ·t} there times the series of
    e^{λ·(h − t)} (_near_exponential), a few products instead of an exp and a sincos."""
    speed_swing = approach_swing = 0.0
    rates, start_fast, modal_fast = tables.rates, tables.start_fast, tables.modal_fast
    beyond = h - tables.start[AIMED_AT]  # NaN where no aim evaluated
    for k in range(tables.fast_count[exact]):
        size = tables.start_size[k]
        speed_swing += tables.speed_size[exact, k] * size
        approach_swing += tables.approach_size[exact, k] * size
        rate = rates[exact, k]
        near = rate * beyond
        if abs(near.real) + abs(near.imag) <= NEAR_EXPONENT:
            modal_fast[k] = start_fast[k] * (tables.aimed_fast[k] * _near_exponential(near))
        else:
            modal_fast[k] = start_fast[k] * _exponential(rate, h)
    return speed_swing, approach_swing


@njit(cache=True, error_model="numpy", inline="always")
def _near_exponential(x):
    """e^x of a complex x with |Re x| + |Im x| ≤ NEAR_EXPONENT, to rounding: its series to
    x³."""
    return 1.0 + x * (1.0 + 0.5 * x * (1.0 + x / 3.0))


@njit(cache=True, error_model="numpy", inline="always")
def _keep_momentum(train, tables, state, motor_torque, load_torque, h, out):
    """Put the step's end `out` back on the train's momentum along the rigid rotation and on
    its integral, which the net torque alone changes, exactly. The rounding of the modal
    round trip, about 1e-13 of Â, leaves the rigid rotation a bias where the torques' large
    accelerations cancel (9e-9 rad/s² on the reference scene: the switches drift, 2e-8 of
    the force scale after 0.3 s)."""
    width = state.shape[0] + INPUTS
    momentum, moment = tables.start[width + 1], tables.start[width + 2]
    net = motor_torque - load_torque * train.rigid_rotation[train.wheel]
    momentum_after, moment_after = _momentum(train, out)
    n = train.mass.shape[0]
    out[n + train.pinion] += (momentum + net * h - momentum_after) / tables.inertia
    out[train.pinion] += (moment + momentum * h + 0.5 * net * h * h
                           - moment_after) / tables.inertia


@njit(cache=True, error_model="numpy", inline="always")
def _approach(train, state):
    """A point's approach δ + η·δ̇ (m) at `state` in an exact segment (equations.point_approach
    with no lever arm and no lead error): the tilt is zero there, so the lever arm drops out,
    and the set has no lead error (it is dβ·z, and its slope dβ makes a set not exact)."""
    return point_approach(train, contact_motion(train, state), 0.0, 0.0)


@njit(cache=True, error_model="numpy", inline="always")
def _slow_series(tables, exact, h):
    """Propagate the slow coordinates of the step's start over h by their series into
    tables.modal_slow (exp(T_slow·h) applied term by term; the block is nilpotent but for
    rounding, so the series ends after a few terms). Returns the SlowBound of the pinion speed
    and of a point's approach."""
    slow_count = tables.slow_count[exact]
    series, modal = tables.series, tables.modal_slow
    speed_row, approach_row = tables.speed_slow, tables.approach_slow
    speed0 = approach0 = 0.0
    largest = 0.0
    for k in range(slow_count):
        coordinate = tables.start_slow[k]
        speed0 += speed_row[exact, k] * coordinate
        approach0 += approach_row[exact, k] * coordinate
        series[0, k] = coordinate
        modal[k] = coordinate
        largest = max(largest, abs(coordinate))
    speed_drift = approach_drift = speed_curve = approach_curve = 0.0
    for order in range(1, MAX_SERIES_TERMS):  # series[0]: the term, series[1]: the next
        size = 0.0
        _next_term(tables, exact, slow_count, h / order)
        speed_change = approach_change = 0.0
        for i in range(slow_count):
            following = series[1, i]
            series[0, i] = following
            modal[i] += following
            speed_change += speed_row[exact, i] * following
            approach_change += approach_row[exact, i] * following
            size = max(size, abs(following))
        speed_drift += abs(speed_change)
        approach_drift += abs(approach_change)
        if order >= 2:
            speed_curve += abs(speed_change)
            approach_curve += abs(approach_change)
        if size <= SERIES_FLOOR * largest:
            break
    return (SlowBound(speed0, speed_drift, speed_curve),
            SlowBound(approach0, approach_drift, approach_curve))


@njit(cache=True, error_model="numpy", inline="always")
def _angle_swing(tables, exact):
    """Σ|a_k| of the pinion angle's fast modes from the step's start (rad): how far they can
    swing it either way."""
    swing = 0.0
    for k in range(tables.fast_count[exact]):
        swing += tables.angle_size[exact, k] * tables.start_size[k]
    return swing


@njit(cache=True, error_model="numpy", inline="always")
def _angle_bound(tables, exact, h):
    """The pinion angle's SlowBound over h from the step's start, from its slow part's
    polynomial (_slow_polynomial, in tables.modal_slow: scratch once the step is taken)."""
    _slow_polynomial(tables, exact, tables.angle_polynomial[exact])
    return _polynomial_bound(tables.modal_slow, tables.slow_count[exact], h)[0]


@njit(cache=True, error_model="numpy", inline="always")
def _polynomial_bound(terms, count, h):
    """Of the polynomial Σ c_n·t^n with the `count` coefficients `terms`, over [0, h]: its
    SlowBound (Σ|c_n|·h^n over its terms of order ≥ 1, and over those of order ≥ 2 for the
    curve), and its value at h."""
    drift = curve = 0.0
    value = terms[0]
    power = h
    for order in range(1, count):
        term = terms[order] * power
        value += term
        drift += abs(term)
        curve += abs(term) if order >= 2 else 0.0
        power *= h
    return SlowBound(terms[0], drift, curve), value


@njit(cache=True, error_model="numpy", inline="always")
def _from_modal(tables, exact, out):
    """out = R_slow·modal_slow + Re(R_fast·modal_fast)."""
    slow_right, fast_right = tables.slow_right, tables.fast_right
    modal_slow, modal_fast = tables.modal_slow, tables.modal_fast
    slow_count, fast_count = tables.slow_count[exact], \
        tables.fast_count[exact]
    for i in range(out.shape[0]):
        total = 0.0
        for k in range(slow_count):
            total += slow_right[exact, i, k] * modal_slow[k]
        for k in range(fast_count):
            entry, coordinate = fast_right[exact, i, k], modal_fast[k]
            total += entry.real * coordinate.real - entry.imag * coordinate.imag
        out[i] = total
