"""Advancing a gear train through its segments with one of scipy's ODE solvers, step by step.

Contract of `ScipyStepper.advance(position, end, torques)`: starting from `position` (time,
state, segment), integrate with the torques held to exactly `end`, integrating each segment on
its own and ending it exactly at its first event (segments.py), so the method keeps its order
across every switch. The result depends only on the position passed in (its step-size hint
included), never on earlier calls: a position saved and restored re-runs identically.

Events are found by this module alone (the compiled integrator has its own rule), on the dense
output of every accepted step: each event function is read at the step's ends and at
INTERIOR_NODES points inside it, so that a function that crosses zero and returns within the
step is seen unless it does so between two nodes; there the cubic through the values and slopes
at the two nodes shows the bump, whose top is then found on the dense output. The earliest
crossing in the event's direction is located by brentq to rounding, and the segment ends there.
The state there, and at every sample time, is then computed by steps of the method from the
start of the step that holds it: the dense output only says when.

Error control (with a `horizon`, as reference_simulate gives it): the tolerance holds for the
forces over the whole run. Every step's error rings on in the train's modes, for the run or for
1/ζ radians, whichever is shorter, and the errors of the steps add up over those radians; the
step tolerance is cut by the radians the train rings (ringing_radians, step_tolerance), which
this module works out from the model's own matrices: with every point loaded and, with contact
loss, with the points loaded that the static deflection loads (a point without load carries no
mesh damping). And an explicit method's step spans at most
STEP_RADIANS of the train's fastest mode, where its error estimate still reads that mode's error.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.integrate
from scipy.optimize import brentq, minimize_scalar

from ..model.assembly import GearTrainModel
from . import segments
from .compiled import reference_events
from .contract import IntegrationError, Position

# consecutive segments without progress before a run is declared stuck (chattering contact)
MAX_STALLED_SEGMENTS = 100
# Phase events in a row that alternate forward and back: the pinion bounces on a switch where the
# entering points take load at once (sharp face edges at low speed). It may get through in the
# end (the sharp-edged low_speed scene did after 2 762 bounces in 1 ms) but the bounces are an
# artefact of the sharp edge, which an edge ramp resolves.
MAX_PHASE_REVERSALS = 1000
# Points inside each step at which the events are read: a step of DOP853 spans at most about a
# third of the fastest period, so an approach that dips below zero and back within it spans
# several nodes, or bulges between two, which the cubic test sees.
INTERIOR_NODES = 7
SLOPE_SPACING = 1e-5  # of a step: the half-spacing of the differences that give the slopes
# Only points whose approach comes this many times its largest change between nodes near zero
# get slopes (and so the bulge test): a smoother one cannot reach zero between two nodes.
NEAR_ZERO = 4.0
# A step spans at most this many radians of the train's fastest mode (|λ|max of the linearized
# train), whatever the error estimate allows: DOP853's estimate is asymptotic, and beyond that it
# can miss a fast mode's error. On light_load_reference_drift (tests/regression) a step of 7.7
# radians of the 9.5e5 rad/s bearing mode passed at a step tolerance of 8e-12 and ended 9e-9 of
# the force scale off, an error the mode's damping took away within 30 µs, which only a sample
# falling there showed (docs/reference-accuracy.md).
STEP_RADIANS = 4.0
EXPLICIT_METHODS = ("DOP853", "RK45", "RK23")  # scipy's; the implicit ones are not held to it
# The debug check of contact forces (check_tension) reads the step at this many points.
TENSION_NODES = 33
# The error of every step rings on in the train's modes until their damping eats it, adding up
# over the radians a mode rings within the run: about 2.5 times the per-step tolerance per radian
# (measured on the undamped and light-load regression scenes, tests/regression). The step
# tolerance is cut so that RINGING_BUDGET radians' worth of error is what remains.
RINGING_BUDGET = 10.0
# scipy raises rtol below 100 ulp to 100 ulp (with a warning): the tightest step tolerance
FINEST_STEP_TOLERANCE = 100 * np.finfo(float).eps
STALL_RESOLUTION = 64 * np.finfo(float).eps  # of the time: a segment this short made no progress
STALL_MESSAGE = ("contact switches without progress. If the pinion sits on a switch, its points "
                 "take load at once (edge_ramp = 0) and throw it back: give edge_ramp > 0 "
                 "(e.g. 1e-3 m)")


@dataclass
class _Step:
    """One accepted step of the solver: its span and dense output."""

    start: float
    end: float
    dense: object  # scipy's DenseOutput: state at a time or at an array of times
    start_state: np.ndarray


class ScipyStepper:
    """Steps the scipy reference (the `Stepper` contract of integrate/contract.py) segment by
    segment, every segment ended exactly at its first event."""
    def __init__(self, model: GearTrainModel, tolerance: float, method: str = "DOP853",
                 max_step: float = np.inf, check_tension: bool = False,
                 horizon: float | None = None):
        """tolerance: the error allowed in the forces over a run of length `horizon`, relative
        to the force scale (GearTrainModel.force_scale); each step is held to
        `step_tolerance(model, tolerance, horizon)` of it, through GearTrainModel.state_scales
        (relative and absolute). horizon: the run's length (s); None: each step is held to
        `tolerance` itself (scipy's own meaning: an error per step, not per run).
        method: a scipy.integrate OdeSolver ("DOP853", "RK45", "Radau", "BDF", "LSODA").
        max_step: the longest step (s); an explicit method's steps are also held to
        STEP_RADIANS of the train's fastest mode.
        check_tension: after every step, read every point's approach at TENSION_NODES points
        of it and raise IntegrationError where a loaded point pulls or a free one penetrates
        by more than the contact band (segments.contact_band): a debug check, for tests."""
        self.model = model
        self.tolerance = tolerance
        self.step_tolerance = (tolerance if horizon is None
                               else step_tolerance(model, tolerance, horizon))
        self.absolute_tolerance = self.step_tolerance * model.state_scales()
        self.method = method
        self.solver_class = getattr(scipy.integrate, method)
        explicit = method in EXPLICIT_METHODS
        self.max_step = min(max_step, STEP_RADIANS / fastest_rate(model)) if explicit \
            else max_step
        self.check_tension = check_tension
        self.fractions = np.linspace(0.0, 1.0, INTERIOR_NODES + 2)
        # The record of what this stepper has met (results never depend on it): segments
        # without a loaded point followed by one with, each a landing of a lifted-off mesh,
        # where a train may amplify every earlier error (global_error.py reads it)
        self.landings = 0

    def advance(self, position: Position, end: float, torques: tuple[float, float],
                sample_times=(), on_sample=None) -> Position:
        """Integrate to `end`; for every t in `sample_times` with position.time <= t < end,
        call on_sample(t, outputs) with the outputs at t."""
        samples = [t for t in sample_times if position.time <= t < end]
        time, hint, state = position.time, position.step_hint, position.state.copy()
        segment = segments.begin(self.model, position.segment.contact_set, state, torques)
        stalled = reversals = 0
        last_phase_event = None
        while time < end:
            reached, state, event, hint = self._integrate_segment(
                time, state, segment, hint, end, torques, samples, on_sample)
            stalled = stalled + 1 if reached - time <= STALL_RESOLUTION * abs(reached) else 0
            if stalled > MAX_STALLED_SEGMENTS:
                raise IntegrationError(f"stuck at t = {reached:.9g} s: {STALL_MESSAGE}")
            if event in (segments.PHASE_END, segments.PHASE_START):
                reversals = reversals + 1 if event != last_phase_event else 0
                last_phase_event = event
                if reversals > MAX_PHASE_REVERSALS:
                    raise IntegrationError(f"stuck at t = {reached:.9g} s: "
                                           f"{segments.chatter_message(self.model)}")
            time = reached
            if event is not None:
                lifted = not segment.loaded.any()
                segment, state = segments.after(self.model, segment, event, state, torques)
                if lifted and segment.loaded.any():
                    self.landings += 1
        return Position(time, state, segment, hint)

    def _integrate_segment(self, time, state, segment, hint, end, torques, samples, on_sample):
        """Step one segment from `time` towards `end` until its first event; returns (time
        reached, state there, the event's number or None, the step size to try next)."""
        model = self.model
        first_step = None if hint is None else min(hint, end - time)
        solver = self._solver(segment, torques, time, state, end, first_step)
        # an event whose function starts a hair above zero (within its band: the rule of
        # segments.py decided which side it starts on) is watched from that value on
        offsets = np.maximum(segments.event_values(model, segment, state[:, None])[:, 0], 0.0)
        while True:
            start_state = solver.y.copy()
            message = solver.step()
            if solver.status == "failed" or not np.all(np.isfinite(solver.y)):
                raise IntegrationError(f"integration failed at t = {solver.t:.9g} s: {message}")
            step = _Step(solver.t_old, solver.t, solver.dense_output(), start_state)
            if solver.status != "finished" or hint is None:
                hint = step.end - step.start  # the last step not cut short by `end`
            event, reached = self._first_event(step, segment, offsets)
            if self.check_tension:
                self._check_tension(step, reached, segment)
            while samples and samples[0] < reached:
                t = samples.pop(0)
                on_sample(t, model.outputs(self._state_at(step, t, segment, torques),
                                           segment.contact_set, segment.loaded))
            if event is not None:
                return reached, self._state_at(step, reached, segment, torques), event, hint
            if solver.status == "finished":
                return step.end, solver.y.copy(), None, hint

    def _solver(self, segment, torques, time, state, end, first_step):
        """A scipy solver for the segment from (time, state) towards `end`."""
        return self.solver_class(
            self.model.rate_function(segment.contact_set, segment.loaded, *torques),
            time, state, end, rtol=self.step_tolerance, atol=self.absolute_tolerance,
            max_step=self.max_step, first_step=first_step)

    def _state_at(self, step, time, segment, torques):
        """The state at `time` inside the step, by steps of the method from the step's start
        (error-controlled like every step): the dense output finds events, but its own error,
        large where a step spans several radians of the fastest mode (stable, but coarse for
        the interpolant), is kept out of samples and out of the states that events restart
        from (docs/reference-accuracy.md)."""
        if time == step.start:
            return step.start_state.copy()
        solver = self._solver(segment, torques, step.start, step.start_state, time,
                              time - step.start)
        while solver.status == "running":
            message = solver.step()
            if solver.status == "failed":
                raise IntegrationError(f"integration failed at t = {solver.t:.9g} s: {message}")
        return solver.y.copy()

    def _first_event(self, step, segment, offsets):
        """(event, time) of the earliest crossing inside the step, or (None, step's end)."""
        times = step.start + (step.end - step.start) * self.fractions
        values, slopes = self._values_and_slopes(step, segment, times)
        values -= offsets[:, None]
        candidates, bumps = reference_events.crossing_candidates(values, slopes, times)
        # interval by interval: a bulge that turns out to stay below zero leaves the intervals
        # after it to be searched (a crossing there is no less due)
        for interval in np.flatnonzero(candidates.any(axis=0)):
            found = [(self._locate(step, segment, offsets, event, times[interval],
                                   times[interval + 1], bumps[event, interval]), int(event))
                     for event in np.flatnonzero(candidates[:, interval])]
            found = [(t, event) for t, event in found if t is not None]
            if found:
                reached, event = min(found)
                return event, reached
        return None, step.end

    def _values_and_slopes(self, step, segment, times):
        """The event functions at the times, and their slopes: φp's from its rate in the state;
        a point's, where its approach comes near zero (within NEAR_ZERO times its largest change
        between nodes), by central differences on the dense output, a step's hundred-thousandth
        apart (truncation 1e-10 of the slope; the approach's rounding, ~1e-21 m, adds
        ~1e-10 m/s); elsewhere 0, which no bulge test flags."""
        states = step.dense(times)
        values = segments.event_values(self.model, segment, states)
        slopes = np.zeros_like(values)
        speed = states[self.model.size + self.model.pinion]
        slopes[segments.PHASE_END], slopes[segments.PHASE_START] = speed, -speed
        near = reference_events.near_zero(values[2:], NEAR_ZERO)
        if near.any():
            spacing = SLOPE_SPACING * (step.end - step.start)
            shifted = step.dense(np.concatenate([times - spacing, times + spacing]))
            ahead = segments.event_values(self.model, segment, shifted)[2:][near]
            slopes[2:][near] = (ahead[:, len(times):] - ahead[:, :len(times)]) / (2.0 * spacing)
        return values, slopes

    def _locate(self, step, segment, offsets, event, left, right, bump):
        """The time in [left, right] where event function `event` first rises through zero;
        None if it does not (a bump that stays below zero)."""
        def function(t):
            return segments.event_value(self.model, segment, event, step.dense(t)) - offsets[event]

        if bump or function(left) >= 0.0:
            # the top of the bulge (or, from a start on zero, the dip before the rise)
            sign = 1.0 if bump else -1.0
            extremum = minimize_scalar(lambda t: -sign * function(t), bounds=(left, right),
                                       method="bounded",
                                       options={"xatol": 1e-9 * (right - left)}).x
            if bump:
                if function(extremum) <= 0.0:
                    return None
                right = extremum
            elif function(extremum) < 0.0:
                left = extremum
            else:
                return left  # at zero and rising: due at once
        return brentq(function, left, right, xtol=1e-300, rtol=4 * np.finfo(float).eps)

    def _check_tension(self, step, reached, segment):
        """The debug check (see __init__): raise where a point's force has the wrong sign."""
        model = self.model
        if not model.contact_loss:
            return
        band = segments.contact_band(model)
        times = np.linspace(step.start, reached, TENSION_NODES)
        contact_set = segment.contact_set
        approach = model.point_approaches(step.dense(times), contact_set)
        wrong = np.where(segment.loaded[:, None] != 0.0, approach < -band, approach > band)
        if wrong.any():
            point, node = (int(k[0]) for k in np.nonzero(wrong))
            kind = "pulls" if segment.loaded[point] else "penetrates unloaded"
            raise IntegrationError(
                f"at t = {times[node]:.12g} s point {point} of contact interval "
                f"{contact_set.index} (cycle {contact_set.cycle}) {kind}: approach "
                f"{approach[point, node]:.3e} m")


def statically_loaded_matrices(model: GearTrainModel, motor_torque: float
                               ) -> tuple[np.ndarray, np.ndarray] | None:
    """Stiffness and damping over q averaged over one mesh period (the nodes of
    GearTrainModel.mesh_period_nodes, as mean_stiffness_matrix), each node's contact points
    loaded as the run's start loads them (segments.static_start): on the static deflection under
    `motor_torque`, the points whose approach is not negative. A point without load carries no
    mesh damping (η·c acts through the loaded points alone), so where a lead error or a tilt
    leaves part of the face unloaded the mesh damps the train less than with every point loaded.
    None where every point of every node is loaded: the train is the one of every point loaded
    (GearTrainModel.eigenvalues's own matrices)."""
    stiffness = np.zeros((model.size, model.size))
    damping = np.zeros((model.size, model.size))
    eta = model.mesh_damping_factor
    every_point_loaded = True
    for y, contact_set, share in model.mesh_period_nodes():
        segment, state = segments.static_start(model, contact_set, y, motor_torque, 0.0)
        y, loaded = state[:model.size], segment.loaded
        every_point_loaded = every_point_loaded and bool(loaded.all())
        every_point = model.stiffness_matrix(y, contact_set)
        loaded_stiffness = model.stiffness_matrix(y, contact_set, loaded)
        stiffness += share * loaded_stiffness
        damping += share * (model.damping_matrix(y, contact_set)
                            - eta * (every_point - loaded_stiffness))
    if every_point_loaded:
        return None
    pitch = model.geometry.angular_pitch
    return stiffness / pitch, damping / pitch


def mode_radians(eigenvalues: np.ndarray, horizon: float) -> float:
    """The most radians any oscillating mode of the eigenvalues (GearTrainModel.eigenvalues) rings
    within `horizon` seconds: max of min(ω·horizon, 1/ζ); 0 where none oscillates."""
    frequency = np.abs(eigenvalues)  # ω, rad/s
    decay = np.maximum(-eigenvalues.real, 0.0)  # ζω, 1/s
    oscillating = np.abs(eigenvalues.imag) > 1e-6 * max(frequency.max(), 1.0)
    radians = np.minimum(frequency * horizon, frequency / np.maximum(decay, 1e-300))
    return float(np.max(radians[oscillating], initial=0.0))


def fastest_rate(model: GearTrainModel) -> float:
    """|λ|max over the eigenvalues of the linearized train (GearTrainModel.eigenvalues), 1/s."""
    return float(np.abs(model.eigenvalues()).max())


def driving_torques(model: GearTrainModel, horizon: float) -> list[float]:
    """The positive motor torques (N·m) of the scene's input table that hold within the first
    `horizon` seconds: those under which the static deflection says which points carry load."""
    inputs = model.scene.inputs
    return sorted({float(torque) for time, torque in zip(inputs.times, inputs.M_motor)
                   if time < horizon and torque > 0.0})


def ringing_radians(model: GearTrainModel, horizon: float) -> float:
    """The most radians any mode of the train rings within `horizon` seconds before its damping
    has taken the amplitude down by e: max over the modes of min(ω·horizon, 1/ζ), where
    −ζω ± iω√(1−ζ²) are the eigenvalues of the linearized train (mass, mean stiffness and mean
    damping over a mesh period), every point loaded; and, with contact loss, the points loaded
    that the static deflection under each motor torque of the scene's input table within the
    horizon loads (statically_loaded_matrices): the most of these. Modes that do not oscillate
    ring 0."""
    radians = mode_radians(model.eigenvalues(), horizon)
    if model.contact_loss:
        for torque in driving_torques(model, horizon):
            matrices = statically_loaded_matrices(model, torque)
            if matrices is not None:
                radians = max(radians, mode_radians(model.eigenvalues(*matrices),
                                                    horizon))
    return radians


def step_tolerance(model: GearTrainModel, tolerance: float, horizon: float) -> float:
    """The tolerance per step that holds a run of `horizon` seconds to `tolerance`: cut by
    RINGING_BUDGET / ringing_radians where the train rings longer than RINGING_BUDGET radians,
    never below FINEST_STEP_TOLERANCE."""
    radians = ringing_radians(model, horizon)
    return max(tolerance * min(1.0, RINGING_BUDGET / radians) if radians > 0.0 else tolerance,
               FINEST_STEP_TOLERANCE)
