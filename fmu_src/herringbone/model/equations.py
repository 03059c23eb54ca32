"""The equations of motion of the assembled gear train (docs/model.md section 5), compiled.

This is the one home of the dynamic equations: GearTrainModel (model/assembly.py) assembles the
arrays of a `System` from the scene's elements and calls these kernels, and every integrator,
the scipy reference and the FMU's own, evaluates them.

State: [y, ẏ] in the relative coordinates of model/assembly.py (y_i = q_i − r_i·φp, y_pinion =
φp − the start of the contact set), in SI units per coordinate (rad or m, rad/s or m/s). Every
element k deforms by δ_k = g̃_k·y (+ its lead error), g̃ being its row with the pinion entry
zeroed (no element deforms under the rigid rotation), and pushes back with
F_k = c_k·δ_k + h_k·δ̇_k; then M·q̈ = f_ext − Σ g_k·F_k.

Contact points come as a table, one column a point, rows as named by the constants below; each
entry is linear in the axial travel v·y_pinion (m) of the points since the set began
(model/mesh.py). A kernel takes the table with `count`, the number of its columns in use, and
where it asks for `loaded`, one entry a point: 1.0 where the point carries load in the current
segment, 0.0 where not (integrate/compiled/walk.py decides).
"""
from __future__ import annotations

from enum import IntEnum
from typing import Annotated, NamedTuple, get_origin, get_type_hints

import numpy as np
from numba import njit

from ..compiling.counting import COUNTED

# rows of a contact-point table: HALF 0 (left) or 1 (right); stiffness (N/m), lever arm (m) and
# lead error (m) each as its value where the set began plus its slope per m of axial travel
HALF, STIFFNESS0, STIFFNESS_SLOPE, LEVER_ARM0, LEVER_ARM_SLOPE, LEAD_ERROR0, LEAD_ERROR_SLOPE \
    = range(7)
POINT_FIELDS = 7

# layout of the vector `outputs` fills (N/m, N, a count, m); the element forces follow, then the
# speeds
K_MESH, K_MESH_LEFT, K_MESH_RIGHT, F_MESH, F_MESH_LEFT, F_MESH_RIGHT, N_CONTACTS, DTE \
    = range(8)
FIRST_ELEMENT_FORCE = 8


class Event(IntEnum):
    """The events that end a segment, numbered alike by both integrators (each locates them by
    its own rule: integrate/segments.py for the reference, integrate/compiled/walk.py for the
    FMU's)."""

    PHASE_END = 0  # φp reaches the end of the contact set's interval: the next set follows
    PHASE_START = 1  # φp falls back to the interval's start: the previous set follows
    CONTACT = 2  # CONTACT + i: point i's approach δ + η·δ̇ crosses zero (with contact loss)


class PeriodTable(NamedTuple):
    """Every contact set of one mesh period, as the compiled kernels take them
    (model/mesh.py's `period_table`): the sets of other periods differ only in where they
    start."""

    lengths: np.ndarray  # per contact interval: its length in φp, rad
    counts: np.ndarray  # per interval: its number of points
    tables: np.ndarray  # per interval: its point table, padded with zero columns to the widest


class Packed(NamedTuple):
    """How an array field of `System` is packed: its entries' type (float: the floats buffer,
    int: the ints buffer) and its shape in named sizes, each the same wherever it appears:
    "coordinates" (the generalized coordinates), "elements" (the shafts and bearings) and
    "entries" (the nonzero coupling entries)."""

    dtype: type
    shape: tuple[str, ...]


