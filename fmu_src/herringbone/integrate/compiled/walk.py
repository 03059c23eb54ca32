"""The compiled loop: a run stepped through its segments (segments.py), one step method inside.

Contract of `advance`: from the run's position (time, state, contact interval and mesh cycle,
loaded points, step size to try), integrate to exactly `end` with the torques held, and leave
the new position in the same arrays, updated in place. The result depends on nothing but the
position and the settings (not on what the workspace held before), so a saved position re-runs
identically.

Segments. Within one the contact set and its loaded points are fixed and the equations smooth;
a segment ends where an event function crosses zero (as segments.py defines them):
    Event.PHASE_END: φp reaches the end of the contact set's interval (rising), the next set
       begins;
    Event.PHASE_START: φp falls back below its start (falling), the previous set begins;
    Event.CONTACT + i: point i's approach δ + η·δ̇ crosses zero (falling while it is loaded,
       rising while it is not), only where contact can be lost.
The loop steps onto every crossing: when an accepted step ends past one, the crossing is located
by steps of the method itself taken from the step's start (aimed by Newton's method: a phase
event's slope, φp's rate, is in the state, a contact's is the point's approach rate), and the
segment ends on the far side of the crossing, past it by at most the event time tolerance: a switch
misplaced by δt leaves a force error of about ω_max·δt times the force that switched, and the
caller keeps that to a hundredth of the relative tolerance. Every segment therefore ends with a
true step of the method, which keeps its order (a step across a switch would drop it to first
order). Where several events cross inside one step, the earliest is located (trials are judged
against the bracket's low end, where nothing has crossed yet, and a last trial just before the
located crossing makes sure no other came first, but where the points of an exact set cross
together). A point that lifts off and lands again inside one step (or touches and leaves) is
caught from the cubic through its approach and approach rate at the step's ends
(`grazing_suspect`), and looked for by trial steps inside the step (`probe_inside`); inside an
exact step that is not certified, from the approach's modal solution itself (`exact_dip`).

What follows an event (`next_segment`): the loaded points of the segment are decided by the
sign of their approach, all of them, whatever the event was. So a point that crossed in the
same bracket as the located event (a whole train separating, or landing, at once) starts the
segment on its own side; and no segment starts with a loaded point in tension or an unloaded
one penetrating. A debug run (contact slack >= 0) also looks inside every step for such a
point by other means (`contact_violated_inside`).

Two step-size rules serve the switches (DOP853 only for the first): a step that would pass the
next phase event is aimed to end just past its predicted crossing, so one trial step locates
it; and each contact interval starts with the step size its last entry settled on
(`first_steps`), since the vibration a switch sets off is one the step before it did not see.

The loop (`walk`) is a few named steps: `plan_step` (how long a step to try), the method's step
(dop853.step, or `implicit_step` with its Jacobian and factors), `control_step` (accept or
reject it, and the next step size), `crossed_event` and `grazing_check` (which event the step
crossed; where a point may have lifted off and landed again inside it, `grazing_probe` looks),
then `finish_step` (no event: the step's end is the new start) or `cross_event` (the crossing
located by `locate_event` to the event time tolerance, the run moved into the next segment by
`end_segment`, which the loop then begins: `begin_segment`). Between the two, where the
new segment is exact, `chain_switches` takes the events that follow one after another for as
long as each step is one that ends on its event, located without a trial, with none of the
loop's bookkeeping in between: a phase switch where the opening step is aimed at the modal
solution's crossing of the phase end and the loop would take and accept it (the run then
the loop's own to the bit), and where contact can be lost, a landing or a lift-off stepped
onto just past the first crossing of the approach's modal solution. Trial steps (`trial_step`) serve
the location, the probe and the debug check. They work on records laid out once: the stepper's
settings (one float array, `Setting`), the run's arrays (`RunArrays`, its position), the mesh
period (`equations.PeriodTable`) and the run's `Workspace`, the scratch arrays that `pack_run`
allocates once per run (rows named by `Vector` and `Values`, the loop's memory by `Counter`
and `Memory`). They come from Python as a few flat buffers (buffers.py), which `advance` takes
apart into these records (`unpack_records`).

Units: time and step sizes in s, angles in rad, the state as model.py lays it out, approaches
in m (their rates in m/s), torques in N·m.
"""
from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import overload

from ...compiling.counting import NUMBERS_ONLY, UNCOUNTED
from ...model.equations import (
    Event,
    approach_rates,
    approaches,
    derivative,
    outputs,
)
from . import buffers, dop853, exponential, radau

# How far past its contact interval (a fraction of its length) a run's pinion may end: the
# event rules place it within 1e-12 of a pitch. A state past that is one so large that its
# rounding hides the phase events (a torque of 1e300 N·m), no result to return.
PHASE_SLACK = 1e-6


class Status(IntEnum):
    """How `advance` ended (CompiledStepper.run_to raises for all but OK)."""

    OK = 0
    STALLED = 1  # MAX_EVENTS_WITHOUT_PROGRESS events in a row without time between them
    STEP_TOO_SMALL = 2  # the step size fell below the time's resolution
    NOT_FINITE = 3  # the state at `end` is not finite
    CHATTER = 4  # MAX_PHASE_REVERSALS phase events in a row, each undoing the last
    CONTACT_VIOLATED = 5  # the debug check found tension or penetration inside a step
    OVER_BUDGET = 6  # `max_steps` steps taken short of `end`
    LEFT_INTERVAL = 7  # the pinion ended outside its contact interval, past PHASE_SLACK


class Method(IntEnum):
    """The step method."""

    EXPLICIT = 0  # DOP853
    IMPLICIT = 1  # Radau IIA
    EXPONENTIAL = 2  # exact segments (exponential.py), DOP853 where a segment is not exact


class Setting(IntEnum):
    """Entries of the settings record (`pack_settings`), one float array per stepper. (The
    method is not among them: it is the workspace's, see allocate_implicit.)"""

    RELATIVE_TOLERANCE = 0
    MAX_STEP = 1  # s
    EVENT_TIME_TOLERANCE = 2  # s: how far past its crossing a segment may end
    CONTACT_SLACK = 3  # m; >= 0 turns the debug contact check on, < 0 leaves it off
    EXACT_MAX_STEP = 4  # s: the longest step of an exact segment (exponential method)
    # s: the longest exact step taken uncertified (control_exact_step): DOP853's step bound
    # h·|λ|max <= 3.5 with no error bound in it, an exact step making none (what such a step
    # hides between its ends, its modal solution shows: grazing_probe)
    EXACT_FLOOR = 5
    ABSOLUTE_TOLERANCE = 6  # from here to the end: per state entry, in the entry's units


class Vector(IntEnum):
    """Rows of the workspace's `vectors`, each as long as the state."""

    RATE = 0  # d(state)/dt at the step's start
    RATE_AFTER = 1  # at its end
    NEW_STATE = 2  # the step's end state (or the bracketed crossing's)
    TRIAL = 3  # a trial step's end state
    WORK = 4  # the methods' own scratch
    STAGES = 5  # dop853.STAGE_ROWS rows from here: the stages (Radau IIA uses the first 3)


class Values(IntEnum):
    """Rows of the workspace's `values`, Event.CONTACT + the widest set's points wide: event
    function values (by Event), then per-point rows (indexed by point)."""

    BEFORE = 0  # event values at the step's start
    AFTER = 1  # at its end (or where the crossing was bracketed)
    TRIAL = 2  # at a trial step's end
    LOW = 3  # at the location bracket's low end
    HIGH = 4  # at its high end
    APPROACH = 5  # per point: δ + η·δ̇, m (scratch)
    SLOPES_BEFORE = 6  # per point: its rate at the step's start, m/s (NaN: not taken)
    SLOPES_AFTER = 7  # at its end


class CompiledSegment(NamedTuple):
    """A segment (segments.Segment: a contact set and its loaded points) as the loop holds it:
    its equations as equations.derivative takes them, with the torques, and its events."""

    points: np.ndarray  # the contact set's point table (model/equations.py's rows)
    point_count: int  # its number of points
    loaded: np.ndarray  # per point: 1 loaded, 0 not (the run's array)
    motor_torque: float  # N·m
    load_torque: float  # N·m
    length: float  # the contact interval's length in φp, rad
    events: int  # the number of event functions: Event.CONTACT (+ count if contact can be lost)
    exact: int  # its exact form's index in the exponential method's tables; −1: none


class Counter(IntEnum):
    """Entries of the workspace's `counters`: the loop's memory within one call of `advance`,
    then the run's tallies, kept over its life (Run.trial_steps, Run.events,
    Run.rejected_steps)."""

    OPENING = 0  # the contact interval whose first step is being taken (forward entry); −1: none
    SEGMENT = 1  # segments begun in this call (what Radau IIA's Jacobian is dated by)
    JACOBIAN_SEGMENT = 2  # the segment Radau IIA's Jacobian belongs to; −1: none
    JACOBIAN_FRESH = 3  # 1 while no step has been accepted on that Jacobian
    STALLED = 4  # events in a row without progress
    REVERSALS = 5  # phase events in a row that reversed the last one
    LAST_PHASE_EVENT = 6  # Event.PHASE_END or PHASE_START; −1: none yet
    TRIAL_STEPS = 7  # trial steps taken (trial_step: event location, grazing probes, checks)
    EVENTS = 8  # events located (cross_event)
    REJECTED_STEPS = 9  # steps rejected (error control; an exact step not certified)
    SWITCHES_CHAINED = 10  # of the EVENTS, phase switches taken by chain_switches
    CONTACTS_CHAINED = 11  # of the EVENTS, landings and lift-offs taken by chain_switches


class Memory(IntEnum):
    """Entries of the workspace's `memory`: the loop's floats within one call of `advance`."""

    FACTORED_H = 0  # s: the step size Radau IIA's LU factors belong to; 0: none
    # s: when the next phase event lies ahead of the next step, from the modal solution,
    # taken where the run entered an exact segment (opening_ahead) or a call began in one
    # (call_opening_ahead), until a step is accepted
    MODAL_AHEAD = 1
    # what kind of time MODAL_AHEAD is (exponential.CROSSING, NEAR, BOUND, or NO_AIM: none)
    MODAL_AIM = 2
    # s: an exact step from the run's state that chain_switches took and did not chain, its
    # state in NEW_STATE and its verdict in TAKEN_VERDICT, for the loop's next step (0: none)
    TAKEN_H = 3
    TAKEN_VERDICT = 4


class Workspace(NamedTuple):
    """The scratch arrays of a run (`pack_run`), reused by every call of `advance`,
    whose results do not depend on what they held. Radau IIA's three are None in the other
    methods' workspaces, the exponential method's tables None in the others': the method is so
    a matter of the workspace's type, which numba compiles `advance` for, and the code of the
    other methods is never compiled (`implicit_step`, `exact_step`)."""

    vectors: np.ndarray  # rows by Vector, each as long as the state
    values: np.ndarray  # rows by Values
    matrices: np.ndarray | None  # Radau IIA's Jacobian and real LU factors (JACOBIAN, REAL_FACTORS)
    complex_factors: np.ndarray | None  # Radau IIA's complex LU factors
    pivots: np.ndarray | None  # Radau IIA's pivots: the real factors' row, the complex ones'
    counters: np.ndarray  # by Counter
    memory: np.ndarray  # by Memory
    # the exponential method's tables, as exponential.pack_tables packs them: each of its
    # kernels takes them apart (exponential.unpack_tables)
    exact: tuple | None


JACOBIAN, REAL_FACTORS = 0, 1  # rows of Workspace.matrices


class RunArrays(NamedTuple):
    """A run's position (integrate/compiled_stepper.py's Run), in the arrays `advance` reads
    and writes back in place."""

    clock: np.ndarray  # [time, step size to try next], s
    place: np.ndarray  # [contact interval, mesh cycle]
    state: np.ndarray  # [y, ẏ]
    loaded: np.ndarray  # per point of the set (padded to the widest set): 1 loaded, 0 not
    first_steps: np.ndarray  # per contact interval, the step size to start it with, s; 0: none
    outputs: np.ndarray  # equations.outputs at the run's position


class StepPlan(NamedTuple):
    """A step to try (`plan_step`)."""

    h_step: float  # its size, s
    h_wanted: float  # the size the controller asked for (bounded by the max step), s
    landing: bool  # whether it ends on the run's `end`
    aimed: bool  # whether it is aimed to end just past a predicted phase event


class Samples(NamedTuple):
    """The sample times of a call of `advance` (none for a plain step) and the rows their
    outputs go to."""
    times: np.ndarray  # s, rising
    rows: np.ndarray  # one row of equations.outputs per time


