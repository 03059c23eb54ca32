"""A contact set's segment as a linear time-varying system at a held pinion speed, and its
first-order correction in the pinion's departure from it, in plain numpy and scipy: the
measurement behind docs/exponential-variable-segments.md ("A transition at a held speed,
corrected to first order"), not a method of the compiled integrator.

Within a segment (contact set, loaded points and torques fixed) the model's derivative is
linear in the state for a given pinion travel angle s (rad since the set began), which sets
each point's stiffness, lever arm and lead error along the face:

    x' = F(x, s(x)),   F(x, s) = A(s)·x + B(s)·u,   s(x) = x[pinion],

so the segment is bilinear in the state only through s(x). With s replaced by a held motion
s_n(t) (the angle at the set's start moving at a held speed) it is linear, x_L' = F(x_L,
s_n(t)): its transition over the set could be made once per set and speed. What that leaves
is first order in the departure ε = s(x) − s_n(t), about 1e-3 of the set's length:

    x ≈ x_L + δ,   δ' = A(s_n)·δ + ∂F/∂s(x_L, s_n)·(s(x_L) − s_n(t)),

a correction linear in δ and bilinear in the set's start state, so that it too could be
made once per set and speed (a quadratic form of the start state: set_tables); the
second-order term is a cubic one (corrected_end's `order`). The runs here integrate with
scipy's DOP853 at 1e-12; what they measure is how far each lands from the model's own run
over the set, not what a compiled form would cost.

Units: time in s, angles in rad, the state as equations.py lays it out, torques in N·m.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp

from herringbone.integrate.compiled import exponential
from herringbone.model import equations

from . import force_error
from .lawson import INPUTS, Segment, inputs, rate

# rad: the central differences in the pinion angle. [A B] is a cubic in it (Σ k·ζ², k and ζ
# linear in the travel), so a step of 1e-4 of the 0.05 rad a set turns leaves its curvature
# to rounding and its slope within (1e-4/0.05)² of its cubic term
ANGLE_STEP = 1e-4


def system_at(segment: Segment, angle: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of x' = A·x + B·u with every point of the set where the pinion has turned
    `angle` (rad) since the set began: exponential.linear_system on the point table moved to
    that travel (its slopes zeroed, since the values already hold them)."""
    points = segment.points.copy()
    travel = segment.system.axial_travel_per_radian * angle
    for i in range(segment.count):
        moved = equations.point_at(segment.points, i, travel)
        points[equations.STIFFNESS0, i], points[equations.LEVER_ARM0, i], \
            points[equations.LEAD_ERROR0, i] = moved
    for field in (equations.STIFFNESS_SLOPE, equations.LEVER_ARM_SLOPE,
                  equations.LEAD_ERROR_SLOPE):
        points[field, :segment.count] = 0.0
    return exponential.linear_system(segment.system, points, segment.count, segment.loaded)


def augmented_at(segment: Segment, angle: float) -> np.ndarray:
    """[A B] at `angle` (system_at side by side): F(x, s) = [A B]·[x; u]."""
    return np.hstack(system_at(segment, angle))


