"""Segments: stretches of a run over which the equations are smooth, and the scipy reference's
own rule for where they end and what follows.

Within a segment the contact set (which points exist, each point's linear piece) and the set of
loaded points are fixed, so the right-hand side is smooth and any integrator keeps its order. A
segment ends where one of its events crosses zero:

- φp reaches the end of the contact set's phase interval (moving forward): the next set begins;
- φp falls back below its start (the train turning backwards): the previous set begins;
- a point's approach δ + η·δ̇ crosses zero: a loaded point loses contact, a free one regains it
  (only with `contact_loss`).

This module is the reference's event rule, written apart from the compiled integrator's
(compiled/walk.py) so that the two check each other instead of sharing their mistakes; only the
equations of motion and the mesh geometry are common to both. Its rule for what follows an event
looks at nothing but the state: at every segment start each point is loaded iff its approach is
positive, and a point whose approach is at rounding level (`contact_band`) takes the sign of its
approach rate, so that a point that has just lifted off is not loaded again and one that has just
touched is.

Event functions come as `h`, one per event, each firing where it rises through zero (a falling
function enters negated): `phase_end` = φp − length, `phase_start` = −φp, then per point −approach
while it is loaded and +approach while it is not.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model import equations
from ..model.assembly import GearTrainModel
from ..model.equations import Event
from ..model.mesh import ContactSet

# plain ints: numpy asks an index that is an IntEnum for its array interfaces, through the
# enum's own attribute lookup, every time it indexes with one
PHASE_END, PHASE_START, CONTACT = (int(event) for event in
                                   (Event.PHASE_END, Event.PHASE_START, Event.CONTACT))
# An approach within this fraction of the force scale's approach of one point (force scale /
# c_point) is at rounding level: a located crossing leaves about |rate|·(time's rounding), some
# 1e-19 m on the shipped scenes, against a band of 1e-14 m; a point in the band carries at most
# 1e-10 of the force scale.
CONTACT_BAND = 1e-10
# φp within this fraction of an angular pitch of its interval's start or end is on the switch: a
# located crossing leaves φp's rate times the time's rounding (5e-16 rad at 160 rad/s and 3 ms),
# and the shortest interval is 1e-10 of a pitch (mesh.PHASE_TOLERANCE), so the band never holds
# a whole interval.
PHASE_BAND = 1e-12
# what a run that chatters on a contact switch is told, by either integrator
CHATTER_MESSAGE = ("the pinion chatters on a contact switch: the points that enter there take "
                   "load at once (sharp face edges, edge_ramp = 0) and throw it back faster "
                   "than it comes on (at low speed, or with a pinion light beside its mesh "
                   "stiffness: check I_pinion and m_pinion); give edge_ramp > 0 (the contact "
                   "ellipse's half-length along the face, e.g. 1e-3 m), which lets the load "
                   "come on gradually")


def chatter_message(model: GearTrainModel) -> str:
    """CHATTER_MESSAGE, and where the face leaves the pair without a point on it for part of
    each mesh period (K_ε = 0), that the chatter is the teeth meeting again by impacts there,
    which no edge ramp settles (a face of 1 µm chattered at one tolerance and not at another,
    told of low speed and a light pinion)."""
    share = model.mesh.share_without_contact()
    if share == 0.0:
        return CHATTER_MESSAGE
    return (f"{CHATTER_MESSAGE}. Here no point is on the face for {100.0 * share:.3g} % of each "
            "mesh period (K_eps = 0): the teeth meet again by impact at every entry, and a "
            "wider face keeps a point on it")


@dataclass(frozen=True)
class Segment:
    """What holds between two events: a contact set and which of its points carry load."""

    contact_set: ContactSet
    loaded: np.ndarray  # 1.0 for the points that carry load, 0.0 for the separated ones


def start(model: GearTrainModel, pinion_angle: float, motor_torque: float,
          pinion_speed: float) -> tuple[Segment, np.ndarray]:
    """The first segment and state: rigid rotation at `pinion_speed` on the static deflection
    under `motor_torque`, every point whose approach is not negative loaded (the initial
    condition, shared by every integrator), in the contact set the pinion turns into from
    `pinion_angle`: on a switch, turning backwards, the one that ends there."""
    contact_set = model.mesh.contact_set(*model.mesh.locate(pinion_angle,
                                                             backwards=pinion_speed < 0.0))
    y = np.zeros(model.size)
    y[model.pinion] = pinion_angle - contact_set.pinion_angle
    return static_start(model, contact_set, y, motor_torque, pinion_speed)


def static_start(model: GearTrainModel, contact_set: ContactSet, y: np.ndarray,
                 motor_torque: float, pinion_speed: float) -> tuple[Segment, np.ndarray]:
    """`start`'s segment and state in `contact_set` from `y` (its pinion coordinate from the
    set's start): rigid rotation at `pinion_speed` on the static deflection under
    `motor_torque`, every point whose approach is not negative loaded."""
    y = model.static_deflection(y, contact_set, motor_torque)
    y_rate = np.zeros(model.size)
    y_rate[model.pinion] = pinion_speed
    state = np.concatenate([y, y_rate])
    loaded = np.ones(len(contact_set))
    if model.contact_loss:
        loaded = (point_approaches(model, contact_set, state) >= 0.0).astype(float)
    return Segment(contact_set, loaded), state


def contact_band(model: GearTrainModel) -> float:
    """The approach (m) below which a point's contact is decided by its approach rate."""
    return CONTACT_BAND * model.force_scale() / model.mesh.c_point