class StepRows(NamedTuple):
    """Views of the rows of the workspace and the settings that every step uses, made once
    per call of `advance` (`step_rows`): a view made at every step is an array numba
    counts."""

    rate: np.ndarray  # Vector.RATE
    rate_after: np.ndarray  # Vector.RATE_AFTER
    new_state: np.ndarray  # Vector.NEW_STATE
    last_stage: np.ndarray  # DOP853's last stage: the rate at its step's end
    stages: np.ndarray  # the rows from Vector.STAGES on
    work: np.ndarray  # Vector.WORK
    tolerance: np.ndarray  # the absolute tolerance, per state entry


class Controller(NamedTuple):
    """The step-size controller's memory: the Runge-Kutta methods' (`control_step`), and of
    an exact step only whether it was rejected (`control_exact_step`)."""

    previous_error: float  # the last accepted uncut Runge-Kutta step's error norm (DOP853: >= 1e-4)
    rejected: bool  # whether the last step was rejected
    previous_h: float  # Radau IIA: the last accepted uncut step's size, s; 0: none

# where a debug run looks inside each step for a point in tension or penetrating unloaded
INSIDE_FRACTIONS = (0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875)
# A cubic through a mode's values and slopes at the ends of a step of h·ω = y misses it by
# about y³/384 of the step's change h·|ġ|: 0.11 at the step bound's 3.5. A point whose cubic
# comes this close to zero is looked at inside the step (`grazing_suspect`), at its cubic's
# turning point and at PROBE_FRACTIONS.
GRAZING_MARGIN = 0.12
PROBE_FRACTIONS = (0.25, 0.5, 0.75)
MAX_EVENTS_WITHOUT_PROGRESS = 1000  # chattering contact (grazing) beyond this is an error
# trial steps to locate one event (a bisection alone halves the bracket 60 times)
MAX_LOCATION_TRIALS = 60
# trials after which a location bisects its bracket (location_estimate)
NEWTON_LOCATION_TRIALS = 12
# A contact set that throws the pinion back into the previous one, and that one forward again:
# beyond this many reversals in a row the train is stuck on the switch (a point entering at
# full load with sharp face edges, at low speed), which an edge ramp resolves
MAX_PHASE_REVERSALS = 1000
# A step aimed at a predicted phase event ends this fraction of its length past the prediction,
# so that it crosses despite the prediction's error; it is aimed only when the event lies more
# than PREDICTION_FLOOR of the step ahead (a nearer one is crossed by the step as it is)
PREDICTION_MARGIN = 1e-4
PREDICTION_FLOOR = 1e-3
# A call that begins inside an exact segment asks for the modal solution's phase event only
# where φp, at its present speed, would leave its interval within this many times the call's
# span (the ringing moves that speed by a tenth or so): at the FMU's finest steps the
# prediction (0.6 µs and more) would otherwise be made at every call for an event far ahead
CALL_REACH = 2.0
# An exact step (exponential method) makes no error, so the step size serves the events only:
# after a certified step the next may be this many times longer (but a step certified right
# after a rejection keeps its size: control_exact_step), after a rejected one this fraction as
# long
EXACT_GROWTH = 4.0
EXACT_SHRINK = 0.25
# An exact step that may hide the pinion turning back across an end of its interval (a
# torsional mode swinging its speed through zero, as in torque_step) is shortened below the
# exact floor (Setting.EXACT_FLOOR), to this fraction of it, before it is taken unsure: three
# quarterings
TURN_BACK_FLOOR = 1.0 / 64.0
NEVER = math.inf  # s: the time to an event that is not ahead

# Inlining and speed. The helpers the loop runs at every step are inlined (inline="always")
# into `advance`, which is compiled without numba's reference counts (compiling.counting):
# a compiled call would cost its call and, compiled with counts, an atomic
# count of every array of every record it is handed, on the way in and out (the System alone
# has 15 arrays). What runs once per event or less (cross_event, locate_event, probe_inside,
# contact_violated_inside, trial_step, exact_samples) stays a call, and returns numbers only,
# so that it too is compiled without counts. Even without counts a call copies every array it
# is handed onto the stack, some ten words each: the exact tables travel as
# exponential.pack_tables' three buffers rather than ExactTables' twenty-six arrays, and each
# of its kernels takes them apart (the twenty-six cost the method a quarter of its time).


# --- the records ------------------------------------------------------------------------------

def pack_settings(relative_tolerance: float, max_step: float, event_time_tolerance: float,
                  contact_slack: float, absolute_tolerance: np.ndarray,
                  exact_max_step: float, exact_floor: float) -> np.ndarray:
    """The settings record `advance` takes: the entries laid out by Setting."""
    settings = np.empty(Setting.ABSOLUTE_TOLERANCE + len(absolute_tolerance))
    settings[Setting.EXACT_MAX_STEP] = exact_max_step
    settings[Setting.EXACT_FLOOR] = exact_floor
    settings[Setting.RELATIVE_TOLERANCE] = relative_tolerance
    settings[Setting.MAX_STEP] = max_step
    settings[Setting.EVENT_TIME_TOLERANCE] = event_time_tolerance
    settings[Setting.CONTACT_SLACK] = contact_slack
    settings[Setting.ABSOLUTE_TOLERANCE:] = absolute_tolerance
    return settings


def pack_run(clock, place, state, loaded, first_steps, outputs, max_points: int
             ) -> tuple[np.ndarray, np.ndarray]:
    """A run's buffers (buffers.pack_run): its position, RunArrays' fields, copied in, and the
    scratch of its Workspace for sets of up to `max_points` points, allocated once per run
    (CompiledStepper.start)."""
    return buffers.pack_run(clock, place, state, loaded, first_steps, outputs,
                            Vector.STAGES + dop853.STAGE_ROWS, len(Values),
                            Event.CONTACT + max_points, len(Memory), len(Counter))


def allocate_implicit(method: Method, size: int) -> tuple:
    """Radau IIA's arrays of a run with `size` state entries (Workspace's matrices,
    complex_factors and pivots), None for the other methods: the method is so a matter of
    the workspace's type, which numba compiles `advance` for."""
    if method != Method.IMPLICIT:
        return None, None, None
    return (np.zeros((2, size, size)), np.zeros((size, size), dtype=np.complex128),
            np.zeros((2, size), dtype=np.int64))


def run_records(run, implicit, exact) -> tuple[RunArrays, Workspace]:
    """A run's RunArrays and Workspace as views of its buffers (pack_run), with Radau IIA's
    arrays (allocate_implicit) and the exponential method's tables
    (exponential.pack_tables; None for the other methods): for Python; `advance` takes them
    apart alike in compiled code."""
    views = buffers.run_views(run)
    matrices, complex_factors, pivots = implicit
    return RunArrays(*views[:6]), Workspace(views[6], views[7], matrices, complex_factors,
                                            pivots, views[8], views[9], exact)


@njit(cache=True, error_model="numpy", inline="always")
def unpack_records(constants, exact, implicit, run):
    """advance's arguments as the loop's records: (System, PeriodTable, settings, RunArrays,
    Workspace), views of the buffers."""
    system, mesh, settings = buffers.unpack_constants(constants)
    clock, place, state, loaded, first_steps, outputs_, vectors, values, counters, memory = \
        buffers.unpack_run(run)
    workspace = Workspace(vectors, values, implicit[0], implicit[1], implicit[2], counters,
                          memory, exact)
    return (system, mesh, settings,
            RunArrays(clock, place, state, loaded, first_steps, outputs_), workspace)


def _lacks(record_type, field):
    """Whether the named tuple type `record_type` (numba's) holds None as `field`."""
    return isinstance(record_type[record_type.fields.index(field)], types.NoneType)


def is_explicit(workspace):
    """Whether the workspace is DOP853's (a constant in compiled code)."""
    return workspace.matrices is None


@overload(is_explicit, inline="always")
def _is_explicit(workspace):
    explicit = _lacks(workspace, "matrices")
    return lambda workspace: explicit


def exact_form(workspace, interval, count, loaded, state):
    """exponential.variant_of where the workspace is the exponential method's; −1 (a constant
    in compiled code) in the others'."""


@overload(exact_form, inline="always")
def _exact_form(workspace, interval, count, loaded, state):
    if _lacks(workspace, "exact"):
        return lambda workspace, interval, count, loaded, state: -1
    return lambda workspace, interval, count, loaded, state: exponential.variant_of(
        workspace.exact, interval, count, loaded, state)


def exact_step(system, segment, state, workspace, h, out):
    """exponential.step on the workspace's tables where it is the exponential method's (the
    segment exact): what its certificate says; never called in the others'."""


@overload(exact_step, inline="always")
def _exact_step(system, segment, state, workspace, h, out):
    if _lacks(workspace, "exact"):
        return lambda system, segment, state, workspace, h, out: exponential.UNSURE
    return lambda system, segment, state, workspace, h, out: exponential.step(
        exponential.exact_train(system), workspace.exact, segment.exact, state,
        segment.motor_torque, segment.load_torque, h,
        system.contact_loss, 1.0 if segment.exact % exponential.VARIANTS
        == exponential.ALL_LOADED else -1.0, segment.length, out)


def exact_state(system, segment, state, workspace, h, out):
    """exponential.state_after on the workspace's tables where it is the exponential
    method's (the segment exact): the state only; never called in the others'."""


@overload(exact_state, inline="always")
def _exact_state(system, segment, state, workspace, h, out):
    if _lacks(workspace, "exact"):
        return lambda system, segment, state, workspace, h, out: None
    return lambda system, segment, state, workspace, h, out: exponential.state_after(
        exponential.exact_train(system), workspace.exact, segment.exact, state,
        segment.motor_torque, segment.load_torque, h, out)


def exact_monotone(workspace, segment, h):
    """exponential.approach_monotone on the workspace's tables where it is the exponential
    method's; False in the others'."""


@overload(exact_monotone, inline="always")
def _exact_monotone(workspace, segment, h):
    if _lacks(workspace, "exact"):
        return lambda workspace, segment, h: False
    return lambda workspace, segment, h: exponential.approach_monotone(
        workspace.exact, segment.exact, h)


def exact_dip(system, segment, state, workspace, h):
    """exponential.approach_dip on the workspace's tables where it is the exponential method's
    and the segment exact, as a fraction of the step of h (s) from `state` (−1: none, NaN:
    it gave up); NaN elsewhere, where it cannot judge."""


@overload(exact_dip, inline="always")
def _exact_dip(system, segment, state, workspace, h):
    if _lacks(workspace, "exact"):
        return lambda system, segment, state, workspace, h: math.nan

    def dip(system, segment, state, workspace, h):
        if segment.exact < 0:
            return math.nan
        at = exponential.approach_dip(exponential.exact_train(system), workspace.exact,
                                      segment.exact, state, segment.motor_torque,
                                      segment.load_torque, h,
                                      1.0 if segment.loaded[0] != 0.0 else -1.0)
        return at / h if at > 0.0 else at
    return dip


def exact_crossing(system, segment, state, workspace, high, guess):
    """exponential.approach_crossing on the workspace's tables where it is the exponential
    method's (the segment exact): where a point's approach crosses zero inside the bracket
    [0, high] (s) from `state`, by Newton's method from `guess` (s); −1 where that does not
    converge, and in the others'."""


@overload(exact_crossing, inline="always")
def _exact_crossing(system, segment, state, workspace, high, guess):
    if _lacks(workspace, "exact"):
        return lambda system, segment, state, workspace, high, guess: -1.0
    return lambda system, segment, state, workspace, high, guess: exponential.approach_crossing(
        exponential.exact_train(system), workspace.exact, segment.exact, state,
        segment.motor_torque, segment.load_torque, high,
        segment.exact % exponential.VARIANTS == exponential.NONE_LOADED, guess)


def exact_first_crossing(system, segment, state, workspace, h):
    """exponential.approach_first_crossing on the workspace's tables where it is the
    exponential method's (the segment exact): where the points' approach first crosses zero
    within h (s) from `state` (−1: it does not; NaN: it cannot tell); NaN in the others'."""


@overload(exact_first_crossing, inline="always")
def _exact_first_crossing(system, segment, state, workspace, h):
    if _lacks(workspace, "exact"):
        return lambda system, segment, state, workspace, h: math.nan
    return lambda system, segment, state, workspace, h: exponential.approach_first_crossing(
        exponential.exact_train(system), workspace.exact, segment.exact, state,
        segment.motor_torque, segment.load_torque, h,
        -1.0 if segment.exact % exponential.VARIANTS == exponential.NONE_LOADED else 1.0)


def exact_event_ahead(system, workspace, exact, state, motor_torque, load_torque, length,
                      horizon):
    """exponential.modal_phase_event_ahead on the workspace's tables where it is the exponential
    method's; (−1, exponential.NO_AIM) in the others'."""


@overload(exact_event_ahead, inline="always")
def _exact_event_ahead(system, workspace, exact, state, motor_torque, load_torque, length,
                       horizon):
    if _lacks(workspace, "exact"):
        return (lambda system, workspace, exact, state, motor_torque, load_torque, length,
                horizon: (-1.0, exponential.NO_AIM))
    return (lambda system, workspace, exact, state, motor_torque, load_torque, length, horizon:
            exponential.modal_phase_event_ahead(exponential.exact_train(system),
                                                workspace.exact, exact, state, motor_torque,
                                                load_torque, length, horizon))


