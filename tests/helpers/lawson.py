"""A Lawson (integrating-factor) Runge-Kutta integrator for one segment of the gear train, in
plain numpy: the measurement behind docs/exponential-variable-segments.md, not a method of the
compiled integrator.

Within a segment (contact set and loaded points fixed, torques held) write the state with its
held inputs as X = [x; u], u = (motor torque, load torque, 1), and split the derivative as

    X' = Â·X + N(X),   Â = [[A0, B0], [0, 0]],   N(X) = [f(x) − A0·x − B0·u; 0],

f being the model's compiled derivative (equations.derivative). In the interaction picture
v = e^{−Â·t}·X the fast linear part drops out, v' = e^{−Â·t}·N(e^{Â·t}·v), and any Runge-Kutta
pair applied to v keeps its error estimate and step controller; back in X a stage reads

    X_i = e^{Â·c_i·h}·(X_n + h·Σ_j a_ij·K_j),   K_j = e^{−Â·c_j·h}·N(X_j).

Where N vanishes (an exact segment, `exponential.exact_condition`) a step is exact at any h;
where it does not, the step is limited by what N's oscillation at the train's frequencies asks
of the pair. Two choices of Â: the set's linear system frozen where the set begins
(`frozen_form`, what tables per contact set could hold) and the Jacobian at a state
(`linearized_form`, refreshed at every step: the limit of any finer tabulation). The
propagators are scipy's expm: this is about steps, not the cost of one (the compiled cost is
measured apart, benchmarks/exponential_variable.py).

Units: time in s, the state as equations.py lays it out, torques in N·m.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import scipy.linalg
from scipy.integrate._ivp import dop853_coefficients
from scipy.integrate._ivp.rk import RK45

from herringbone.integrate.compiled import exponential
from herringbone.integrate.compiled_stepper import CompiledStepper
from herringbone.integrate.contract import start_position
from herringbone.model.assembly import GearTrainModel
from herringbone.model.equations import derivative

INPUTS = exponential.INPUTS
# Hairer's controller as compiled/dop853.py has it (safety, bounds, β of the stabilized rule)
SAFETY, MIN_FACTOR, MAX_FACTOR, BETA = 0.85, 0.2, 10.0, 0.04


class Tableau(NamedTuple):
    """An explicit Runge-Kutta pair: stages a (s×s), weights b, nodes c, error weights
    (length s + 1, the last on the rate at the step's end), its order (the controller's
    exponent is −1/(order + 1)) and whether the error norm is DOP853's combined one."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    error: np.ndarray
    error3: np.ndarray | None
    order: int


DOP853 = Tableau(dop853_coefficients.A, dop853_coefficients.B,
                 dop853_coefficients.C[:dop853_coefficients.N_STAGES], dop853_coefficients.E5,
                 dop853_coefficients.E3, 7)
DOPRI5 = Tableau(RK45.A, RK45.B, RK45.C, RK45.E, None, 4)


class Segment(NamedTuple):
    """One segment of a train: its system (equations.System), the set's point table and
    count, the loaded points (1.0/0.0) and the torques (N·m)."""

    system: object
    points: np.ndarray
    count: int
    loaded: np.ndarray
    torques: tuple[float, float]


class Result(NamedTuple):
    """A run over a segment: the state at its end, accepted and rejected steps."""

    state: np.ndarray
    accepted: int
    rejected: int


def rate(segment: Segment, state: np.ndarray) -> np.ndarray:
    """The model's derivative of `state` in `segment`."""
    out = np.empty_like(state)
    derivative(segment.system, segment.points, segment.count, segment.loaded,
               segment.torques[0], segment.torques[1], state, out)
    return out


def inputs(segment: Segment) -> np.ndarray:
    """u = (motor torque, load torque, 1)."""
    return np.array([segment.torques[0], segment.torques[1], 1.0])


def frozen_form(segment: Segment) -> np.ndarray:
    """Â of the set's linear system frozen where the set begins (exponential.linear_system,
    the form its tables would hold), (N + INPUTS)²."""
    a, b = exponential.linear_system(segment.system, segment.points, segment.count,
                                     segment.loaded)
    size = a.shape[0]
    augmented = np.zeros((size + INPUTS, size + INPUTS))
    augmented[:size, :size], augmented[:size, size:] = a, b
    return augmented


def linearized_form(segment: Segment, state: np.ndarray, scales: np.ndarray) -> np.ndarray:
    """Â of the linearization at `state`: the Jacobian of f by central differences (steps of
    1e-6 of `scales`, per state entry) and f's remainder there in the column of the held 1."""
    size = state.shape[0]
    jacobian = np.zeros((size, size))
    for j in range(size):
        step = 1e-6 * scales[j]
        up, down = state.copy(), state.copy()
        up[j] += step
        down[j] -= step
        jacobian[:, j] = (rate(segment, up) - rate(segment, down)) / (2.0 * step)
    augmented = np.zeros((size + INPUTS, size + INPUTS))
    augmented[:size, :size] = jacobian
    augmented[:size, size + INPUTS - 1] = rate(segment, state) - jacobian @ state
    return augmented


def frozen(segment: Segment) -> Callable[[np.ndarray], np.ndarray]:
    """The `form` of `integrate` that holds frozen_form(segment) at every step."""
    held = frozen_form(segment)
    return lambda state: held


