"""The equations of motion of the assembled gear train (docs/model.md section 5), compiled.

This is the one home of the dynamic equations: GearTrainModel (model.py) assembles the arrays
of a `System` from the scene's elements and calls these kernels, and every integrator, the scipy
reference and the FMU's own, evaluates them.

State: [y, ẏ] in the relative coordinates of model.py (y_i = q_i − r_i·φp, y_pinion = φp − the
start of the contact set). Every element k deforms by δ_k = g̃_k·y (+ its lead error), g̃ being
its row with the pinion entry zeroed (no element deforms under the rigid rotation), and pushes
back with F_k = c_k·δ_k + h_k·δ̇_k; then M·q̈ = f_ext − Σ g_k·F_k.

Contact points come as a table, one column a point, rows as named by the constants below; each
entry is linear in the axial travel v·y_pinion of the points since the set began (mesh.py).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

# rows of a contact-point table
HALF, STIFFNESS0, STIFFNESS_SLOPE, LEVER_ARM0, LEVER_ARM_SLOPE, LEAD_ERROR0, LEAD_ERROR_SLOPE \
    = range(7)
POINT_FIELDS = 7

# layout of the vector `outputs` fills; the element forces follow, then the speeds
K_MESH, K_MESH_LEFT, K_MESH_RIGHT, F_MESH, F_MESH_LEFT, F_MESH_RIGHT, N_CONTACTS, DTE \
    = range(8)
FIRST_ELEMENT_FORCE = 8


class System(NamedTuple):
    """The assembled arrays of a gear train (built by GearTrainModel)."""

    pinion: int  # index of the pinion angle among the coordinates
    wheel: int
    mass: np.ndarray  # diagonal of M
    rigid_rotation: np.ndarray  # r
    element_rows_relative: np.ndarray  # g̃ of the shafts and bearings, one row each
    element_stiffness: np.ndarray
    element_damping: np.ndarray
    # ÿ = P·(f_ext − Σ g·F) with P = (I − r̃·e_pinionᵀ)·M⁻¹, r̃ = r with its pinion entry
    # zeroed; the terms that do not depend on the contact set are assembled once:
    motor_acceleration: np.ndarray  # P·(where M_motor acts)
    load_acceleration: np.ndarray  # P·(where M_load resists)
    # −P·Σ g·c·g̃ (acting on y) and −P·Σ g·h·g̃ (acting on ẏ) of the shafts and bearings, as
    # their nonzero entries (a fifth of the matrix for the full train): row, column, values
    coupling_row: np.ndarray
    coupling_column: np.ndarray
    elastic_acceleration: np.ndarray
    damping_acceleration: np.ndarray
    contact_base_acceleration: np.ndarray  # P·base, P·tilt: a point's row is base + ζ·tilt
    contact_tilt_acceleration: np.ndarray
    contact_row_base_relative: np.ndarray
    contact_row_tilt_relative: np.ndarray
    mesh_damping_factor: float  # η: a point's damping is η times its stiffness
    axial_travel_per_radian: float  # v = Rp·cot β
    radius_wheel: float
    contact_loss: bool


def pack_system(system: System) -> tuple[np.ndarray, np.ndarray]:
    """The System as two flat arrays, floats and ints, that `unpack_system` takes apart in
    compiled code: numba types each of a call's arguments at every call, and the 21 fields
    take it 1 µs, two arrays 0.05 µs. Laid out by field order, with the sizes first."""
    sizes = (len(system.mass), len(system.element_stiffness), len(system.coupling_row))
    floats = np.concatenate([
        system.mass, system.rigid_rotation, system.element_rows_relative.ravel(),
        system.element_stiffness, system.element_damping, system.motor_acceleration,
        system.load_acceleration, system.elastic_acceleration, system.damping_acceleration,
        system.contact_base_acceleration, system.contact_tilt_acceleration,
        system.contact_row_base_relative, system.contact_row_tilt_relative,
        [system.mesh_damping_factor, system.axial_travel_per_radian, system.radius_wheel]])
    ints = np.concatenate([[*sizes, system.pinion, system.wheel, system.contact_loss],
                           system.coupling_row, system.coupling_column]).astype(np.int64)
    return floats, ints


@njit(cache=True, error_model="numpy")
def unpack_system(floats, ints):
    """pack_system's inverse: a System whose arrays are views of the two."""
    coordinates, elements, entries = ints[0], ints[1], ints[2]
    row, column = ints[6:6 + entries], ints[6 + entries:6 + 2 * entries]
    at = np.cumsum(np.array([0, coordinates, coordinates, elements * coordinates, elements,
                             elements, coordinates, coordinates, entries, entries, coordinates,
                             coordinates, coordinates, coordinates]))
    return System(ints[3], ints[4], floats[at[0]:at[1]], floats[at[1]:at[2]],
                  floats[at[2]:at[3]].reshape((elements, coordinates)), floats[at[3]:at[4]],
                  floats[at[4]:at[5]], floats[at[5]:at[6]], floats[at[6]:at[7]], row, column,
                  floats[at[7]:at[8]], floats[at[8]:at[9]], floats[at[9]:at[10]],
                  floats[at[10]:at[11]], floats[at[11]:at[12]], floats[at[12]:at[13]],
                  floats[at[13]], floats[at[13] + 1], floats[at[13] + 2], ints[5] != 0)


