"""Segments: stretches of a run over which the equations are smooth.

Within a segment the contact set (which points exist, each point's linear piece) and the set of
loaded points are fixed, so the right-hand side is smooth and any integrator keeps its order. A
segment ends where one of its events crosses zero; every integrator (the scipy reference, the
FMU's own) steps to that crossing, then takes the next segment from the compiled
walk.next_segment (here wrapped for scipy's event objects):

- `phase_end`: φp reaches the end of the contact set's phase interval (moving forward);
- `phase_start`: φp falls back below its start (the train turning backwards);
- a point's approach δ + η·δ̇ crosses zero: a loaded point loses contact, a free one regains it
  (only with `contact_loss`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .compiled import walk
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
    contact_set = segment.contact_set
    count = len(contact_set)
    values = np.empty(2 + count)
    walk.event_values(model.system, contact_set.table, count, contact_set.length, state,
                      np.empty(count), values)
    return values if model.contact_loss else values[:2]


def after(model: GearTrainModel, segment: Segment, event: Event,
          state: np.ndarray) -> tuple[Segment, np.ndarray]:
    """The segment that follows an event, and the state re-expressed for it (the compiled
    walk.next_segment, which the FMU's integrator runs too)."""
    lengths, counts, tables = model.mesh.period_table()
    old = segment.contact_set
    state = state.copy()
    loaded = np.zeros(tables.shape[2])
    loaded[:len(old)] = segment.loaded
    number = {"phase_end": 0, "phase_start": 1}.get(event.kind, 2 + event.point)
    interval, cycle = walk.next_segment(model.system, lengths, counts, tables, number,
                                        old.index, old.cycle, state, loaded,
                                        np.empty(tables.shape[2]))
    new = old if (cycle, interval) == (old.cycle, old.index) else model.mesh.contact_set(
        cycle, interval)
    return Segment(new, loaded[:len(new)]), state


def _loaded_by_sign(model, state, contact_set) -> np.ndarray:
    loaded = np.empty(len(contact_set))
    walk.set_loaded_by_sign(model.system, contact_set.table, len(contact_set), state,
                            np.empty(len(contact_set)), loaded)
    return loaded