class System(NamedTuple):
    """The assembled arrays of a gear train (built by GearTrainModel). Units: SI throughout, per
    coordinate (an angle's row in rad and N·m, a displacement's in m and N).

    The annotations are also the layout `pack_system` and `unpack_system` follow: an array's
    `Packed` says its buffer and shape; a scalar goes to the floats if a float, to the ints if
    an int or a bool (0 or 1)."""

    pinion: int  # index of the pinion angle among the coordinates
    wheel: int  # index of the wheel angle
    mass: Annotated[np.ndarray, Packed(float, ("coordinates",))]  # diagonal of M
    rigid_rotation: Annotated[np.ndarray, Packed(float, ("coordinates",))]  # r
    # g̃ of the shafts and bearings, one row each
    element_rows_relative: Annotated[np.ndarray, Packed(float, ("elements", "coordinates"))]
    element_stiffness: Annotated[np.ndarray, Packed(float, ("elements",))]  # c
    element_damping: Annotated[np.ndarray, Packed(float, ("elements",))]  # h
    # ÿ = P·(f_ext − Σ g·F) with P = (I − r̃·e_pinionᵀ)·M⁻¹, r̃ = r with its pinion entry
    # zeroed; the terms that do not depend on the contact set are assembled once:
    motor_acceleration: Annotated[np.ndarray, Packed(float, ("coordinates",))]  # P·(M_motor's)
    load_acceleration: Annotated[np.ndarray, Packed(float, ("coordinates",))]  # P·(M_load's)
    # −P·Σ g·c·g̃ (acting on y) and −P·Σ g·h·g̃ (acting on ẏ) of the shafts and bearings, as
    # their nonzero entries (a fifth of the matrix for the full train): row, column, values
    coupling_row: Annotated[np.ndarray, Packed(int, ("entries",))]
    coupling_column: Annotated[np.ndarray, Packed(int, ("entries",))]
    elastic_acceleration: Annotated[np.ndarray, Packed(float, ("entries",))]
    damping_acceleration: Annotated[np.ndarray, Packed(float, ("entries",))]
    # P·base, P·tilt: a point's row is base + ζ·tilt
    contact_base_acceleration: Annotated[np.ndarray, Packed(float, ("coordinates",))]
    contact_tilt_acceleration: Annotated[np.ndarray, Packed(float, ("coordinates",))]
    # g̃ of the base and tilt parts
    contact_row_base_relative: Annotated[np.ndarray, Packed(float, ("coordinates",))]
    contact_row_tilt_relative: Annotated[np.ndarray, Packed(float, ("coordinates",))]
    mesh_damping_factor: float  # η (s): a point's damping is η times its stiffness
    axial_travel_per_radian: float  # v = Rp·cot β (m/rad)
    radius_wheel: float  # Rw (m)
    contact_loss: bool  # whether a point whose approach turns negative lifts off


def _packing() -> tuple[Packed, ...]:
    """Every field's `Packed`, in System's order, read from System's annotations (a scalar's
    shape is ())."""
    hints = get_type_hints(System, include_extras=True)
    packing = []
    for name in System._fields:
        hint = hints[name]
        if get_origin(hint) is Annotated:
            packing.append(hint.__metadata__[0])
        else:
            packing.append(Packed(int if hint is bool else hint, ()))
    return tuple(packing)


PACKING = _packing()
# The ints buffer opens with a header, FIELD_HEADER entries a field (where the field starts in
# its buffer, its rows and its columns; 1 and 1 for a scalar, n and 1 for a vector); the ints
# fields follow it.
FIELD_HEADER = 3
HEADER = FIELD_HEADER * len(PACKING)


def pack_system(system: System) -> tuple[np.ndarray, np.ndarray]:
    """The System as two flat arrays, floats (float64) and ints (int64), that `unpack_system`
    takes apart in compiled code: numba types each of a call's arguments at every call, and the
    21 fields take it 1 µs, two arrays 0.05 µs. Laid out as System's annotations say (see
    `Packed`), each field's place and shape in the ints' header. Raises ValueError if a field's
    shape does not match its declaration, or a named size differs between two fields."""
    sizes: dict[str, int] = {}
    parts: dict[type, list[np.ndarray]] = {float: [], int: []}
    used = {float: 0, int: HEADER}
    header = np.empty(HEADER, dtype=np.int64)
    for k, (name, value, packed) in enumerate(zip(System._fields, system, PACKING)):
        array = np.asarray(value, dtype=np.float64 if packed.dtype is float else np.int64)
        if array.ndim != len(packed.shape):
            raise ValueError(f"System.{name} has shape {array.shape}, declared "
                             f"{packed.shape}")
        for size, length in zip(packed.shape, array.shape):
            if sizes.setdefault(size, length) != length:
                raise ValueError(f"System.{name} has {length} {size}, another field "
                                 f"{sizes[size]}")
        rows, columns = (*array.shape, 1, 1)[:2]
        header[FIELD_HEADER * k:FIELD_HEADER * (k + 1)] = used[packed.dtype], rows, columns
        parts[packed.dtype].append(array.ravel())
        used[packed.dtype] += array.size
    floats = np.concatenate(parts[float]) if parts[float] else np.empty(0)
    ints = np.concatenate([header, *parts[int]])
    return floats, ints