@njit(cache=True, error_model="numpy", inline="always")
def stop_at(samples, k, end, exact):
    """Where the loop stops: at `end`, or where the segment is not exact (its exact form
    `exact` < 0), at the sample time `k` of `samples` if that comes first (the exact segments
    take their samples inside their steps: `sample_inside`)."""
    if exact >= 0 or k >= samples.times.shape[0]:
        return end
    return min(end, samples.times[k])


@njit(cache=True, error_model="numpy", inline="always")
def sample_inside(samples, k, system, segment, state, workspace, time, until):
    """exact_samples where a sample lies before `until`; k (none taken) where none does (a
    plain step has none, and at an event's pace even an empty call costs its arguments)."""
    if k >= samples.times.shape[0] or samples.times[k] >= until:
        return k
    return exact_samples(system, segment, state, workspace, samples.times, samples.rows, k,
                         time, until)


@njit(**NUMBERS_ONLY)
def exact_samples(system, segment, state, workspace, times, rows, k, time, until):
    """The outputs (equations.outputs) at every sample time from the `k`-th on that lies in
    [time, until) (s) into its row of `rows`, each from the exact solution of the segment (an
    exact one) from `state` at `time`: an accepted step, or the bracket of a located event,
    covers them, and the solution anywhere in it is as exact as at its end. Returns the index
    of the first sample left."""
    scratch = workspace.vectors[Vector.TRIAL]
    while k < times.shape[0] and times[k] < until:
        exact_state(system, segment, state, workspace, times[k] - time, scratch)
        outputs(system, segment.points, segment.point_count, segment.loaded, scratch, rows[k])
        k += 1
    return k


@njit(cache=True, error_model="numpy", inline="always")
def sample_in_window(samples, k, system, segment, state, workspace, time, until, event):
    """window_samples where a sample lies before `until`; k (none taken) where none does."""
    if k >= samples.times.shape[0] or samples.times[k] >= until:
        return k
    return window_samples(system, segment, state, workspace, samples.times, samples.rows, k,
                          time, until, event)


@njit(**NUMBERS_ONLY)
def window_samples(system, segment, state, workspace, times, rows, k, time, until, event):
    """exact_samples for the samples in the location's window before a located crossing of
    `event` at `until` (s), which lies somewhere in it: each taken only where the event has
    not crossed at its own time (its function keeps the sign it had at `time`). One past the
    crossing belongs to the next segment, whose solution reaches back to it, as a run that
    stops at the sample finds. The event values at `time` are made again (the loop holds them
    already; chain_switches does not keep them). Returns the index of the first sample
    left."""
    scratch, values = workspace.vectors[Vector.TRIAL], workspace.values
    event_values(system, segment, state, values[Values.APPROACH], values[Values.BEFORE])
    while k < times.shape[0] and times[k] < until:
        exact_state(system, segment, state, workspace, times[k] - time, scratch)
        event_values(system, segment, scratch, values[Values.APPROACH], values[Values.TRIAL])
        if crosses(values[Values.BEFORE], values[Values.TRIAL], event, segment.loaded):
            break
        outputs(system, segment.points, segment.point_count, segment.loaded, scratch, rows[k])
        k += 1
    return k


@njit(cache=True, error_model="numpy", inline="always")
def segment_of(system, mesh, interval, loaded, torques, exact):
    """The CompiledSegment of contact interval `interval` of the mesh's period (a
    PeriodTable), with the run's loaded points, the torques (N·m) and its exact form (−1:
    none)."""
    count = mesh.counts[interval]
    return CompiledSegment(mesh.tables[interval], count, loaded, torques[0], torques[1],
                           mesh.lengths[interval],
                           Event.CONTACT + (count if system.contact_loss else 0), exact)


# --- the event functions ----------------------------------------------------------------------

@njit(cache=True, error_model="numpy", inline="always")
def event_values(system, segment, state, approach, out):
    """The event functions at `state` into `out` (by Event): φp − length and φp (rad), then,
    where contact can be lost, each point's approach (m; `approach` is scratch)."""
    out[Event.PHASE_END] = state[system.pinion] - segment.length
    out[Event.PHASE_START] = state[system.pinion]
    if system.contact_loss:
        approaches(system, segment.points, segment.point_count, state, approach)
        for i in range(segment.point_count):
            out[Event.CONTACT + i] = approach[i]


@njit(cache=True, error_model="numpy", inline="always")
def phase_event_ahead(system, state, rate, length):
    """When (s from now) φp would reach the end of its interval of `length` rad (moving
    forward) or its start (moving back), from its rate and acceleration in `rate`: the zero of
    the quadratic by one Newton step from the linear guess; inf if φp stands still or turns back
    before it gets there."""
    n = state.shape[0] // 2
    angle, speed, acceleration = (state[system.pinion], state[n + system.pinion],
                                  rate[n + system.pinion])
    if speed == 0.0:
        return math.inf
    linear = ((length if speed > 0.0 else 0.0) - angle) / speed
    slope = speed + acceleration * linear
    if slope * speed <= 0.0:  # turning back before it gets there
        return math.inf
    ahead = linear - 0.5 * acceleration * linear * linear / slope
    return ahead if ahead > 0.0 else math.inf


@njit(cache=True, error_model="numpy", inline="always")
def event_ahead(system, segment, state, workspace, rate, explicit):
    """When (s from now) the next phase event is predicted, for the step to be aimed just
    past it (plan_step), and whether that is the modal solution's crossing itself: for the
    first step in an exact segment after its entry or a call's start, the time opening_ahead
    or call_opening_ahead took (remember_modal_aim), or where that is only a bound, the
    sooner of it and phase_event_ahead's; else from φp's rate and acceleration `rate`
    (phase_event_ahead) for DOP853 and the exponential method, and never for Radau IIA
    (plan_step says why)."""
    if segment.exact >= 0:
        ahead, aim = workspace.memory[Memory.MODAL_AHEAD], workspace.memory[Memory.MODAL_AIM]
        if aim == exponential.CROSSING:
            return ahead, True
        if aim == exponential.NEAR:
            return ahead, False
        if aim == exponential.BOUND:
            # (the ringing often sends phase_event_ahead to inf, which no step is aimed at:
            # an opening step grown to milliseconds then crossed the event early on)
            return min(ahead, phase_event_ahead(system, state, rate, segment.length)), False
    return (phase_event_ahead(system, state, rate, segment.length) if explicit else NEVER,
            False)


@njit(cache=True, error_model="numpy", inline="always")
def crosses(before, after, event, loaded):
    """Whether event function `event` crosses zero from `before` to `after` (its values), in
    its direction: rising for PHASE_END and an unloaded point, falling for the others, ending
    strictly past zero."""
    rising = event == Event.PHASE_END or (event >= Event.CONTACT
                                          and loaded[event - Event.CONTACT] == 0.0)
    return (rising and before[event] <= 0.0 < after[event]) or (
        not rising and before[event] >= 0.0 > after[event])


@njit(cache=True, error_model="numpy", inline="always")
def first_crossing(before, after, number, loaded):
    """The event among the first `number` whose function crosses zero first (by linear
    interpolation) between two rows of event values, in its direction; −1 if none does."""
    first, first_fraction = -1, 2.0
    for event in range(number):
        if crosses(before, after, event, loaded):
            fraction = before[event] / (before[event] - after[event])
            if fraction < first_fraction:
                first, first_fraction = event, fraction
    return first


@njit(cache=True, error_model="numpy")
def crossings(before, after, number, loaded):
    """How many of the first `number` events cross zero between two rows of event values, each
    in its direction."""
    crossed = 0
    for event in range(number):
        if crosses(before, after, event, loaded):
            crossed += 1
    return crossed


@njit(cache=True, error_model="numpy")
def hermite_root(g0, g1, d0, d1):
    """The zero in [0, 1] of the cubic with values g0, g1 and slopes d0, d1 at 0 and 1 (g0, g1
    of opposite signs), by Newton's method from the chord's zero; −1 if it does not settle."""
    c2 = 3.0 * (g1 - g0) - 2.0 * d0 - d1
    c3 = 2.0 * (g0 - g1) + d0 + d1
    s = g0 / (g0 - g1)
    for _ in range(4):
        slope = d0 + s * (2.0 * c2 + 3.0 * s * c3)
        if slope == 0.0:
            return -1.0
        s -= (g0 + s * (d0 + s * (c2 + s * c3))) / slope
    return s if 0.0 < s < 1.0 else -1.0


# --- trial steps ------------------------------------------------------------------------------

@njit(cache=True, error_model="numpy")
def trial_step(system, segment, settings, state, workspace, h, out):
    """A step of size h (s) from `state` (its rate in the workspace's RATE row) to `out`, taken
    only to look where an event lies: its error is not checked (it is shorter than a step
    already accepted). Radau IIA factorizes for h (and says so in the workspace's memory)."""
    vectors = workspace.vectors
    workspace.counters[Counter.TRIAL_STEPS] += 1
    if segment.exact >= 0:
        exact_state(system, segment, state, workspace, h, out)
    elif is_explicit(workspace):
        dop853.step(system, segment, state, vectors[Vector.RATE], h,
                    settings[Setting.ABSOLUTE_TOLERANCE:], settings[Setting.RELATIVE_TOLERANCE],
                    vectors[Vector.STAGES:], vectors[Vector.WORK], out)
    else:
        implicit_trial_step(system, segment, settings, state, workspace, h, out)


def implicit_trial_step(system, segment, settings, state, workspace, h, out):
    """trial_step's step of Radau IIA where the workspace is its; never called (and nothing
    compiled) where the workspace is DOP853's."""


@overload(implicit_trial_step)
def _implicit_trial_step(system, segment, settings, state, workspace, h, out):
    if _lacks(workspace, "matrices"):
        return lambda system, segment, settings, state, workspace, h, out: None
    return radau_trial_step


def radau_trial_step(system, segment, settings, state, workspace, h, out):
    """A step of Radau IIA of size h (s) from `state` to `out`, its LU factors made for h."""
    factorize_for(workspace, h)
    factored_step(system, segment, settings, state, workspace, h, out, False)


@njit(cache=True, error_model="numpy", inline="always")
def factorize_for(workspace, h):
    """Radau IIA's LU factors of the workspace's Jacobian for a step of h (s), and the record
    of the step size they belong to."""
    radau.factorize(workspace.matrices[JACOBIAN], h, radau_factors(workspace))
    workspace.memory[Memory.FACTORED_H] = h


@njit(cache=True, error_model="numpy", inline="always")
def radau_factors(workspace):
    """Radau IIA's LU factors in the workspace, as a radau.Factors record."""
    return radau.Factors(workspace.matrices[REAL_FACTORS], workspace.pivots[0],
                         workspace.complex_factors, workspace.pivots[1])


@njit(cache=True, error_model="numpy", inline="always")
def factored_step(system, segment, settings, state, workspace, h, out, rejected):
    """Radau IIA's step of size h (s) from `state` (its rate in the RATE row) to `out`, on the
    factors made for h. Returns (the error norm, inf where Newton did not converge; Newton
    iterations)."""
    vectors = workspace.vectors
    return radau.step(system, segment, state, vectors[Vector.RATE], h,
                      settings[Setting.ABSOLUTE_TOLERANCE:], settings[Setting.RELATIVE_TOLERANCE],
                      radau_factors(workspace), vectors[Vector.STAGES:], out, rejected)


@njit(cache=True, error_model="numpy")
def contact_violated_inside(system, segment, settings, state, workspace, h):
    """Debug check of a step of h (s) from `state`, by trial steps to INSIDE_FRACTIONS of it:
    whether a loaded point's approach falls below −slack (tension) or an unloaded one's rises
    above slack (penetration without load) anywhere there, slack being the settings' contact
    slack (m). It looks for what the event search (crossings at step ends, the cubic for a dip
    within a step) would have missed, by other means, at seven times the cost of a step."""
    trial = workspace.vectors[Vector.TRIAL]
    approach = workspace.values[Values.APPROACH]
    slack = settings[Setting.CONTACT_SLACK]
    loaded = segment.loaded
    for fraction in INSIDE_FRACTIONS:
        trial_step(system, segment, settings, state, workspace, fraction * h, trial)
        approaches(system, segment.points, segment.point_count, trial, approach)
        for i in range(segment.point_count):
            if (loaded[i] != 0.0 and approach[i] < -slack) or (
                    loaded[i] == 0.0 and approach[i] > slack):
                return True
    return False


# --- the grazing check ------------------------------------------------------------------------