def linearized(segment: Segment, scales: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """The `form` of `integrate` that linearizes at every step's start (linearized_form)."""
    return lambda state: linearized_form(segment, state, scales)


def integrate(segment: Segment, state: np.ndarray, span: float, absolute: np.ndarray,
              relative: float, h: float, tableau: Tableau = DOP853,
              form: Callable[[np.ndarray], np.ndarray] | None = None,
              max_step: float = math.inf) -> Result:
    """Integrate `segment` from `state` over `span` (s), from the step size h (s), to the
    tolerances (absolute per state entry, relative a number) by `tableau`: plainly where `form`
    is None, else by Lawson's scheme on the Â that form(state at the step's start) gives.
    Error norm and controller as compiled/dop853.py's (scipy's norm for DOPRI5)."""
    time, x = 0.0, state.copy()
    accepted = rejected = 0
    previous, was_rejected = 1e-4, False
    while time < span * (1.0 - 1e-12):
        h = min(h, max_step, span - time)
        new, estimate, estimate3 = _step(segment, x, h, tableau,
                                         None if form is None else form(x))
        norm = _error_norm(x, new, h, estimate, estimate3, absolute, relative)
        if norm <= 1.0:
            time, x, accepted = time + h, new, accepted + 1
            factor = (MAX_FACTOR if norm == 0.0 else SAFETY * norm ** -(
                1.0 / (tableau.order + 1) - 0.2 * BETA) * previous ** BETA)
            factor = min(MAX_FACTOR, max(MIN_FACTOR, factor))
            h *= min(1.0, factor) if was_rejected else factor
            previous, was_rejected = max(norm, 1e-4), False
        else:
            rejected, was_rejected = rejected + 1, True
            h *= max(MIN_FACTOR, SAFETY * norm ** (-1.0 / (tableau.order + 1)))
    return Result(x, accepted, rejected)


def _step(segment, x, h, tableau, augmented):
    """One step of h: the new state and the error estimates (state entries)."""
    size, stages = x.shape[0], len(tableau.b)
    if augmented is None:  # the plain pair
        k = np.zeros((stages + 1, size))
        k[0] = rate(segment, x)
        for i in range(1, stages):
            k[i] = rate(segment, x + h * (tableau.a[i, :i] @ k[:i]))
        new = x + h * (tableau.b @ k[:stages])
        k[stages] = rate(segment, new)
        return new, k.T @ tableau.error, (None if tableau.error3 is None
                                          else k.T @ tableau.error3)
    held = np.concatenate([x, inputs(segment)])
    propagators = {}

    def propagator(tau):
        if tau not in propagators:
            propagators[tau] = scipy.linalg.expm(augmented * tau)
        return propagators[tau]

    def remainder(big):  # N(X)
        out = np.zeros_like(big)
        out[:size] = rate(segment, big[:size]) - augmented[:size] @ big
        return out

    k = np.zeros((stages + 1, held.shape[0]))
    k[0] = remainder(held)
    for i in range(1, stages):
        c = tableau.c[i] * h
        k[i] = propagator(-c) @ remainder(propagator(c) @ (held + h * (tableau.a[i, :i] @ k[:i])))
    whole = propagator(h)
    new = whole @ (held + h * (tableau.b @ k[:stages]))
    k[stages] = propagator(-h) @ remainder(new)
    estimate = (whole @ (k.T @ tableau.error))[:size]
    estimate3 = None if tableau.error3 is None else (whole @ (k.T @ tableau.error3))[:size]
    return new[:size], estimate, estimate3


def _error_norm(x, new, h, estimate, estimate3, absolute, relative):
    """DOP853's combined norm where there is a third-order estimate, else scipy's RMS."""
    scale = absolute + relative * np.maximum(np.abs(x), np.abs(new))
    error5 = float(np.sum((estimate / scale) ** 2))
    if estimate3 is None:
        return abs(h) * math.sqrt(error5 / x.shape[0])
    error3 = float(np.sum((estimate3 / scale) ** 2))
    if error5 == 0.0 and error3 == 0.0:
        return 0.0
    return abs(h) * error5 / math.sqrt((error5 + 0.01 * error3) * x.shape[0])


def segments_after_switches(scene, count: int, warm: float):
    """(model, stepper, [(Segment, start state, span s), ...]) for `count` segments of a
    scene, each from just past the switch that began it (the vibration it set off ringing),
    reached by the compiled DOP853 stepper at tolerance 1e-7 after `warm` s; a segment's span
    is the time its pinion angle takes, at its speed there, to reach the set's end."""
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7, "dop853")
    run = stepper.start(start_position(model, scene.inputs.at(0.0)[0]))
    stepper.run_to(run, warm, scene.inputs.at(0.0))
    found, half = [], len(run.state) // 2
    for _ in range(count):
        place = int(run.place[0])
        while int(run.place[0]) == place:
            stepper.run_to(run, run.time + 2e-6, scene.inputs.at(run.time))
        interval = int(run.place[0])
        points = stepper.tables[interval]
        segment = Segment(model.system, points, int(stepper.counts[interval]),
                          run.loaded.copy(), scene.inputs.at(run.time))
        state = run.state.copy()
        span = ((stepper.lengths[interval] - state[model.pinion])
                / state[half + model.pinion])
        found.append((segment, state, span))
    return model, stepper, found