# unpack_system's readers: field k of System (its index in System._fields) out of the buffer
# that PACKING gives it, as a view
@njit(cache=True, error_model="numpy", inline="always")
def _scalar(buffer, ints, k):
    return buffer[ints[FIELD_HEADER * k]]


@njit(cache=True, error_model="numpy", inline="always")
def _vector(buffer, ints, k):
    start, rows = ints[FIELD_HEADER * k], ints[FIELD_HEADER * k + 1]
    return buffer[start:start + rows]


@njit(cache=True, error_model="numpy", inline="always")
def _matrix(buffer, ints, k):
    start, rows, columns = (ints[FIELD_HEADER * k], ints[FIELD_HEADER * k + 1],
                            ints[FIELD_HEADER * k + 2])
    return buffer[start:start + rows * columns].reshape((rows, columns))


@njit(**COUNTED)
def unpack_system(floats, ints):
    """pack_system's inverse: a System whose arrays are views of the two buffers. Argument k
    of System reads field k with the reader of its shape (scalar, vector, matrix) from its
    buffer (PACKING); test_packed_system_unpacks_to_the_same_arrays holds the two together."""
    return System(
        _scalar(ints, ints, 0),  # pinion
        _scalar(ints, ints, 1),  # wheel
        _vector(floats, ints, 2),  # mass
        _vector(floats, ints, 3),  # rigid_rotation
        _matrix(floats, ints, 4),  # element_rows_relative
        _vector(floats, ints, 5),  # element_stiffness
        _vector(floats, ints, 6),  # element_damping
        _vector(floats, ints, 7),  # motor_acceleration
        _vector(floats, ints, 8),  # load_acceleration
        _vector(ints, ints, 9),  # coupling_row
        _vector(ints, ints, 10),  # coupling_column
        _vector(floats, ints, 11),  # elastic_acceleration
        _vector(floats, ints, 12),  # damping_acceleration
        _vector(floats, ints, 13),  # contact_base_acceleration
        _vector(floats, ints, 14),  # contact_tilt_acceleration
        _vector(floats, ints, 15),  # contact_row_base_relative
        _vector(floats, ints, 16),  # contact_row_tilt_relative
        _scalar(floats, ints, 17),  # mesh_damping_factor
        _scalar(floats, ints, 18),  # axial_travel_per_radian
        _scalar(floats, ints, 19),  # radius_wheel
        _scalar(ints, ints, 20) != 0)  # contact_loss


@njit(cache=True, error_model="numpy", inline="always")
def point_at(points, i, travel):
    """Stiffness c (N/m), lever arm ζ (m) and lead error e (m) of point i of the table `points`
    after the axial travel `travel` (m) since its set began."""
    return (points[STIFFNESS0, i] + points[STIFFNESS_SLOPE, i] * travel,
            points[LEVER_ARM0, i] + points[LEVER_ARM_SLOPE, i] * travel,
            points[LEAD_ERROR0, i] + points[LEAD_ERROR_SLOPE, i] * travel)


@njit(cache=True, error_model="numpy", inline="always")
def contact_motion(system, state):
    """g̃·y and g̃·ẏ of the base and tilt parts of a contact row (m, m/s per unit lever arm
    for the tilt), and the axial travel (m)."""
    n = system.mass.shape[0]
    base = tilt = base_rate = tilt_rate = 0.0
    for j in range(n):
        base += system.contact_row_base_relative[j] * state[j]
        tilt += system.contact_row_tilt_relative[j] * state[j]
        base_rate += system.contact_row_base_relative[j] * state[n + j]
        tilt_rate += system.contact_row_tilt_relative[j] * state[n + j]
    return base, tilt, base_rate, tilt_rate, system.axial_travel_per_radian * state[system.pinion]