@njit(cache=True, error_model="numpy", inline="always")
def grazing_suspect(before, after, slopes_before, slopes_after, h, count, loaded):
    """Where inside a step of h (s), as a fraction of it, some point's approach may cross zero
    and come back though both ends lie on the same side: a lift-off and landing, or a touch,
    too brief for the ends to show. Each point's approach is modelled by the cubic through its
    values (`before`, `after`: rows of event values) and slopes (m/s) at the step's ends; a
    point is suspect where that cubic turns back towards zero and comes within
    GRAZING_MARGIN·h·(|ġ0| + |ġ1|) of it (the cubic's own error, for a step of up to
    h·|λ|max = 3.5 of the mode that moves the point). The earliest suspect turning point, or −1
    if there is none."""
    earliest = -1.0
    for i in range(count):
        g0, g1 = before[Event.CONTACT + i], after[Event.CONTACT + i]
        d0, d1 = h * slopes_before[i], h * slopes_after[i]
        sign = 1.0 if loaded[i] != 0.0 else -1.0  # loaded: watch for a dip below zero
        if sign * g0 < 0.0 or sign * g1 < 0.0:
            continue
        margin = GRAZING_MARGIN * (abs(d0) + abs(d1))
        # the cubic's slope terms lift or lower it by at most 4/27 of |d0| + |d1|
        if min(sign * g0, sign * g1) > margin + 4.0 / 27.0 * (abs(d0) + abs(d1)):
            continue
        turning = cubic_turning_points(g0, g1, d0, d1)
        for s in turning:
            if 0.0 < s < 1.0 and sign * hermite_value(g0, g1, d0, d1, s) < margin:
                if earliest < 0.0 or s < earliest:
                    earliest = s
    return earliest


@njit(cache=True, error_model="numpy", inline="always")
def cubic_turning_points(g0, g1, d0, d1):
    """The zeros (−1 for none) of the slope of the Hermite cubic p(s) = g0 + d0·s + c2·s² +
    c3·s³ on [0, 1] with values g0, g1 and slopes d0, d1 at its ends."""
    c2 = 3.0 * (g1 - g0) - 2.0 * d0 - d1
    c3 = 2.0 * (g0 - g1) + d0 + d1
    # p'(s) = d0 + 2·c2·s + 3·c3·s² = 0
    a, b, c = 3.0 * c3, 2.0 * c2, d0
    first = second = -1.0
    if a == 0.0:
        if b != 0.0:
            first = -c / b
    else:
        discriminant = b * b - 4.0 * a * c
        if discriminant >= 0.0:
            root = math.sqrt(discriminant)
            first, second = (-b - root) / (2.0 * a), (-b + root) / (2.0 * a)
    return (first, second)


@njit(cache=True, error_model="numpy", inline="always")
def hermite_value(g0, g1, d0, d1, s):
    """The Hermite cubic of cubic_turning_points at s."""
    c2 = 3.0 * (g1 - g0) - 2.0 * d0 - d1
    c3 = 2.0 * (g0 - g1) + d0 + d1
    return g0 + s * (d0 + s * (c2 + s * c3))


@njit(cache=True, error_model="numpy")
def probe_inside(system, segment, settings, state, workspace, suspect, h, event):
    """The grazing probe of a step of h (s) from `state` that crossed `event` (−1: none) by its
    end: trial steps to fractions of it, in increasing order, the suspect turning point (a
    fraction, grazing_suspect's) among PROBE_FRACTIONS, until one shows an event crossed. One
    that does becomes the bracket's end: its state goes to NEW_STATE, its event values to the
    AFTER row. Returns (the event crossed first, or −1; the bracket's end, s)."""
    done = 0.0
    for _ in range(len(PROBE_FRACTIONS) + 1):
        fraction = 2.0
        for candidate in PROBE_FRACTIONS:  # the next fraction after `done`, the suspect's too
            if done < candidate < fraction:
                fraction = candidate
        if done < suspect < fraction:
            fraction = suspect
        if fraction >= 1.0:
            break
        done = fraction
        found, high = probe_at(system, segment, settings, state, workspace, fraction, h, -1)
        if found >= 0:
            return found, high
    return event, h


@njit(cache=True, error_model="numpy", inline="always")
def probe_at(system, segment, settings, state, workspace, fraction, h, event):
    """A trial step to `fraction` of a step of h (s) from `state` that crossed `event` (−1:
    none) by its end. Where it shows an event crossed, it becomes the bracket's end: its
    state goes to NEW_STATE, its event values to the AFTER row. Returns (the event crossed
    first, or `event`; the bracket's end, s)."""
    vectors, values = workspace.vectors, workspace.values
    trial = vectors[Vector.TRIAL]
    if fraction >= 1.0:
        return event, h
    trial_step(system, segment, settings, state, workspace, fraction * h, trial)
    event_values(system, segment, trial, values[Values.APPROACH], values[Values.TRIAL])
    found = first_crossing(values[Values.BEFORE], values[Values.TRIAL], segment.events,
                           segment.loaded)
    if found < 0:
        return event, h
    copy_into(vectors[Vector.NEW_STATE], trial)
    copy_into(values[Values.AFTER], values[Values.TRIAL])
    return found, fraction * h


# --- the steps of the loop --------------------------------------------------------------------

@njit(cache=True, error_model="numpy", inline="always")
def plan_step(max_step, time, end, h, ahead, crossing, settings):
    """The next step from `time` (s) with the controller's step size h (s): at most the
    settings' max step, stretched by a hair to land on `end` rather than leave a remainder of
    rounding size, or cut to end just past the phase event predicted `ahead` s from now
    (event_ahead; inf for none, and for Radau IIA, whose error stopped falling with the
    step size in the order test when its steps were aimed): by PREDICTION_MARGIN of it, or
    where that is the modal solution's `crossing` itself, by the event location's
    tolerance, so that the location needs no trial step. `max_step` (s): the `settings`'
    for the segment's method. Returns the StepPlan."""
    h_wanted = min(h, max_step)
    landing = end - time <= h_wanted * (1.0 + 1e-7)
    h_step = end - time if landing else h_wanted
    # a step that would pass the next phase event ends just past it instead: the event is
    # then located by a single trial step (or none), and nothing of the step past it is
    # thrown away
    passing = (ahead + location_tolerance(settings, ahead) if crossing
               else (1.0 + PREDICTION_MARGIN) * ahead)
    if PREDICTION_FLOOR * h_step < passing < h_step:
        return StepPlan(passing, h_wanted, False, True)
    return StepPlan(h_step, h_wanted, landing, False)


@njit(cache=True, error_model="numpy", inline="always")
def next_plan(system, segment, settings, state, workspace, rows, explicit, clock, target):
    """The StepPlan from the run's `clock` (its time and step size, s) towards `target` (s):
    plan_step with the segment's max step and the phase event event_ahead predicts."""
    ahead, crossing = event_ahead(system, segment, state, workspace, rows.rate, explicit)
    return plan_step(settings[Setting.EXACT_MAX_STEP if segment.exact >= 0
                              else Setting.MAX_STEP], clock[0], target, clock[1], ahead,
                     crossing, settings)


@njit(cache=True, error_model="numpy", inline="always")
def step_allowed(steps, max_steps, time, plan):
    """Status.OVER_BUDGET where `steps` steps have been taken of `max_steps` (checked before a
    step, where the position is a consistent one), STEP_TOO_SMALL where the planned step no
    longer moves the time (s) but for rounding, else OK."""
    if steps >= max_steps:
        return Status.OVER_BUDGET
    if not plan.landing and plan.h_step <= 1e-15 * max(abs(time), 1.0):
        return Status.STEP_TOO_SMALL
    return Status.OK


def implicit_step(system, segment, settings, state, workspace, h, rejected):
    """`radau_step` where the workspace is Radau IIA's; never called (and nothing compiled)
    where it is DOP853's, whose loop takes the explicit branch."""


@overload(implicit_step)
def _implicit_step(system, segment, settings, state, workspace, h, rejected):
    # radau_step itself, compiled as a call of its own (a wrapper that called it would count
    # every array it passes on: 5 % of a Radau IIA step)
    if _lacks(workspace, "matrices"):
        return lambda system, segment, settings, state, workspace, h, rejected: (
            False, math.inf, 0)
    return radau_step


def radau_step(system, segment, settings, state, workspace, h, rejected):
    """One step of Radau IIA of size h (s) from `state` to NEW_STATE, with the Jacobian of the
    segment (made at its first step) and LU factors for h (kept while h stays), as the
    workspace's counters and memory record them; `rejected`: whether the step before it was
    (radau.step estimates an error over 1 again then). Returns (retry: Newton failed on an old
    Jacobian, which is dropped, and the step is to be tried again; the error norm, inf where
    Newton did not converge; Newton iterations)."""
    vectors, counters, memory = workspace.vectors, workspace.counters, workspace.memory
    if counters[Counter.JACOBIAN_SEGMENT] != counters[Counter.SEGMENT]:
        radau.jacobian_of(system, segment, state, vectors[Vector.RATE],
                          settings[Setting.ABSOLUTE_TOLERANCE:],
                          settings[Setting.RELATIVE_TOLERANCE], workspace.matrices[JACOBIAN],
                          vectors[Vector.TRIAL], vectors[Vector.WORK])
        counters[Counter.JACOBIAN_SEGMENT] = counters[Counter.SEGMENT]
        counters[Counter.JACOBIAN_FRESH] = 1
        memory[Memory.FACTORED_H] = 0.0
    if h != memory[Memory.FACTORED_H]:
        factorize_for(workspace, h)
    error, iterations = factored_step(system, segment, settings, state, workspace, h,
                                      vectors[Vector.NEW_STATE], rejected)
    if math.isinf(error) and counters[Counter.JACOBIAN_FRESH] == 0:
        counters[Counter.JACOBIAN_SEGMENT] = -1  # Newton failed on an old Jacobian: refresh it
        return True, error, iterations
    return False, error, iterations


@njit(cache=True, error_model="numpy", inline="always")
def control_step(explicit, error, iterations, plan, controller):
    """Accept the step of `plan` (a StepPlan) with this error norm and Newton iterations, or
    reject it, by the explicit or the implicit method's controller (its memory a
    Controller). Returns (accepted; the step size to try next, s; the Controller)."""
    previous_error, rejected = controller.previous_error, controller.rejected
    previous_h = controller.previous_h
    h_step, h_wanted, landing, aimed = plan.h_step, plan.h_wanted, plan.landing, plan.aimed
    prediction = (1.0 if explicit
                  else radau.predicted_factor(h_step, error, previous_h, previous_error))
    if not error <= 1.0:  # too large, or NaN
        factor = (dop853.step_factor(error, previous_error, rejected) if explicit
                  else radau.step_factor(error, iterations, rejected, prediction))
        return (False, h_step * (factor if math.isfinite(error) else 0.5),
                Controller(previous_error, True, previous_h))
    if explicit:
        factor = dop853.step_factor(error, previous_error, rejected)
        if not (landing or aimed):  # a cut step's small error would hold the next one back
            previous_error = max(error, 1e-4)
    else:
        factor = radau.step_factor(error, iterations, rejected, prediction)
        if factor < 1.2:
            factor = 1.0  # keep the factorization (scipy's rule)
        if not (landing or aimed):
            previous_error, previous_h = error, h_step
    h_next = h_step * factor
    if landing or aimed:  # a step cut short says little about the next one
        h_next = max(h_next, h_wanted)
    return True, h_next, Controller(previous_error, False, previous_h)


@njit(cache=True, error_model="numpy", inline="always")
def control_exact_step(verdict, plan, floor, rejected):
    """Accept or reject an exact step of `plan` (a StepPlan) by its certificate's `verdict`
    (exponential.step's). A certified one is accepted and the next may be EXACT_GROWTH times
    longer, or as long where the step before it was `rejected` (its growth would try again
    what was just refused: near a landing the certifiable step shrinks as the approach
    closes). One whose phase events are sure is accepted at the exact floor `floor` (s;
    Setting.EXACT_FLOOR) or below, where the approach's modal solution shows a crossing
    its ends do not (grazing_probe), and the next may grow up to `floor`; one that is not (the
    pinion may turn back across an end of its interval and return, which no end shows) only
    at TURN_BACK_FLOOR of `floor`. A longer one is rejected and tried EXACT_SHRINK times as
    long, not below where it would be accepted. A step cut short (landing on the end, aimed
    at a phase event) keeps the size the loop wanted, or grows from its own where that is
    longer: the size it wanted was not tried, and growing it at every cut step let it run
    away (to 1e44 s in 30 ms driven every 1 ms, to inf every 0.1 ms), and the next uncut
    step was refused by the certificate again and again. Returns (accepted; the step size to
    try next, s)."""
    h_step = plan.h_step
    grown = h_step * (1.0 if rejected else EXACT_GROWTH)
    if plan.landing or plan.aimed:
        grown = max(grown, plan.h_wanted)
    if verdict == exponential.CERTIFIED:
        return True, grown
    lowest = floor if verdict == exponential.PHASE_SURE else TURN_BACK_FLOOR * floor
    if h_step <= lowest:
        return True, min(floor, grown)
    return False, max(lowest, EXACT_SHRINK * h_step)