@njit(cache=True, error_model="numpy", inline="always")
def point_at(points, i, travel):
    """Stiffness c, lever arm ζ and lead error e of point i after the axial travel."""
    return (points[STIFFNESS0, i] + points[STIFFNESS_SLOPE, i] * travel,
            points[LEVER_ARM0, i] + points[LEVER_ARM_SLOPE, i] * travel,
            points[LEAD_ERROR0, i] + points[LEAD_ERROR_SLOPE, i] * travel)


@njit(cache=True, error_model="numpy", inline="always")
def _contact_motion(system, state):
    """g̃·y and g̃·ẏ of the base and tilt parts of a contact row, and the axial travel."""
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
    """δ + η·δ̇ of a point with this lever arm and lead error, from _contact_motion's sums: its
    load per unit stiffness (the point's force is its stiffness times this)."""
    base, tilt, base_rate, tilt_rate, _ = motion
    return (base + lever_arm * tilt + lead_error
            + system.mesh_damping_factor * (base_rate + lever_arm * tilt_rate))


@njit(cache=True, error_model="numpy")
def point_geometry(system, points, count, pinion_travel_angle):
    """Stiffness, lever arm and lead error of every point of a set, as arrays."""
    travel = system.axial_travel_per_radian * pinion_travel_angle
    stiffness, lever_arm, lead_error = np.empty(count), np.empty(count), np.empty(count)
    for i in range(count):
        stiffness[i], lever_arm[i], lead_error[i] = point_at(points, i, travel)
    return stiffness, lever_arm, lead_error


# inlined: walk.py evaluates it at every step, where a call's reference counting costs more
@njit(cache=True, error_model="numpy", inline="always")
def approaches(system, points, count, state, out):
    """out[i] = δ + η·δ̇ of point i: its load per unit stiffness. A point is loaded while this
    is positive, even where its stiffness ramps from zero."""
    motion = _contact_motion(system, state)
    travel = motion[4]
    for i in range(count):
        _, lever_arm, lead_error = point_at(points, i, travel)
        out[i] = point_approach(system, motion, lever_arm, lead_error)


# inlined: walk.py evaluates it at every step where contact can be lost
@njit(cache=True, error_model="numpy", inline="always")
def approach_rates(system, points, count, state, rate, out):
    """out[i] = d/dt (δ + η·δ̇) of point i, from the state and its derivative `rate`: with the
    values of `approaches` at both ends of a step, it shows a point that lifts off and lands
    again within the step (walk.py)."""
    _, tilt, _, tilt_rate, travel = _contact_motion(system, state)
    # the same sums over the derivative: g̃·ẏ and g̃·ÿ of the base and tilt parts
    base_rate, _, base_acceleration, tilt_acceleration, _ = _contact_motion(system, rate)
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
    """c·Δ + h·Δ̇ of a shaft or bearing."""
    n = system.mass.shape[0]
    deformation = rate = 0.0
    for j in range(n):
        deformation += system.element_rows_relative[element, j] * state[j]
        rate += system.element_rows_relative[element, j] * state[n + j]
    return (system.element_stiffness[element] * deformation
            + system.element_damping[element] * rate)


@njit(cache=True, error_model="numpy", inline="always")
def derivative(system, points, count, loaded, motor_torque, load_torque, state, out):
    """out = d(state)/dt with the contact set and its loaded points (loaded[i] = 1) fixed.
    `out` must not be `state`."""
    n = system.mass.shape[0]
    motion = _contact_motion(system, state)
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


@njit(cache=True, error_model="numpy")
def outputs(system, points, count, loaded, state, out):
    """docs/model.md section 7 into `out`, laid out as the constants above say: mesh stiffness and
    force (both halves), n_contacts, dte, then the shaft and bearing forces, then the speeds."""
    n = system.mass.shape[0]
    out[:FIRST_ELEMENT_FORCE] = 0.0
    motion = _contact_motion(system, state)
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