@njit(cache=True, error_model="numpy", inline="always")
def point_approach(system, motion, lever_arm, lead_error):
    """δ + η·δ̇ (m) of a point with this lever arm (m) and lead error (m), from
    contact_motion's sums: its load per unit stiffness (the point's force, N, is its stiffness
    times this)."""
    base, tilt, base_rate, tilt_rate, _ = motion
    return (base + lever_arm * tilt + lead_error
            + system.mesh_damping_factor * (base_rate + lever_arm * tilt_rate))


@njit(**COUNTED)
def point_geometry(system, points, count, pinion_travel_angle):
    """Stiffness (N/m), lever arm (m) and lead error (m) of the first `count` points of the
    table `points`, as three new arrays, once the pinion has turned `pinion_travel_angle` (rad)
    since the set began."""
    travel = system.axial_travel_per_radian * pinion_travel_angle
    stiffness, lever_arm, lead_error = np.empty(count), np.empty(count), np.empty(count)
    for i in range(count):
        stiffness[i], lever_arm[i], lead_error[i] = point_at(points, i, travel)
    return stiffness, lever_arm, lead_error


# inlined: walk.py evaluates it at every step, where a call's reference counting costs more
@njit(cache=True, error_model="numpy", inline="always")
def approaches(system, points, count, state, out):
    """out[i] = δ + η·δ̇ (m) of point i < count at `state`: its load per unit stiffness. A
    point is loaded while this is positive, even where its stiffness ramps from zero."""
    motion = contact_motion(system, state)
    travel = motion[4]
    for i in range(count):
        _, lever_arm, lead_error = point_at(points, i, travel)
        out[i] = point_approach(system, motion, lever_arm, lead_error)


# inlined: walk.py evaluates it at every step where contact can be lost
@njit(cache=True, error_model="numpy", inline="always")
def approach_rates(system, points, count, state, rate, out):
    """out[i] = d/dt (δ + η·δ̇) (m/s) of point i < count, from the state and its derivative
    `rate` (as `derivative` writes it): with the values of `approaches` at both ends of a step,
    it shows a point that lifts off and lands again within the step (walk.py)."""
    _, tilt, _, tilt_rate, travel = contact_motion(system, state)
    # the same sums over the derivative: g̃·ẏ and g̃·ÿ of the base and tilt parts
    base_rate, _, base_acceleration, tilt_acceleration, _ = contact_motion(system, rate)
    travel_rate = system.axial_travel_per_radian * rate[system.pinion]
    eta = system.mesh_damping_factor
    for i in range(count):
        _, lever_arm, _ = point_at(points, i, travel)
        out[i] = (base_rate + lever_arm * tilt_rate
                  + eta * (base_acceleration + lever_arm * tilt_acceleration)
                  + travel_rate * (points[LEVER_ARM_SLOPE, i] * (tilt + eta * tilt_rate)
                                   + points[LEAD_ERROR_SLOPE, i]))


@njit(cache=True, error_model="numpy")
def element_force(system, element, state):
    """c·δ + h·δ̇ of shaft or bearing `element` (its index among the System's element rows)
    at `state`: its force (N) or, for a torsional element, its torque (N·m)."""
    n = system.mass.shape[0]
    deformation = rate = 0.0
    for j in range(n):
        deformation += system.element_rows_relative[element, j] * state[j]
        rate += system.element_rows_relative[element, j] * state[n + j]
    return (system.element_stiffness[element] * deformation
            + system.element_damping[element] * rate)


