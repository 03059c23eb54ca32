"""Segments: stretches of a run over which the equations are smooth.

Within a segment the contact set (which points exist, each point's linear piece) and the set of
loaded points are fixed, so the right-hand side is smooth and any integrator keeps its order. A
segment ends where one of its events crosses zero; every integrator (the scipy reference, the
FMU's own) steps to that crossing, then asks this module for the next segment:

- `phase_end`: φp reaches the end of the contact set's phase interval (moving forward);
- `phase_start`: φp falls back below its start (the train turning backwards);
- a point's approach δ + η·δ̇ crosses zero: a loaded point loses contact, a free one regains it
  (only with `contact_loss`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .mesh import ContactSet
from .model import GearTrainModel


@dataclass(frozen=True)
class Segment:
    contact_set: ContactSet
    loaded: np.ndarray  # 1.0 for the points that carry load, 0.0 for the separated ones


@dataclass(frozen=True)
class Event:
    """A zero crossing that ends a segment: kind "phase_end", "phase_start" or "contact"."""

    kind: str
    direction: float  # +1: fires when the function rises through zero, −1: when it falls
    point: int = -1  # the contact point, for kind "contact"


def start(model: GearTrainModel, pinion_angle: float, motor_torque: float,
          pinion_speed: float) -> tuple[Segment, np.ndarray]:
    """The first segment and state: rigid rotation at `pinion_speed` on the static deflection
    under `motor_torque` (MODEL.md section 6)."""
    contact_set = model.mesh.contact_set(*model.mesh.locate(pinion_angle))
    y = np.zeros(model.size)
    y[model.pinion] = pinion_angle - contact_set.pinion_angle
    y = model.static_deflection(y, contact_set, motor_torque)
    y_rate = np.zeros(model.size)
    y_rate[model.pinion] = pinion_speed
    state = np.concatenate([y, y_rate])
    return Segment(contact_set, _loaded_by_sign(model, state, contact_set)), state


def events(model: GearTrainModel, segment: Segment) -> list[Event]:
    contact_events = [Event("contact", -1.0 if loaded else 1.0, point)
                      for point, loaded in enumerate(segment.loaded)] if model.contact_loss else []
    return [Event("phase_end", 1.0), Event("phase_start", -1.0)] + contact_events


def event_values(model: GearTrainModel, segment: Segment, state: np.ndarray) -> np.ndarray:
    """The event functions of `events(model, segment)`, in that order, at a state."""
    pinion_travel = state[model.pinion]
    values = [pinion_travel - segment.contact_set.length, pinion_travel]
    if model.contact_loss:
        values.extend(model.point_approach(state, segment.contact_set))
    return np.array(values)


def after(model: GearTrainModel, segment: Segment, event: Event,
          state: np.ndarray) -> tuple[Segment, np.ndarray]:
    """The segment that follows an event, and the state re-expressed for it."""
    if event.kind == "contact":
        loaded = segment.loaded.copy()
        loaded[event.point] = 1.0 if event.direction > 0 else 0.0
        return Segment(segment.contact_set, loaded), state
    old = segment.contact_set
    step = 1 if event.kind == "phase_end" else -1
    new = model.mesh.contact_set(old.cycle, old.index + step)
    state = state.copy()
    # lengths, not absolute angles, keep the pinion entry exact however far the train turned
    state[model.pinion] += -old.length if step > 0 else new.length
    return Segment(new, _loaded_by_sign(model, state, new)), state


def _loaded_by_sign(model, state, contact_set) -> np.ndarray:
    if not model.contact_loss:
        return np.ones(len(contact_set))
    return (model.point_approach(state, contact_set) >= 0.0).astype(float)