@njit(cache=True, error_model="numpy", inline="always")
def crossed_event(system, segment, new_state, values):
    """The event values at the end of a step (NEW_STATE; into the AFTER row of `values`), and
    which event the step crossed first (−1: none)."""
    after = values[Values.AFTER]
    event_values(system, segment, new_state, values[Values.APPROACH], after)
    return first_crossing(values[Values.BEFORE], after, segment.events, segment.loaded)


@njit(cache=True, error_model="numpy", inline="always")
def grazing_check(system, segment, state, rate, new_state, rate_after, values, h):
    """The grazing check of a step of h (s) from `state` (its rate `rate`), where contact can
    be lost: the approach slopes at its end (from `new_state` and its rate; into the
    SLOPES_AFTER row of `values`), and where inside the step, as a fraction of it, a point
    may lift off and land again (or touch and leave) unseen by its ends, also before an event
    the step's end shows (a dip inside a short contact interval): grazing_suspect's turning
    point, −1 for none. The slopes at its start are taken from `state` and `rate` where the
    step before did not take them (a certified exact step leaves them NaN)."""
    slopes_before, slopes_after = approach_slopes(system, segment, state, rate, new_state,
                                                  rate_after, values)
    return grazing_suspect(values[Values.BEFORE], values[Values.AFTER],
                           slopes_before, slopes_after, h, segment.point_count,
                           segment.loaded)


@njit(cache=True, error_model="numpy", inline="always")
def approach_slopes(system, segment, state, rate, new_state, rate_after, values):
    """The approach slopes (m/s) at a step's end (from `new_state` and its rate) into the
    SLOPES_AFTER row of `values`, and at its start (from `state` and `rate`) into SLOPES_BEFORE
    where the step before did not take them (a certified exact step leaves them NaN).
    Returns the two rows."""
    slopes_before, slopes_after = values[Values.SLOPES_BEFORE], values[Values.SLOPES_AFTER]
    if math.isnan(slopes_before[0]):
        approach_rates(system, segment.points, segment.point_count, state, rate, slopes_before)
    approach_rates(system, segment.points, segment.point_count, new_state, rate_after, slopes_after)
    return slopes_before, slopes_after


@njit(cache=True, error_model="numpy", inline="always")
def finish_step(state, workspace):
    """Make the accepted step's end, which crossed no event, the new start: state, rate,
    event values and approach slopes."""
    vectors, values = workspace.vectors, workspace.values
    copy_into(state, vectors[Vector.NEW_STATE])
    copy_into(vectors[Vector.RATE], vectors[Vector.RATE_AFTER])
    copy_into(values[Values.BEFORE], values[Values.AFTER])
    copy_into(values[Values.SLOPES_BEFORE], values[Values.SLOPES_AFTER])


@njit(cache=True, error_model="numpy", inline="always")
def begin_segment(system, mesh, interval, state, loaded, torques, workspace, exact):
    """The CompiledSegment of contact interval `interval` (segment_of; `exact`: its exact form
    at `state`, exact_form's, which the caller has made), with the rate, event values and
    (where contact can be lost) approach slopes at `state`, its start, in the workspace."""
    segment = segment_of(system, mesh, interval, loaded, torques, exact)
    rate, values = workspace.vectors[Vector.RATE], workspace.values
    derivative(system, segment.points, segment.point_count, loaded, torques[0], torques[1], state,
               rate)
    event_values(system, segment, state, values[Values.APPROACH], values[Values.BEFORE])
    if system.contact_loss:
        approach_rates(system, segment.points, segment.point_count, state, rate,
                       values[Values.SLOPES_BEFORE])
    return segment


# --- event location -----------------------------------------------------------------------------

@njit(cache=True, error_model="numpy", inline="always")
def next_estimate(event, older_h, older_value, newer_h, newer_value, newer_slope):
    """Where (s from the step's start) event function `event` crosses zero, from its two
    latest values: Newton's step from the newer where its slope there is known (event_slope),
    else the secant's zero (a contact's slope at a step's end that the grazing check did not
    take is NaN); −1 where neither gives one."""
    if newer_slope != 0.0 and math.isfinite(newer_slope):
        return newer_h - newer_value / newer_slope
    if newer_value != older_value:
        return newer_h - newer_value * (newer_h - older_h) / (newer_value - older_value)
    return -1.0


@njit(cache=True, error_model="numpy", inline="always")
def location_estimate(trials, estimate, low, high):
    """Where the next trial of a location aims (s from the step's start), after `trials`
    trials, given the Newton or secant `estimate` and the bracket [low, high): the estimate,
    but the bracket's middle where the estimate lies outside it or NEWTON_LOCATION_TRIALS
    trials have not closed it. Newton's estimates close a bracket in one to ten trials; where
    an event function stays at zero over a stretch (rounding), they stay at its low end and
    the trials, aimed just past them, creep up by the event time tolerance each, which sixty
    trials do not close. Bisection closes any bracket within the trials left."""
    if trials >= NEWTON_LOCATION_TRIALS or not low <= estimate < high:
        return 0.5 * (low + high)
    return estimate


@njit(cache=True, error_model="numpy", inline="always")
def first_estimate(system, state, new_state, values, event, high, h_step, tolerance):
    """Where (s from the step's start) `event` crosses zero inside a whole step of h_step (s)
    that crossed it (`high` == h_step: NEW_STATE and the AFTER values at its end), from its
    values and slopes at both ends: for a phase event that the step passed by no more than
    twice the location `tolerance` (s) by its tangent at the end (a step aimed past the
    modal solution's crossing, plan_step), that tangent's zero, which ends the location
    without a trial; else the zero of the cubic through them (hermite_root), fifty times
    closer than the chord's. A phase event's slope is φp's rate, in the state; a point's, its
    approach rate, which the grazing check took at both ends (the SLOPES rows, marked not
    taken by a NaN first entry). −1 where there is none."""
    if high != h_step:
        return -1.0
    if event < Event.CONTACT:
        pinion_rate = state.shape[0] // 2 + system.pinion
        slope_before, slope_after = state[pinion_rate], new_state[pinion_rate]
        past = values[Values.AFTER, event] / slope_after
        if 0.0 <= past <= 2.0 * tolerance:
            return high - past
    else:
        before, after = values[Values.SLOPES_BEFORE], values[Values.SLOPES_AFTER]
        if math.isnan(before[0]) or math.isnan(after[0]):
            return -1.0
        slope_before, slope_after = before[event - Event.CONTACT], after[event - Event.CONTACT]
    return high * hermite_root(values[Values.BEFORE, event], values[Values.AFTER, event],
                               high * slope_before, high * slope_after)


@njit(cache=True, error_model="numpy", inline="always")
def location_tolerance(settings, h_step):
    """How closely (s) an event is located in a step of h_step (s): the settings' event time
    tolerance, not below the step's rounding. A located crossing lies within twice this
    before the bracket's high end."""
    return max(settings[Setting.EVENT_TIME_TOLERANCE], 1e-14 * h_step)


@njit(cache=True, error_model="numpy", inline="always")
def location_start(system, segment, state, workspace, event, high, h_step, tolerance):
    """The first estimate of where `event` crosses inside a step of h_step (s) that crossed
    it by `high` (s): the zero of the cubic through its values and slopes at the step's ends
    (first_estimate), and for a contact in an exact segment the crossing of the approach's
    modal solution from there (exact_crossing: the location's first trial then ends the
    bracket just past the crossing), where that converges."""
    estimate = first_estimate(system, state, workspace.vectors[Vector.NEW_STATE],
                              workspace.values, event, high, h_step, tolerance)
    if event < Event.CONTACT or segment.exact < 0:
        return estimate
    crossing = exact_crossing(system, segment, state, workspace, high, estimate)
    return crossing if crossing > 0.0 else estimate


@njit(cache=True, error_model="numpy", inline="always")
def points_together(segment, event, before, after):
    """Whether the crossings from `before` to `after` (event values) are all points' and
    `event` one of them, in an exact segment: its points' approaches are one function there
    (to the tilt's rounding; exponential._approach), so they cross together, and no trial
    just before the located crossing is needed to tell which came first."""
    return (segment.exact >= 0 and event >= Event.CONTACT
            and not crosses(before, after, Event.PHASE_END, segment.loaded)
            and not crosses(before, after, Event.PHASE_START, segment.loaded))


@njit(**NUMBERS_ONLY)
def locate_event(system, segment, settings, state, workspace, event, high, h_step):
    """Locate the crossing of `event` inside the bracket [0, high] of step sizes (s) from
    `state` (NEW_STATE and the AFTER row of values hold the state and event values at `high`),
    by trial steps of the method, to the event time tolerance. The first estimate is
    location_start's; the next ones Newton's from the latest trial (its slope: event_slope),
    until a bisection takes over (location_estimate). Trials are judged against the
    bracket's low end, so that of several events crossed the earliest is taken (a trial just
    before the located crossing tells, unless they are points of an exact set:
    points_together).
    Returns (the event; the bracket's high end, s, its state in NEW_STATE)."""
    vectors, values = workspace.vectors, workspace.values
    new_state, trial = vectors[Vector.NEW_STATE], vectors[Vector.TRIAL]
    low_values, high_values = values[Values.LOW], values[Values.HIGH]
    trial_values = values[Values.TRIAL]
    low = 0.0
    copy_into(low_values, values[Values.BEFORE])
    copy_into(high_values, values[Values.AFTER])
    older_h, older_value = low, low_values[event]  # the two latest points, for the secant
    newer_h, newer_value = high, high_values[event]
    # (a contact's slope at `high` is the grazing check's, where it took one)
    newer_slope = (values[Values.SLOPES_AFTER, event - Event.CONTACT] if event >= Event.CONTACT
                   else event_slope(system, segment, new_state, workspace, event))
    tolerance = location_tolerance(settings, h_step)
    estimate = location_start(system, segment, state, workspace, event, high, h_step,
                              tolerance)
    for trials in range(MAX_LOCATION_TRIALS):
        # whatever crossed in between crossed together, to the tolerance (written as the
        # trial just before a crossing is placed, high − 2·tolerance, so that one ends it)
        if low >= high - 2.0 * tolerance:
            break
        if estimate < 0.0:
            estimate = next_estimate(event, older_h, older_value, newer_h, newer_value,
                                     newer_slope)
        estimate = location_estimate(trials, estimate, low, high)
        if high - estimate <= 2.0 * tolerance:
            # located, unless another event that had also crossed by `high` crossed
            # earlier: then a trial just before this crossing says which
            if crossings(low_values, high_values, segment.events, segment.loaded) == 1 or \
                    points_together(segment, event, low_values, high_values):
                break
            trial_h = high - 2.0 * tolerance
        else:
            # aim just past the estimate, so that a good estimate ends the search at once
            trial_h = estimate + tolerance
        estimate = -1.0
        trial_step(system, segment, settings, state, workspace, trial_h, trial)
        event_values(system, segment, trial, values[Values.APPROACH], trial_values)
        crossed = first_crossing(low_values, trial_values, segment.events, segment.loaded)
        if crossed < 0:
            older_h, older_value, low = newer_h, newer_value, trial_h
            copy_into(low_values, trial_values)
        else:
            older_h, older_value = ((low, low_values[crossed]) if crossed != event
                                    else (newer_h, newer_value))
            event, high = crossed, trial_h  # (another event that crosses first is located)
            copy_into(new_state, trial)
            copy_into(high_values, trial_values)
        newer_h, newer_value = trial_h, trial_values[event]
        newer_slope = event_slope(system, segment, trial, workspace, event)
    return event, high