@njit(cache=True, error_model="numpy", inline="always")
def derivative(system, points, count, loaded, motor_torque, load_torque, state, out):
    """out = d(state)/dt = [ẏ, ÿ] with the contact set (the first `count` points of `points`)
    and its loaded points (loaded[i] = 1.0) fixed, the motor driving with `motor_torque` and the
    load resisting with `load_torque` (N·m). `out` must not be `state`."""
    n = system.mass.shape[0]
    motion = contact_motion(system, state)
    travel = motion[4]
    total = moment = 0.0  # Σ F and Σ ζ·F of the points
    for i in range(count):
        if loaded[i] != 0.0:
            stiffness, lever_arm, lead_error = point_at(points, i, travel)
            force = stiffness * point_approach(system, motion, lever_arm, lead_error)
            total += force
            moment += lever_arm * force
    for j in range(n):
        out[n + j] = (motor_torque * system.motor_acceleration[j]
                      - load_torque * system.load_acceleration[j]
                      - total * system.contact_base_acceleration[j]
                      - moment * system.contact_tilt_acceleration[j])
        out[j] = state[n + j]
    for entry in range(system.coupling_row.shape[0]):
        k = system.coupling_column[entry]
        out[n + system.coupling_row[entry]] += (system.elastic_acceleration[entry] * state[k]
                                                + system.damping_acceleration[entry]
                                                * state[n + k])


@njit(**COUNTED)
def packed_derivative(floats, ints, points, count, loaded, motor_torque, load_torque, state,
                      out):
    """`derivative` of the System that pack_system gave as (floats, ints): the entry for callers
    from Python, which numba then types by nine plain arguments where a System's twenty-one
    arrays cost it 15 µs a call (the scipy reference calls it at every stage of every step)."""
    derivative(unpack_system(floats, ints), points, count, loaded, motor_torque, load_torque,
               state, out)

@njit(**COUNTED)
def approaches_from_sums(points, count, base, tilt, travel, out):
    """out[i, j] = B_j + e0_i + ζ0_i·T_j + s_j·(ζ1_i·T_j + e1_i) (m): the approach of point
    i < count of the table `points` at state j, from that state's sums B = g_b·(y + η·ẏ) and
    T = g_t·(y + η·ẏ) and its axial travel s (GearTrainModel.point_approaches, which forms
    them by one product of numpy's: the arithmetic here is numpy's, term by term)."""
    for i in range(count):
        lead_error, lever_arm = points[LEAD_ERROR0, i], points[LEVER_ARM0, i]
        arm_slope, error_slope = points[LEVER_ARM_SLOPE, i], points[LEAD_ERROR_SLOPE, i]
        for j in range(base.shape[0]):
            out[i, j] = (base[j] + lead_error + lever_arm * tilt[j]
                         + travel[j] * (arm_slope * tilt[j] + error_slope))


@njit(**COUNTED)
def outputs(system, points, count, loaded, state, out):
    """docs/model.md section 7 into `out`, laid out as the constants above say: mesh stiffness
    (N/m) and force (N), in all and per half, n_contacts (loaded points of nonzero stiffness),
    dte (m), then the shaft and bearing forces (N or N·m, System's element order), then the
    speeds of the coordinates (rad/s or m/s, absolute: the rigid rotation added back). `out`
    holds FIRST_ELEMENT_FORCE + elements + coordinates entries."""
    n = system.mass.shape[0]
    out[:FIRST_ELEMENT_FORCE] = 0.0
    motion = contact_motion(system, state)
    travel = motion[4]
    for i in range(count):
        if loaded[i] != 0.0:
            stiffness, lever_arm, lead_error = point_at(points, i, travel)
            force = stiffness * point_approach(system, motion, lever_arm, lead_error)
            side = K_MESH_LEFT if points[HALF, i] == 0.0 else K_MESH_RIGHT
            out[K_MESH] += stiffness
            out[side] += stiffness
            out[F_MESH] += force
            out[side + F_MESH - K_MESH] += force
            if stiffness > 0.0:
                out[N_CONTACTS] += 1.0
    # Rp·φp − Rw·φw: the rigid rotation cancels (Rp = Rw/u), leaving −Rw·(φw − φp/u)
    out[DTE] = -system.radius_wheel * state[system.wheel]
    elements = system.element_stiffness.shape[0]
    for element in range(elements):
        out[FIRST_ELEMENT_FORCE + element] = element_force(system, element, state)
    pinion_speed = state[n + system.pinion]
    for j in range(n):
        speed = pinion_speed if j == system.pinion else (
            state[n + j] + system.rigid_rotation[j] * pinion_speed)
        out[FIRST_ELEMENT_FORCE + elements + j] = speed
