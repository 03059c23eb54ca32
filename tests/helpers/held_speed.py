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
made once per set and speed (a quadratic form of the start state). The runs here integrate
both with scipy's DOP853 at 1e-12; what they measure is how far each lands from the model's
own run over the set, not what a compiled form would cost.

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

ANGLE_STEP = 1e-7  # rad: the central difference of ∂F/∂s (F is quadratic in s at most)


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


def rate_at(segment: Segment, state: np.ndarray, angle: float) -> np.ndarray:
    """F(state, angle): the segment's derivative with its points where `angle` puts them."""
    a, b = system_at(segment, angle)
    return a @ state + b @ inputs(segment)


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


def held_end(segment: Segment, state: np.ndarray, span: float, absolute: np.ndarray,
             nominal: Callable[[float], float]) -> np.ndarray:
    """x_L at the set's end: the segment with its points moved by `nominal` (s_n(t))."""
    return solve_ivp(lambda t, x: rate_at(segment, x, nominal(t)), (0.0, span), state,
                     method="DOP853", rtol=1e-12, atol=absolute).y[:, -1]


def corrected_end(segment: Segment, state: np.ndarray, span: float, absolute: np.ndarray,
                  nominal: Callable[[float], float], pinion: int) -> np.ndarray:
    """x_L + δ at the set's end: the held motion's run and its first-order correction in the
    pinion's departure from `nominal`, integrated together."""
    size = len(state)

    def joint(t, both):
        held, correction = both[:size], both[size:]
        angle = nominal(t)
        slope = (rate_at(segment, held, angle + ANGLE_STEP)
                 - rate_at(segment, held, angle - ANGLE_STEP)) / (2.0 * ANGLE_STEP)
        return np.concatenate([rate_at(segment, held, angle),
                               system_at(segment, angle)[0] @ correction
                               + slope * (held[pinion] - angle)])

    end = solve_ivp(joint, (0.0, span), np.concatenate([state, np.zeros(size)]),
                    method="DOP853", rtol=1e-12,
                    atol=np.concatenate([absolute, absolute])).y[:, -1]
    return end[:size] + end[size:]


def second_order_end(segment: Segment, state: np.ndarray, span: float, absolute: np.ndarray,
                     nominal: Callable[[float], float], pinion: int) -> np.ndarray:
    """x_L + δ₁ + δ₂ at the set's end: corrected_end's run with the second-order term in the
    departure ε = s(x_L) − s_n as well (F being a polynomial in s, its derivatives in s by
    central differences),

        δ₂' = A(s_n)·δ₂ + ∂F/∂s(x_L)·δ₁[pinion] + ∂A/∂s·δ₁·ε + ½·∂²F/∂s²(x_L)·ε²,

    a cubic form of the set's start [x; u] where δ₁ is a quadratic one."""
    size, step = len(state), 1e3 * ANGLE_STEP

    def joint(t, three):
        held, first, second = three[:size], three[size:2 * size], three[2 * size:]
        angle = nominal(t)
        here, ahead, behind = (rate_at(segment, held, angle + shift)
                               for shift in (0.0, step, -step))
        slope = (ahead - behind) / (2.0 * step)
        curvature = (ahead - 2.0 * here + behind) / step ** 2
        matrix = system_at(segment, angle)[0]
        matrix_slope = (system_at(segment, angle + step)[0]
                        - system_at(segment, angle - step)[0]) / (2.0 * step)
        departure = held[pinion] - angle
        return np.concatenate([here, matrix @ first + slope * departure,
                               matrix @ second + slope * first[pinion]
                               + matrix_slope @ first * departure
                               + 0.5 * curvature * departure ** 2])

    end = solve_ivp(joint, (0.0, span), np.concatenate([state, np.zeros(2 * size)]),
                    method="DOP853", rtol=1e-12, atol=np.concatenate([absolute] * 3)).y[:, -1]
    return end[:size] + end[size:2 * size] + end[2 * size:]


def force_error_between(model, segment: Segment, state: np.ndarray, other: np.ndarray) -> float:
    """How far the forces of two states of the segment lie apart (force_error: the largest of
    the mesh and bearing forces' differences, over the force scale)."""
    def named(x):
        out = np.empty(model.output_layout_size)
        equations.outputs(segment.system, segment.points, segment.count, segment.loaded, x, out)
        return {name: np.array([value]) for name, value in model.named_outputs(out).items()}

    return force_error(named(state), named(other), model)


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

    def augmented(angle):  # scaled: diag(1/σ_x)·[A B]·diag(σ)
        a, b = system_at(segment, angle)
        return np.block([[a, b]]) * scales[None, :] / scales[:size, None]

    def derivative(t, flat):
        angle = nominal(t)
        transition = flat[:width * width].reshape(width, width)
        form = flat[width * width:].reshape(size, width, width)
        here = augmented(angle)
        slope = (augmented(angle + ANGLE_STEP) - augmented(angle - ANGLE_STEP)) \
            / (2.0 * ANGLE_STEP)
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