@njit(cache=True, error_model="numpy", inline="always")
def event_slope(system, segment, state, workspace, event):
    """The rate of event function `event` at `state`: φp's (in the state) for a phase event,
    the point's approach rate (equations.approach_rates; m/s) for a contact. The workspace's
    RATE_AFTER and APPROACH rows serve as scratch: the location needs neither."""
    if event < Event.CONTACT:
        return state[state.shape[0] // 2 + system.pinion]
    rate, slopes = workspace.vectors[Vector.RATE_AFTER], workspace.values[Values.APPROACH]
    derivative(system, segment.points, segment.point_count, segment.loaded,
               segment.motor_torque, segment.load_torque, state, rate)
    approach_rates(system, segment.points, segment.point_count, state, rate, slopes)
    return slopes[event - Event.CONTACT]


@njit(**NUMBERS_ONLY)
def violated_before(system, segment, settings, state, workspace, high, h_step):
    """A debug run's check of a step from `state` to a crossing located at `high` (s) in a
    step of h_step (s), where no other point may have crossed unseen
    (contact_violated_inside); the event's own crossing lies within two location
    tolerances of `high`, so a step that short is not looked into. False in a run that is not
    a debug run."""
    tolerance = location_tolerance(settings, h_step)
    return (settings[Setting.CONTACT_SLACK] >= 0.0 and system.contact_loss
            and high > 16.0 * tolerance
            and contact_violated_inside(system, segment, settings, state, workspace, high))


# --- the segment's end --------------------------------------------------------------------------

@njit(cache=True, error_model="numpy", inline="always")
def count_progress(counters, event, high, h_step):
    """Whether the run still moves after an event located at `high` (s) into a step of h_step
    (s), by the counters of events in a row without progress and of phase events in a row that
    reversed the last one: Status.OK, STALLED or CHATTER."""
    stalled = counters[Counter.STALLED] + 1 if high <= 1e-12 * h_step else 0
    counters[Counter.STALLED] = stalled
    if stalled > MAX_EVENTS_WITHOUT_PROGRESS:
        return Status.STALLED
    if event < Event.CONTACT:
        reversals = (counters[Counter.REVERSALS] + 1
                     if event != counters[Counter.LAST_PHASE_EVENT] else 0)
        counters[Counter.REVERSALS], counters[Counter.LAST_PHASE_EVENT] = reversals, event
        if reversals > MAX_PHASE_REVERSALS:
            return Status.CHATTER
    return Status.OK


@njit(cache=True, error_model="numpy", inline="always")
def pass_event(state, workspace, clock, time, end, plan, high, event):
    """Move the run past the crossing of `event` located at `high` (s from the step's start)
    by the accepted step of `plan` (a StepPlan) from `time` (s; where the step would land:
    `end`): the state there (NEW_STATE) and the time. Returns count_progress's Status."""
    copy_into(state, workspace.vectors[Vector.NEW_STATE])
    clock[0] = end if plan.landing and high == plan.h_step else time + high
    return count_progress(workspace.counters, event, high, plan.h_step)


@njit(cache=True, error_model="numpy", inline="always")
def opening_ahead(system, mesh, run, workspace, segment, exact, horizon):
    """Where the run has just entered an exact segment forward (end_segment; the torques
    those of `segment`, the one it left; `exact`: the new segment's exact form): when the
    next phase event lies ahead (exponential.modal_phase_event_ahead, from the modal
    solution), for the opening step to be aimed at, and what kind of time that is (inf where
    the angle surely stays inside its interval until `horizon`, s: where the call stops);
    (−1, exponential.NO_AIM) elsewhere. φp's acceleration just after a switch is the fast
    modes' (1e6 rad/s² and more), so phase_event_ahead's extrapolation lands the opening step
    halfway. Taken here, once an event, where it was measured to cost least
    (docs/exponential-measurements.md, "An opening step aimed by the slow motion")."""
    if workspace.counters[Counter.OPENING] < 0 or exact < 0:
        return -1.0, exponential.NO_AIM
    return exact_event_ahead(system, workspace, exact, run.state, segment.motor_torque,
                             segment.load_torque, mesh.lengths[run.place[0]], horizon)


@njit(cache=True, error_model="numpy", inline="always")
def enter_next_segment(system, mesh, run, workspace, segment, event, end):
    """The run, past `event` (pass_event), moved into the segment that follows (end_segment),
    that segment's exact form made, and after a forward entry into an exact one its opening
    step aimed (opening_ahead, the call stopping at `end`, s; remember_modal_aim). `segment`:
    the one left, whose torques are held. Returns the new segment's exact form."""
    end_segment(system, mesh, run, workspace, event)
    interval = run.place[0]
    exact = exact_form(workspace, interval, mesh.counts[interval], run.loaded, run.state)
    ahead, aim = opening_ahead(system, mesh, run, workspace, segment, exact, end - run.clock[0])
    remember_modal_aim(workspace, ahead, aim)
    return exact


@njit(cache=True, error_model="numpy", inline="always")
def call_opening_ahead(system, mesh, run, workspace, segment, horizon):
    """Where a call of `advance` begins inside an exact segment (`segment`, begun at the run's
    state): when the next phase event lies ahead, and what kind of time that is, as
    opening_ahead gives them at a segment's entry (`horizon`, s: how far the call goes);
    (−1, exponential.NO_AIM) elsewhere, and where the event is far beyond the horizon
    (CALL_REACH). The FMU's calls begin mid-segment, where φp's acceleration still carries
    the fast modes' ringing: aimed by phase_event_ahead, a quarter of the reference scene's
    1 ms calls took four steps for their one event. The modal coordinates it makes are the
    ones the call's first step starts from (exponential._start_from)."""
    state, pinion = run.state, system.pinion
    speed, length = state[state.shape[0] // 2 + pinion], mesh.lengths[run.place[0]]
    way = length - state[pinion] if speed > 0.0 else state[pinion]
    if segment.exact < 0 or way > CALL_REACH * abs(speed) * horizon:
        return -1.0, exponential.NO_AIM
    return exact_event_ahead(system, workspace, segment.exact, run.state, segment.motor_torque,
                             segment.load_torque, length, horizon)


@njit(cache=True, error_model="numpy", inline="always")
def open_walk(system, mesh, settings, run, workspace, end, torques, max_steps, samples, k):
    """walk's start: the segment the run is in begun (begin_segment), its first step aimed
    (aim_first_step), and where that is the modal solution's crossing of the phase end, the
    switches from there taken by chain_switches, as after an event. Returns (its Status,
    the steps it took, the next sample's index, the CompiledSegment the run is then in, begun
    there)."""
    interval = run.place[0]
    exact = exact_form(workspace, interval, mesh.counts[interval], run.loaded, run.state)
    aim_first_step(system, mesh, run, workspace,
                   segment_of(system, mesh, interval, run.loaded, torques, exact), samples, k,
                   end)
    status, steps, k, exact = chain_switches(system, mesh, settings, run, workspace, exact,
                                             torques, end, samples, k, 0, max_steps)
    return status, steps, k, begin_segment(system, mesh, run.place[0], run.state, run.loaded,
                                           torques, workspace, exact)


@njit(cache=True, error_model="numpy", inline="always")
def aim_first_step(system, mesh, run, workspace, segment, samples, k, end):
    """At a call's start: call_opening_ahead's aim for its first step, to where the call
    stops (stop_at: `end`, s, or the `k`-th of `samples`), remembered (remember_modal_aim)."""
    horizon = stop_at(samples, k, end, segment.exact) - run.clock[0]
    ahead, aim = call_opening_ahead(system, mesh, run, workspace, segment, horizon)
    remember_modal_aim(workspace, ahead, aim)


@njit(cache=True, error_model="numpy", inline="always")
def remember_modal_aim(workspace, ahead, aim):
    """Keep the modal solution's aim for the next step (event_ahead): `ahead` (s) and what
    kind of time it is, `aim` (exponential.CROSSING, NEAR, BOUND, or NO_AIM: none)."""
    workspace.memory[Memory.MODAL_AHEAD] = ahead
    workspace.memory[Memory.MODAL_AIM] = aim


@njit(cache=True, error_model="numpy", inline="always")
def end_segment(system, mesh, run, workspace, event):
    """Move the run into the segment that follows `event` at its state: the next contact set
    and its loaded points (next_segment, into the run's place and loaded points), and after a
    phase event into the next set, its first step size. (The loop then begins the segment
    there: begin_segment.)"""
    clock, place, state, loaded = run.clock, run.place, run.state, run.loaded
    counters = workspace.counters
    place[0], place[1] = next_segment(system, mesh, event, place[0], place[1], state, loaded,
                                      workspace.values[Values.APPROACH])
    counters[Counter.SEGMENT] += 1
    interval = place[0]
    # The switch sets off vibration that the step before it did not see: start the set as the
    # step taken after the last entry into it proposed (the mesh repeats).
    entered, first = event == Event.PHASE_END, run.first_steps[interval]
    clock[1] = min(clock[1], first) if entered and first > 0.0 else clock[1]
    counters[Counter.OPENING] = interval if entered else counters[Counter.OPENING]


@njit(cache=True, error_model="numpy", inline="always")
def next_segment(system, mesh, event, interval, cycle, state, loaded, approach):
    """What follows an event: a phase event moves to the next (or previous) contact set and
    re-expresses the pinion entry of `state` from the new set's start (by lengths, not
    absolute angles, so it stays exact however far the train has turned); then every point
    of the set is loaded by the sign of its approach. That rule, not a flip of the point
    whose event fired, is what keeps the loaded set true to the state: a point that crossed
    zero in the same bracket as the located event (a whole train separating or landing at
    once) starts the segment on its own side, with its own event ahead of it. Updates state
    and loaded (`approach` is scratch); returns the new (interval, cycle)."""
    lengths = mesh.lengths
    if event == Event.PHASE_END:
        state[system.pinion] -= lengths[interval]
        interval += 1
        if interval == lengths.shape[0]:
            interval, cycle = 0, cycle + 1
    elif event == Event.PHASE_START:
        interval -= 1
        if interval < 0:
            interval, cycle = lengths.shape[0] - 1, cycle - 1
        state[system.pinion] += lengths[interval]
    set_loaded_by_sign(system, mesh.tables[interval], mesh.counts[interval], state, approach,
                       loaded)
    return interval, cycle


@njit(cache=True, error_model="numpy", inline="always")
def set_loaded_by_sign(system, points, count, state, approach, loaded):
    """Which points of a new set carry load: all, or where contact can be lost, those whose
    approach δ + η·δ̇ is not negative (segments.py). `approach` is scratch."""
    loaded[:] = 0.0
    if system.contact_loss:
        approaches(system, points, count, state, approach)
    for i in range(count):
        loaded[i] = 1.0 if not system.contact_loss or approach[i] >= 0.0 else 0.0


# --- the loop ---------------------------------------------------------------------------------

@njit(cache=True, error_model="numpy", inline="always")
def copy_into(target, source):
    """target[:] = source, entry by entry: a slice assignment may copy through a buffer from
    the heap, which `advance` (compiled without the heap's reference counts) cannot use."""
    for j in range(source.shape[0]):
        target[j] = source[j]


@njit(cache=True, error_model="numpy", inline="always")
def all_finite(state):
    """Whether every entry of `state` is finite."""
    for j in range(state.shape[0]):
        if not math.isfinite(state[j]):
            return False
    return True


@njit(cache=True, error_model="numpy", inline="always")
def advance_to(constants, exact, implicit, run, end, torques, max_steps, samples, k):
    """One stretch of advance's (`samples`: its Samples, the `k`-th the next to take): the run
    integrated to `end`, or to where `stop_at` stops it first. Returns (the Status's value,
    accepted steps, the next sample's index)."""
    system, mesh, settings, run, workspace = unpack_records(constants, exact, implicit, run)
    begin_walk(workspace)
    status, steps, k = walk(system, mesh, settings, run, workspace, end, torques, max_steps,
                            samples, k)
    if status == Status.OK and not all_finite(run.state):
        status = Status.NOT_FINITE
    interval = run.place[0]
    # every method ends within its contact interval; a state past it (one so large that its
    # rounding hides the phase events: a torque of 1e300 N·m) is no result to return
    length = mesh.lengths[interval]
    if status == Status.OK and not (-PHASE_SLACK * length <= run.state[system.pinion]
                                    <= (1 + PHASE_SLACK) * length):
        status = Status.LEFT_INTERVAL
    outputs(system, mesh.tables[interval], mesh.counts[interval], run.loaded, run.state,
            run.outputs)
    return status.value, steps, k  # an int: numba hands an IntEnum member back at 0.8 µs a call


@njit(cache=True, error_model="numpy", inline="always")
def walk(system, mesh, settings, run, workspace, end, torques, max_steps, samples, k):
    """advance's loop (after begin_walk): steps and events (cross_event, chain_switches) to
    `end` or where stop_at stops it, unless the run fails, taking the samples (a Samples)
    from the `k`-th that exact segments pass. Returns (Status, steps, next sample)."""
    clock, state, first_steps = run.clock, run.state, run.first_steps
    counters, values, rows = workspace.counters, workspace.values, step_rows(workspace, settings)
    explicit = is_explicit(workspace)
    status, steps, k, segment = open_walk(system, mesh, settings, run, workspace, end, torques,
                                          max_steps, samples, k)
    controller, h = Controller(1e-4, False, 0.0), clock[1]
    while status == Status.OK:
        target = stop_at(samples, k, end, segment.exact)
        if clock[0] >= target:
            break
        time, h = clock[0], clock[1]
        plan = next_plan(system, segment, settings, state, workspace, rows, explicit, clock, target)
        status = step_allowed(steps, max_steps, time, plan)
        if status != Status.OK:
            break
        if segment.exact >= 0:
            certified, accepted, clock[1], controller = take_exact_step(
                system, segment, settings, state, workspace, rows, plan, controller)
        else:
            retry, accepted, h_next, controller = runge_kutta_step(
                system, segment, settings, state, workspace, rows, plan, controller)
            if retry:  # (Newton failed on an old Jacobian: again on a fresh one)
                continue
            certified, clock[1] = False, h_next
        if not accepted:
            continue
        steps, counters[Counter.JACOBIAN_FRESH] = steps + 1, 0
        # (here, not in a helper: from an inlined one numba 0.68 dropped this store)
        if counters[Counter.OPENING] >= 0 and not (plan.landing or plan.aimed):
            first_steps[counters[Counter.OPENING]] = clock[1]
        counters[Counter.OPENING], workspace.memory[Memory.MODAL_AIM] = -1, exponential.NO_AIM
        event = crossed_event(system, segment, rows.new_state, values)
        rate_after_step(system, segment, explicit, rows)
        event, high = probe_step(system, segment, settings, state, workspace, plan.h_step,
                                 event, certified)
        if event >= 0:
            status, k, exact = cross_event(system, mesh, settings, run, workspace, segment,
                                           plan, target, event, high, samples, k)
            if status == Status.OK:
                status, steps, k, exact = chain_switches(system, mesh, settings, run,
                                                         workspace, exact, torques, end,
                                                         samples, k, steps, max_steps)
                segment = begin_segment(system, mesh, run.place[0], state, run.loaded, torques,
                                        workspace, exact)
        elif settings[Setting.CONTACT_SLACK] >= 0.0 and system.contact_loss and \
                contact_violated_inside(system, segment, settings, state, workspace, plan.h_step):
            status = Status.CONTACT_VIOLATED
        else:
            reached = target if plan.landing else time + plan.h_step
            if segment.exact >= 0:
                k = sample_inside(samples, k, system, segment, state, workspace, time, reached)
            finish_step(state, workspace)
            clock[0], counters[Counter.STALLED] = reached, 0
    clock[1] = h if status == Status.CONTACT_VIOLATED else clock[1]
    return status, steps, k


@njit(cache=True, error_model="numpy", inline="always")
def runge_kutta_step(system, segment, settings, state, workspace, rows, plan, controller):
    """The step of `plan` (a StepPlan) from `state` by the workspace's Runge-Kutta method
    (DOP853, or Radau IIA by implicit_step) into NEW_STATE, judged by control_step with the
    Controller's memory. Returns (whether to try again: Radau IIA's Newton failed on an old
    Jacobian, so it takes a fresh one; accepted; the step size to try next, s; the
    Controller)."""
    explicit = is_explicit(workspace)
    if explicit:
        error, iterations = dop853.step(
            system, segment, state, rows.rate, plan.h_step, rows.tolerance,
            settings[Setting.RELATIVE_TOLERANCE], rows.stages, rows.work, rows.new_state), 0
    else:
        retry, error, iterations = implicit_step(system, segment, settings, state, workspace,
                                                 plan.h_step, controller.rejected)
        if retry:
            return True, False, plan.h_step, controller
    accepted, h_next, controller = control_step(explicit, error, iterations, plan, controller)
    workspace.counters[Counter.REJECTED_STEPS] += 0 if accepted else 1
    return False, accepted, h_next, controller


@njit(cache=True, error_model="numpy", inline="always")
def take_exact_step(system, segment, settings, state, workspace, rows, plan, controller):
    """The step of `plan` (a StepPlan) from `state` by the segment's exact solution into
    NEW_STATE, judged by control_exact_step with the Controller's memory of whether the step
    before was rejected. A step longer than the exact floor whose approach is not certified
    to keep its sign is certified where the approach is monotone over it
    (exponential.approach_monotone): it crosses at most once, as the step's ends show.
    Returns (certified; accepted; the step size to try next, s; the Controller)."""
    verdict = taken_step(workspace, plan.h_step)
    if verdict < 0:
        verdict = exact_step(system, segment, state, workspace, plan.h_step, rows.new_state)
    # (asked here, not inside exponential.step: a call there slows every exact step)
    if verdict == exponential.PHASE_SURE and plan.h_step > settings[Setting.EXACT_FLOOR] \
            and exact_monotone(workspace, segment, plan.h_step):
        verdict = exponential.CERTIFIED
    accepted, h_next = control_exact_step(verdict, plan, settings[Setting.EXACT_FLOOR],
                                          controller.rejected)
    workspace.counters[Counter.REJECTED_STEPS] += 0 if accepted else 1
    return (verdict == exponential.CERTIFIED, accepted, h_next,
            Controller(controller.previous_error, not accepted, controller.previous_h))


@njit(cache=True, error_model="numpy", inline="always")
def taken_step(workspace, h):
    """The verdict (exponential.step's) on the step of h (s) from the run's state where
    chain_switches took that step and left it to the loop (Memory.TAKEN_H: its state is in
    NEW_STATE, the same to the bit as taking it again), −1 where it did not; forgotten either
    way. The chain's opening step short of the switch and a call's last step, where it chains
    no landing or lift-off, are the loop's next step: taken again, each an exact step more."""
    memory = workspace.memory
    taken = memory[Memory.TAKEN_H] == h
    memory[Memory.TAKEN_H] = 0.0
    return int(memory[Memory.TAKEN_VERDICT]) if taken else -1


@njit(cache=True, error_model="numpy", inline="always")
def rate_after_step(system, segment, explicit, rows):
    """The rate at an accepted step's end (NEW_STATE) into RATE_AFTER: DOP853's last stage
    where it took the step, else the equations there."""
    if explicit and segment.exact < 0:
        copy_into(rows.rate_after, rows.last_stage)
    else:
        derivative(system, segment.points, segment.point_count, segment.loaded,
                   segment.motor_torque, segment.load_torque, rows.new_state, rows.rate_after)


@njit(cache=True, error_model="numpy", inline="always")
def probe_step(system, segment, settings, state, workspace, h_step, event, certified):
    """grazing_probe's answer for an accepted step where contact can be lost (where it cannot:
    the step's `event`, its end h_step, s). A `certified` exact step that crossed no contact
    event is answered here (nothing hidden; the approach slopes at its end not taken),
    without the call that hands over grazing_probe's records, word by word, at every such
    step (docs/exponential-measurements.md, "A call's records")."""
    if not system.contact_loss:
        return event, h_step
    if certified and event < Event.CONTACT:
        workspace.values[Values.SLOPES_AFTER, 0] = math.nan
        return event, h_step
    return grazing_probe(system, segment, settings, state, workspace, h_step, event, certified)


@njit(cache=True, error_model="numpy")
def grazing_probe(system, segment, settings, state, workspace, h_step, event, certified):
    """What an accepted step of h_step (s) hides between its ends (the rate at its end in
    RATE_AFTER). A `certified` exact step hides nothing; one that is not, its approach's
    modal solution shows (exact_dip), and where it lies past zero a probe there (probe_at)
    shrinks the bracket to it. Either marks the approach slopes at its end not taken, for
    the next step's check to take them if it needs them, or where it crossed a contact
    event takes them at both ends, for the location's first estimate. A step of DOP853 or
    Radau IIA has the grazing check of the cubic through its ends (grazing_check) and its
    probes (probe_inside). Returns (the event crossed first, −1 for none; the bracket's high
    end, s)."""
    vectors, values = workspace.vectors, workspace.values
    dip = -1.0 if certified else exact_dip(system, segment, state, workspace, h_step)
    if not math.isnan(dip):  # an exact step: its modal solution shows what lies inside
        if event >= Event.CONTACT:  # the location's first estimate takes the slopes
            approach_slopes(system, segment, state, vectors[Vector.RATE],
                            vectors[Vector.NEW_STATE], vectors[Vector.RATE_AFTER], values)
        else:
            values[Values.SLOPES_AFTER, 0] = math.nan
        if dip > 0.0:
            return probe_at(system, segment, settings, state, workspace, dip, h_step, event)
        return event, h_step
    suspect = grazing_check(system, segment, state, vectors[Vector.RATE],
                            vectors[Vector.NEW_STATE], vectors[Vector.RATE_AFTER], values, h_step)
    if suspect > 0.0:
        return probe_inside(system, segment, settings, state, workspace, suspect, h_step, event)
    return event, h_step


@njit(cache=True, error_model="numpy", inline="always")
def samples_before_event(samples, k, system, segment, settings, state, workspace, time, high,
                         h_step, event):
    """In an exact segment, the samples (a Samples) from the `k`-th on before `event`,
    located at `high` (s) into the step of h_step (s) from `state` at `time` (s): those before
    the location's window (sample_inside), then those in it (sample_in_window). Returns the
    next sample's index."""
    # the crossing lies within twice the location tolerance before `high`: a sample there is
    # on the side its own time puts it
    window_start = time + high - 2.0 * location_tolerance(settings, h_step)
    k = sample_inside(samples, k, system, segment, state, workspace, time, window_start)
    return sample_in_window(samples, k, system, segment, state, workspace, time, time + high,
                            event)


@njit(**NUMBERS_ONLY)
def cross_event(system, mesh, settings, run, workspace, segment, plan, end, event, high,
                samples, k):
    """After an accepted step of `plan` (a StepPlan) in `segment` from the run's time that
    crossed `event` by `high` (s from the step's start; its state in NEW_STATE): the crossing
    located (locate_event), a debug run's check up to it (violated_before), the samples from
    the `k`-th on before it taken where the segment is exact (sample_inside; sample_in_window
    for those in the location's window), the run moved
    past it (pass_event; `end`: where the step would land, s) and into the next segment
    (end_segment), which the loop begins where this returns Status.OK; after a contact event
    in an exact segment, with a step no longer than the exact floor (the approach starts at
    zero, where a longer one is not certified). Returns (Status; the next sample's index;
    the exact form of the segment it entered, −1 where it entered none). It returns numbers
    only, so it is compiled without reference counts (compiling.counting): it runs at every
    event, and counting every array of the records it is handed cost a fifth of the
    exponential method's time."""
    state, h_step, time = run.state, plan.h_step, run.clock[0]
    event, high = locate_event(system, segment, settings, state, workspace, event, high, h_step)
    workspace.counters[Counter.EVENTS] += 1
    if violated_before(system, segment, settings, state, workspace, high, h_step):
        return Status.CONTACT_VIOLATED, k, -1
    if segment.exact >= 0:
        k = samples_before_event(samples, k, system, segment, settings, state, workspace, time,
                                 high, h_step, event)
    status = pass_event(state, workspace, run.clock, time, end, plan, high, event)
    exact = -1
    if status == Status.OK:
        exact = enter_next_segment(system, mesh, run, workspace, segment, event, end)
        if event >= Event.CONTACT and segment.exact >= 0:
            run.clock[1] = min(run.clock[1], settings[Setting.EXACT_FLOOR])
    return status, k, exact


# --- events chained ---------------------------------------------------------------------------

@njit(**NUMBERS_ONLY)
def chain_switches(system, mesh, settings, run, workspace, exact, torques, end, samples, k,
                   steps, max_steps):
    """After cross_event has moved the run into a new segment (Status.OK), and at a call's
    start (open_walk): while the segment is exact and its next event can be stepped onto at
    once, take that step and enter the next segment, for as long as it is a step the loop
    would accept and locate without a trial (next_chained says when). What the loop does
    besides between two such events (the rate and event values at the step's ends, the
    grazing check, the location, begin_segment) changes nothing there, and cost high_speed
    two fifths of its time: docs/exponential-measurements.md, "Phase switches chained".
    `exact`: the exact form of the run's segment (exact_form); `torques` (N·m) are held;
    `end` (s): where the call stops; the samples (a Samples) from the `k`-th on
    that a step passes are taken inside it, as cross_event takes them; `steps` accepted of
    `max_steps`. A debug run (contact slack >= 0) checks every step by violated_before: not
    here. Returns (pass_event's Status: a stalled or chattering run stops, and walk's loop
    with it, after begin_segment; the accepted steps; the next sample's index; the exact form
    of the segment it leaves the run in)."""
    status, counters = Status.OK, workspace.counters
    if settings[Setting.CONTACT_SLACK] >= 0.0:
        return status, steps, k, exact
    event = -1
    while status == Status.OK and exact >= 0:
        segment = segment_of(system, mesh, run.place[0], run.loaded, torques, exact)
        event, plan = next_chained(system, settings, run, workspace, segment, end, steps,
                                   max_steps, event >= Event.CONTACT)
        if event < 0:
            break
        k = samples_before_event(samples, k, system, segment, settings, run.state, workspace,
                                 run.clock[0], plan.h_step, plan.h_step, event)
        # as take_exact_step would: a certified step, after an accepted one
        run.clock[1] = control_exact_step(exponential.CERTIFIED, plan,
                                          settings[Setting.EXACT_FLOOR], False)[1]
        steps += 1
        counters[Counter.EVENTS] += 1
        counters[Counter.SWITCHES_CHAINED if event < Event.CONTACT
                 else Counter.CONTACTS_CHAINED] += 1
        status = pass_event(run.state, workspace, run.clock, run.clock[0], end, plan,
                            plan.h_step, event)
        if status == Status.OK:
            exact = enter_next_segment(system, mesh, run, workspace, segment, event, end)
            if event >= Event.CONTACT:  # as cross_event leaves it
                run.clock[1] = min(run.clock[1], settings[Setting.EXACT_FLOOR])
    return status, steps, k, exact


@njit(cache=True, error_model="numpy", inline="always")
def next_chained(system, settings, run, workspace, segment, end, steps, max_steps,
                 after_contact):
    """chain_switches' next step in `segment` (exact, from the run's state): the phase switch
    the opening aim found, where the opening step (opening_step) ends on it (switch_onto),
    or where a landing or a lift-off comes inside that step (contact_inside), or the chain
    began the segment at one (`after_contact`), the first landing or lift-off, or the phase
    switch with the approach certified by its march (aimed_contact). (After a landing or a
    lift-off the loop located, the approach often lies at zero without crossing:
    separation's, where a march from there cost a sixth of the scene's time for no event.)
    Returns (the event the step ends on, −1 where there is none to chain; its StepPlan; its
    exact state in NEW_STATE)."""
    crossing = workspace.memory[Memory.MODAL_AIM] == exponential.CROSSING
    plan, verdict = opening_step(system, settings, run, workspace, segment, end, steps,
                                 max_steps, crossing, after_contact)
    if verdict == exponential.CERTIFIED and switch_onto(system, settings, workspace, segment,
                                                        plan):
        return Event.PHASE_END, plan
    if system.contact_loss and (after_contact or verdict == exponential.PHASE_SURE
                                and contact_inside(system, workspace, segment, plan)):
        return aimed_contact(exponential.exact_train(system), settings, run, workspace, segment,
                             end, steps, max_steps, plan, verdict)
    if verdict != NOT_TAKEN:  # the loop's next step: take_exact_step takes it from here
        workspace.memory[Memory.TAKEN_H] = plan.h_step
        workspace.memory[Memory.TAKEN_VERDICT] = verdict
    return -1, StepPlan(0.0, 0.0, False, False)


# what opening_step says of a step it did not take (the others: exponential.step's verdicts)
NOT_TAKEN = -1


@njit(cache=True, error_model="numpy", inline="always")
def opening_step(system, settings, run, workspace, segment, end, steps, max_steps, crossing,
                 after_contact):
    """The step the loop would take next from the run's state in `segment` (exact) where the
    opening aim found the modal solution's crossing of the phase end (`crossing`;
    Memory.MODAL_AHEAD): its StepPlan, aimed just past the crossing or, where the
    controller wants a shorter one, not, and exponential.step's verdict on it, its exact
    state in NEW_STATE; taken where the loop would take it (step_allowed) and it is aimed
    (then it ends before `end`, s, where the call stops), or contact can be lost and the
    chain did not begin the segment at a landing or a lift-off (`after_contact`:
    aimed_contact marches then): a step short of the switch may show one inside it
    (contact_inside), the call's last step too (left to the loop, the lift-off and the
    landing that fall there were located with trial steps: 85 against one call's 19 over
    jump_resonance's fifty calls of 1 ms). NOT_TAKEN where it is not taken."""
    time = run.clock[0]
    plan = plan_step(settings[Setting.EXACT_MAX_STEP], time, end, run.clock[1],
                     workspace.memory[Memory.MODAL_AHEAD], True, settings)
    if not crossing or not (plan.aimed or system.contact_loss and not after_contact) or \
            step_allowed(steps, max_steps, time, plan) != Status.OK:
        return plan, NOT_TAKEN
    return plan, exact_step(system, segment, run.state, workspace, plan.h_step,
                            workspace.vectors[Vector.NEW_STATE])


@njit(cache=True, error_model="numpy", inline="always")
def switch_onto(system, settings, workspace, segment, plan):
    """Whether the opening step of `plan`, certified, is one the loop would locate its
    phase end at with no trial: aimed, its end past the phase end by at most two location
    tolerances (switch_at_end) and no point crossed (points_stay)."""
    new_state = workspace.vectors[Vector.NEW_STATE]
    return plan.aimed and switch_at_end(system, settings, segment, new_state, plan.h_step) \
        and (not system.contact_loss or points_stay(system, segment, new_state,
                                                    workspace.values[Values.APPROACH]))


@njit(cache=True, error_model="numpy", inline="always")
def contact_inside(system, workspace, segment, plan):
    """Whether the opening step of `plan`, whose certificate failed on the points' approach
    (exponential.PHASE_SURE), shows a landing or a lift-off inside it: a point lies across
    zero at its end, or it ends short of the switch (a lift-off 20 µs into jump_resonance's
    long set lies within the step the controller holds its first one to)."""
    return not plan.aimed or not points_stay(system, segment,
                                             workspace.vectors[Vector.NEW_STATE],
                                             workspace.values[Values.APPROACH])


@njit(cache=True, error_model="numpy", inline="always")
def switch_at_end(system, settings, segment, new_state, h):
    """Whether the step of h (s) that ends at `new_state` passed its segment's phase end by at
    most two location tolerances, as first_estimate reads it (by φp's tangent there)."""
    speed = new_state[new_state.shape[0] // 2 + system.pinion]
    past = (new_state[system.pinion] - segment.length) / speed
    return 0.0 < past <= 2.0 * location_tolerance(settings, h)


# a call of its own: inlined beside opening_step, the two copies of exact_step's inlined code
# left numba's pedantic check of its IR warning at every compile
@njit(**NUMBERS_ONLY)
def aimed_contact(train, settings, run, workspace, segment, end, steps, max_steps, opening,
                  verdict):
    """next_chained's step where contact can be lost: within the step to the phase switch
    (the opening step's, `opening`, where the opening aim found the crossing; else the
    modal solution's crossing aimed at here), the points' approach (one function in an
    exact set) marched from the start for its first crossing (exact_first_crossing). Where
    it crosses first, the step aimed just past that crossing, taken where the angle stays
    inside its interval (its phase events sure, its end inside) and every point has crossed
    at its end (points_crossed); where it does not cross, the phase switch, its approach
    certified by the march, taken as switch_onto takes it: the opening step itself where
    opening_step took it (`verdict`, its exact state still in NEW_STATE; NOT_TAKEN where it
    did not). `train`: the train's exponential.ExactTrain, which serves as its System here.
    Returns (the event, −1: none to chain; the StepPlan; the exact state in NEW_STATE)."""
    time, memory, none = run.clock[0], workspace.memory, (-1, StepPlan(0.0, 0.0, False, False))
    plan = opening
    if memory[Memory.MODAL_AIM] != exponential.CROSSING:
        ahead, aim = exact_event_ahead(train, workspace, segment.exact, run.state,
                                       segment.motor_torque, segment.load_torque,
                                       segment.length, end - time)
        if aim != exponential.CROSSING and ahead != math.inf:  # inf: it stays inside
            return none
        plan = plan_step(settings[Setting.EXACT_MAX_STEP], time, end, run.clock[1], ahead,
                         aim == exponential.CROSSING, settings)
        verdict = NOT_TAKEN
    if step_allowed(steps, max_steps, time, plan) != Status.OK:
        return none
    crossing = exact_first_crossing(train, segment, run.state, workspace, plan.h_step)
    if math.isnan(crossing):
        return none
    event = Event.PHASE_END if crossing < 0.0 else Event.CONTACT
    if event == Event.CONTACT:  # aimed just past the crossing
        plan = StepPlan(crossing + location_tolerance(settings, crossing), plan.h_wanted,
                        False, True)
        verdict = NOT_TAKEN
    if not plan.aimed or time + plan.h_step >= end:
        return none
    new_state = workspace.vectors[Vector.NEW_STATE]
    if verdict == NOT_TAKEN:
        verdict = exact_step(train, segment, run.state, workspace, plan.h_step, new_state)
    if verdict == exponential.UNSURE:
        return none
    if event == Event.CONTACT:
        ends_on_it = (0.0 < new_state[train.pinion] < segment.length) and points_crossed(
            train, segment, new_state, workspace.values[Values.APPROACH])
    else:  # the phase switch, its approach certified by the march
        ends_on_it = switch_at_end(train, settings, segment, new_state, plan.h_step) and \
            points_stay(train, segment, new_state, workspace.values[Values.APPROACH])
    return (event if ends_on_it else -1), plan


@njit(cache=True, error_model="numpy", inline="always")
def points_stay(system, segment, state, approach):
    """Whether at `state`, a step's end, no point of `segment` is past zero in the direction
    of its event, a loaded point's approach not below zero and an unloaded one's not above
    (`approach` is scratch): crosses sees a contact event only at an end strictly past zero,
    so then none crossed, whatever the values at the step's start; elsewhere the loop
    judges the step."""
    approaches(system, segment.points, segment.point_count, state, approach)
    for i in range(segment.point_count):
        if (approach[i] < 0.0) if segment.loaded[i] != 0.0 else (approach[i] > 0.0):
            return False
    return True


# a call of its own: only a chained landing or lift-off asks it
@njit(**NUMBERS_ONLY)
def points_crossed(train, segment, state, approach):
    """Whether at `state`, a step's end, every point of `segment` is past zero in the
    direction of its event, as points_stay reads it: the points of an exact set cross
    together. (Where the step was aimed just past the modal solution's crossing, Newton's
    method placed it within 1e-10 of the time to it, well inside the location tolerance.)
    `train`: as aimed_contact's."""
    approaches(train, segment.points, segment.point_count, state, approach)
    for i in range(segment.point_count):
        if (approach[i] >= 0.0) if segment.loaded[i] != 0.0 else (approach[i] <= 0.0):
            return False
    return True


@njit(cache=True, error_model="numpy", inline="always")
def step_rows(workspace, settings):
    """The StepRows of a workspace and its settings."""
    vectors = workspace.vectors
    return StepRows(vectors[Vector.RATE], vectors[Vector.RATE_AFTER], vectors[Vector.NEW_STATE],
                    vectors[Vector.STAGES + dop853.N_STAGES], vectors[Vector.STAGES:],
                    vectors[Vector.WORK], settings[Setting.ABSOLUTE_TOLERANCE:])


@njit(cache=True, error_model="numpy", inline="always")
def begin_walk(workspace):
    """The loop's memory at the start of a call of `advance`."""
    counters = workspace.counters
    counters[:Counter.TRIAL_STEPS] = 0
    counters[Counter.OPENING] = counters[Counter.JACOBIAN_SEGMENT] = -1
    counters[Counter.LAST_PHASE_EVENT] = -1
    workspace.memory[Memory.FACTORED_H] = workspace.memory[Memory.TAKEN_H] = 0.0
    workspace.memory[Memory.MODAL_AIM] = exponential.NO_AIM


# --- the loop's entry ---------------------------------------------------------------------------

@njit(**UNCOUNTED)
def advance(constants, exact, implicit, run, times, rows, end, motor_torque, load_torque,
            max_steps):
    """Integrate a run to exactly `end` (s) in one call, with the torques (motor, load; N·m)
    held, the outputs (equations.outputs, as the run's `outputs`) at each of `times` (s,
    rising, none past `end`; none for a plain step, as the FMU's) written into the row of
    `rows` of the same index. Where the segment is exact (the exponential method), a sample is
    taken from the exact solution inside the step that passes it (sample_inside), and the
    steps are those of a run without samples; elsewhere the run stops at each time, and the
    run and the rows are to the bit those of one call per time. At most `max_steps` steps in
    all: beyond them the run stops where it is with OVER_BUDGET (a runaway that would hold its
    caller for ever). Returns (the Status's value, accepted steps, rows written): where the
    run fails it stops there, with the rows it passed written (none of the failing stretch
    where its end showed the failure: a state not finite, or past its contact interval).

    One entry for every drive, so that each method's loop is compiled once (minutes on two
    cores). Its records come as a few buffers (buffers.py says why): constants,
    buffers.pack_constants' (the System, the mesh period, the settings); exact,
    exponential.pack_tables' (None but for the exponential method); implicit,
    allocate_implicit's; run, pack_run's (the run's position, read and written back, also
    where the run fails, its `outputs` getting equations.outputs there, and its workspace);
    `rows` C-contiguous, a row as long as the run's outputs. Compiled UNCOUNTED
    (compiling.counting): its body neither allocates nor copies by slices."""
    position, samples = RunArrays(*buffers.unpack_run(run)[:6]), Samples(times, rows)
    torques = (motor_torque, load_torque)
    k, steps = 0, 0
    while True:
        while k < times.shape[0] and times[k] <= position.clock[0]:
            copy_into(rows[k], position.outputs)
            k += 1
        if position.clock[0] >= end:
            return Status.OK.value, steps, k
        first = k
        status, taken, k = advance_to(constants, exact, implicit, run, end, torques,
                                      max_steps - steps, samples, k)
        steps += taken
        if status != Status.OK.value:
            failed_at_end = (status == Status.NOT_FINITE.value
                             or status == Status.LEFT_INTERVAL.value)
            return status, steps, first if failed_at_end else k