def in_angle(segment: Segment, angle: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """[A B] at `angle` and its first and second derivatives in the angle (central
    differences of ANGLE_STEP)."""
    here, ahead, behind = (augmented_at(segment, angle + shift)
                           for shift in (0.0, ANGLE_STEP, -ANGLE_STEP))
    return (here, (ahead - behind) / (2.0 * ANGLE_STEP),
            (ahead - 2.0 * here + behind) / ANGLE_STEP ** 2)


def rate_at(segment: Segment, state: np.ndarray, angle: float) -> np.ndarray:
    """F(state, angle): the segment's derivative with its points where `angle` puts them."""
    return augmented_at(segment, angle) @ np.concatenate([state, inputs(segment)])


def held_motion(segment: Segment, state: np.ndarray, pinion: int,
                speed_factor: float = 1.0) -> Callable[[float], float]:
    """s_n(t): the pinion angle of `state` moving on at the train's rigid speed there (its
    angular momentum over its inertia, both referred to the pinion along the rigid rotation
    r), which leaves out the pinion's own vibration; times `speed_factor`, for a table made
    at a speed beside the train's."""
    half = len(state) // 2
    mass, rigid = segment.system.mass, segment.system.rigid_rotation
    pinion_speed = state[half + pinion]
    speeds = state[half:] + rigid * pinion_speed  # q̇ = ẏ + r·φ̇p, but the pinion's own
    speeds[pinion] = pinion_speed
    speed = speed_factor * float(np.sum(mass * rigid * speeds) / np.sum(mass * rigid ** 2))
    return lambda t: state[pinion] + speed * t


def model_end(segment: Segment, state: np.ndarray, span: float,
              absolute: np.ndarray) -> np.ndarray:
    """The model's own run over the set (its derivative, equations.derivative), at 1e-12."""
    return solve_ivp(lambda _t, x: rate(segment, x), (0.0, span), state, method="DOP853",
                     rtol=1e-12, atol=absolute).y[:, -1]


def corrected_end(segment: Segment, state: np.ndarray, span: float, absolute: np.ndarray,
                  nominal: Callable[[float], float], pinion: int, order: int = 1) -> np.ndarray:
    """x_L + δ₁ + … + δ_order at the set's end: the segment with its points moved by
    `nominal` (s_n(t); order 0, x_L alone) and its corrections in the pinion's departure
    ε = s(x_L) − s_n up to `order` (1 or 2), integrated together:

        δ₁' = A·δ₁ + ∂F/∂s(x_L)·ε,
        δ₂' = A·δ₂ + ∂F/∂s(x_L)·δ₁[pinion] + ∂A/∂s·δ₁·ε + ½·∂²F/∂s²(x_L)·ε²,

    A and F at s_n; δ₁ a quadratic form of the set's start [x; u], δ₂ a cubic one."""
    size, held_inputs = len(state), inputs(segment)

    def joint(t, parts):
        held, first, second = parts[:size], parts[size:2 * size], parts[2 * size:]
        matrix, slope, curvature = in_angle(segment, nominal(t))
        start = np.concatenate([held, held_inputs])
        departure = held[pinion] - nominal(t)
        rates = [matrix @ start]
        if order >= 1:
            rates.append(matrix[:, :size] @ first + slope @ start * departure)
        if order >= 2:
            rates.append(matrix[:, :size] @ second + slope @ start * first[pinion]
                         + slope[:, :size] @ first * departure
                         + 0.5 * curvature @ start * departure ** 2)
        return np.concatenate(rates)

    end = solve_ivp(joint, (0.0, span), np.concatenate([state, np.zeros(order * size)]),
                    method="DOP853", rtol=1e-12,
                    atol=np.tile(absolute, order + 1)).y[:, -1]
    return end.reshape(order + 1, size).sum(axis=0)


def force_error_between(model, segment: Segment, state: np.ndarray, other: np.ndarray) -> float:
    """How far the forces of two states of the segment lie apart (force_error: the largest of
    the mesh and bearing forces' differences, over the force scale)."""
    def named(x):
        out = np.empty(model.output_layout_size)
        equations.outputs(segment.system, segment.points, segment.count, segment.loaded, x, out)
        return {name: np.array([value]) for name, value in model.named_outputs(out).items()}

    return force_error(named(state), named(other), model)


def augmented_scales(model) -> np.ndarray:
    """The scales of [x; u]: the state's, the torques' (the force scale on each radius, as
    the exponential method scales its modal forms), 1."""
    force = model.force_scale()
    return np.concatenate([model.state_scales(), [force * model.geometry.radius_pinion,
                                                  force * model.geometry.radius_wheel, 1.0]])


class SetTables(NamedTuple):
    """What a set's held-speed tables would hold, in the scaled [x; u] (each entry over its
    scale, `scales`): the transition over the set at the held motion (N + INPUTS square: the
    inputs held) and the first-order correction as a quadratic form of the start
    (N × (N + INPUTS) × (N + INPUTS))."""

    transition: np.ndarray
    correction: np.ndarray
    scales: np.ndarray


def set_tables(segment: Segment, span: float, nominal: Callable[[float], float],
               pinion: int, scales: np.ndarray) -> SetTables:
    """The tables of one set at one held motion (`nominal`, s_n(t)), independent of any start
    state, in [x; u] scaled by `scales` (the state's scales, the torques', 1): Φ' = Â(s_n)·Φ
    from the identity; and with X = [x; u], x_L = Φ_x·X, the correction's forcing
    ∂F/∂s(x_L, s_n)·(s(x_L) − s_n) = (Â_s·Φ·X)·(ℓ·X), ℓ = Φ's pinion row less s_n on the held
    1, so that Q' = A(s_n)·Q + (Â_s·Φ) ⊗ ℓ from Q = 0 gives δ = Q : X ⊗ X."""
    width, size = len(scales), len(scales) - INPUTS

    scaling = scales[None, :] / scales[:size, None]  # diag(1/σ_x)·[A B]·diag(σ)

    def derivative(t, flat):
        angle = nominal(t)
        transition = flat[:width * width].reshape(width, width)
        form = flat[width * width:].reshape(size, width, width)
        here, slope, _ = (matrix * scaling for matrix in in_angle(segment, angle))
        row = scales[pinion] * transition[pinion]
        row[-1] -= angle
        d_transition = np.zeros((width, width))
        d_transition[:size] = here @ transition
        d_form = (np.einsum("il,ljk->ijk", here[:, :size], form)
                  + np.einsum("ij,k->ijk", slope @ transition, row))
        return np.concatenate([d_transition.ravel(), d_form.ravel()])

    start = np.concatenate([np.eye(width).ravel(), np.zeros(size * width * width)])
    end = solve_ivp(derivative, (0.0, span), start, method="DOP853", rtol=1e-11,
                    atol=1e-13).y[:, -1]
    return SetTables(end[:width * width].reshape(width, width),
                     end[width * width:].reshape(size, width, width), scales)


def tabulated_end(tables: SetTables, segment: Segment, state: np.ndarray) -> np.ndarray:
    """The state at the set's end from its tables: Φ_x·X + Q : X ⊗ X, X = [state; u]
    scaled."""
    size = len(state)
    start = np.concatenate([state, inputs(segment)]) / tables.scales
    scaled = (tables.transition @ start)[:size] + np.einsum("ijk,j,k->i", tables.correction,
                                                              start, start)
    return scaled * tables.scales[:size]
