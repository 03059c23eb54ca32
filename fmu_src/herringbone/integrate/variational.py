"""The sensitivity of a run to its start: the variational equations through the segments, with
the saltation of the sensitivities at every event (compiled/variational.py).

`VariationalFlow(model, max_step).run(position, duration, torques, directions)` integrates the
state from `position` for `duration` seconds together with Φ = ∂x(duration)/∂x(0)·directions,
the derivative of the flow along each column of `directions`. It is the derivative of the
continuous flow (to the order-8 integration's error at the step it is given), not of one
integrator's discrete map: the steps are fixed, the events located to rounding, and each event
adds its saltation jump. The state it carries is its own integration's, within the step's
accuracy of any other integrator's; analysis/steady_state.py takes the monodromy of the period
map from it (docs/monodromy.md).
"""
from __future__ import annotations

import functools

import numpy as np

from ..model.assembly import GearTrainModel
from .compiled import dop853, variational
from .contract import IntegrationError, Position

# DOP853's error in a mode's eigenvalue, |ln R(h·λ)/h − λ|, is about ERROR_CONSTANT·|λ|⁹·h⁸
# (order 8; `error_constant` measures it where |h·λ| = 1, the largest over directions)
ERROR_CONSTANT_AT = 1.0

FAILURES = {variational.Status.TOO_MANY_EVENTS: "events without end (chattering contact)",
            variational.Status.NOT_FINITE: "the state is no longer finite"}


@functools.cache
def error_constant() -> float:
    """C of DOP853's eigenvalue error C·|λ|⁹·h⁸, the largest over the left half-plane's
    directions at |h·λ| = ERROR_CONSTANT_AT (above it where the error grows faster)."""
    z = ERROR_CONSTANT_AT * np.exp(1j * np.linspace(0.5 * np.pi, 1.5 * np.pi, 181))
    return float(np.abs(np.log(dop853.stability_function(z)) - z).max()
                 / ERROR_CONSTANT_AT ** 9)


def multiplier_step(modes: np.ndarray, duration: float, error: float) -> float:
    """The longest fixed DOP853 step (s) that puts each mode λ's multiplier e^{λ·duration}
    within `error` of its value: its eigenvalue error C·|λ|⁹·h⁸ times duration times
    |e^{λ·duration}| at most `error` (a strongly damped mode's multiplier is small, and so is
    its error). The rigid rotation (λ = 0) is left out; inf where no mode bounds the step (each
    decays so far over `duration` that its multiplier's error cannot reach `error`)."""
    fastest = np.abs(modes).max()
    modes = modes[np.abs(modes) > 1e-6 * fastest]
    # in logarithms: a mode damped by e^{-Re λ·duration} beyond e^709 (a long period at low
    # speed) overflows e^{…} itself, and its bound is then just far above the others'
    log_steps = (np.log(error / (duration * error_constant())) - modes.real * duration
                 - 9.0 * np.log(np.abs(modes))) / 8.0
    least = float(log_steps.min())
    return float(np.exp(least)) if least < np.log(np.finfo(float).max) else np.inf


class VariationalFlow:
    """The flow of one model and its sensitivity, by fixed steps of at most `max_step` (s)."""

    def __init__(self, model: GearTrainModel, max_step: float):
        if not max_step > 0.0:
            raise ValueError(f"max_step is {max_step!r}; allowed: > 0 s")
        self.model = model
        self.max_step = float(max_step)
        self.mesh = model.mesh.period_table()
        self.system_arrays = model.packed_system
        self.width = self.mesh[2].shape[2]  # the widest set's points

    def run(self, position: Position, duration: float, torques: tuple[float, float],
            directions: np.ndarray, max_step: float | None = None):
        """(state, sensitivity, contact set) after `duration` s from `position` with the
        torques (N·m) held: the state [y, ẏ] there, ∂state/∂(start)·directions (the state's
        size by the directions' count), and the contact set it ends in; steps of at most
        `max_step` (s; None: the flow's). Raises IntegrationError where the run cannot go
        on."""
        contact_set = position.segment.contact_set
        loaded = np.zeros(self.width)
        loaded[:len(contact_set)] = position.segment.loaded
        status, state, sensitivity, interval, cycle, _, _ = variational.flow_sensitivity(
            *self.system_arrays, self.mesh, int(contact_set.index), int(contact_set.cycle),
            loaded, np.asarray(position.state, dtype=float), float(duration),
            (float(torques[0]), float(torques[1])),
            self.max_step if max_step is None else min(self.max_step, float(max_step)),
            np.ascontiguousarray(directions, dtype=float))
        if status != variational.Status.OK:
            raise IntegrationError(f"variational run failed: "
                                   f"{FAILURES[variational.Status(status)]}")
        return state, sensitivity, self.model.mesh.contact_set(int(cycle), int(interval))