def point_approaches(model: GearTrainModel, contact_set: ContactSet,
                     state: np.ndarray) -> np.ndarray:
    """δ + η·δ̇ of every point of the set by the compiled equations.approaches (the initial
    condition's, which every integrator starts from)."""
    out = np.empty(len(contact_set))
    equations.approaches(model.system, contact_set.table, len(contact_set), state, out)
    return out


def point_approach_rates(model: GearTrainModel, segment: Segment, state: np.ndarray,
                         torques: tuple[float, float]) -> np.ndarray:
    """d/dt (δ + η·δ̇) of every point of the set, the segment's loaded points carrying load."""
    contact_set = segment.contact_set
    rate = model.derivative(state, contact_set, segment.loaded, *torques)
    out = np.empty(len(contact_set))
    equations.approach_rates(model.system, contact_set.table, len(contact_set), state, rate, out)
    return out


def loaded_points(model: GearTrainModel, contact_set: ContactSet, state: np.ndarray,
                  torques: tuple[float, float]) -> np.ndarray:
    """Which points carry load at a segment start: those whose approach is positive; one within
    the contact band goes by its approach rate (its own force is then nil, so the rate hardly
    depends on its flag: it is taken with the flags by sign)."""
    if not model.contact_loss:
        return np.ones(len(contact_set))
    approach = model.point_approaches(state, contact_set)  # as the event functions read it
    loaded = (approach > 0.0).astype(float)
    at_zero = np.abs(approach) <= contact_band(model)
    if at_zero.any():
        rates = point_approach_rates(model, Segment(contact_set, loaded), state, torques)
        loaded[at_zero] = np.where(rates[at_zero] != 0.0, rates[at_zero] > 0.0,
                                   approach[at_zero] > 0.0)
    return loaded


def neighbour_set(model: GearTrainModel, contact_set: ContactSet, forward: bool,
                  state: np.ndarray) -> ContactSet:
    """The next (or previous) contact set; re-expresses the pinion entry of `state` (in place)
    from the new set's start, by interval lengths rather than absolute angles, so that it stays
    exact however far the train has turned."""
    step = 1 if forward else -1
    new = model.mesh.contact_set(contact_set.cycle, contact_set.index + step)
    state[model.pinion] += -contact_set.length if forward else new.length
    return new


def begin(model: GearTrainModel, contact_set: ContactSet, state: np.ndarray,
          torques: tuple[float, float]) -> Segment:
    """The segment that starts at `state`: the set that holds φp (moving on while φp lies past
    an end of the interval by more than the phase band: an event due at once), its points loaded
    by `loaded_points`. Updates the pinion entry of `state` in place."""
    band = PHASE_BAND * model.geometry.angular_pitch
    for _ in range(len(model.mesh.switch_phases) + 2):
        if state[model.pinion] - contact_set.length > band:
            contact_set = neighbour_set(model, contact_set, True, state)
        elif state[model.pinion] < -band:
            contact_set = neighbour_set(model, contact_set, False, state)
        else:
            break
    return Segment(contact_set, loaded_points(model, contact_set, state, torques))


def event_values(model: GearTrainModel, segment: Segment, states: np.ndarray) -> np.ndarray:
    """h of every event (rows) at every state (columns of `states`, one state a column)."""
    contact_set = segment.contact_set
    phase = states[model.pinion]
    values = np.empty((CONTACT + (len(contact_set) if model.contact_loss else 0),
                       states.shape[1]))
    values[PHASE_END] = phase - contact_set.length
    values[PHASE_START] = -phase
    if model.contact_loss:
        signs = 1.0 - 2.0 * segment.loaded  # loaded: watch −approach rise through zero
        values[CONTACT:] = signs[:, None] * model.point_approaches(states, contact_set)
    return values


def event_value(model: GearTrainModel, segment: Segment, event: int, state: np.ndarray) -> float:
    """h of event number `event` alone at one state (a vector): event_values' entry, computed
    without the others, since a root search reads one event many times."""
    if event == PHASE_END:
        return float(state[model.pinion] - segment.contact_set.length)
    if event == PHASE_START:
        return float(-state[model.pinion])
    point = event - CONTACT
    sign = 1.0 - 2.0 * segment.loaded[point]
    return float(sign * model.point_approach(state, segment.contact_set, point))


def after(model: GearTrainModel, segment: Segment, event: int, state: np.ndarray,
          torques: tuple[float, float]) -> tuple[Segment, np.ndarray]:
    """The segment that follows event number `event` (an `Event`: PHASE_END, PHASE_START or
    CONTACT + point) at `state`, and the state re-expressed for it: a phase event moves to
    the neighbouring set, φp on its side of the switch: the event located the crossing, and
    whatever the located time's rounding leaves on the other side is that rounding, which at
    high speed exceeds PHASE_BAND (1.1e-12 rad of φp at 6.7e5 rad/s and t = 14 ms,
    tests/regression/found_0deb4142a8.toml), where `begin` would send the state back across
    the switch; then every point's flag is decided afresh (`begin`)."""
    state = state.copy()
    contact_set = segment.contact_set
    if event in (PHASE_END, PHASE_START):
        contact_set = neighbour_set(model, contact_set, event == PHASE_END, state)
        state[model.pinion] = (max(state[model.pinion], 0.0) if event == PHASE_END
                               else min(state[model.pinion], contact_set.length))
    return begin(model, contact_set, state, torques), state
