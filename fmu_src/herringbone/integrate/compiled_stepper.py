"""The fast integrator: the compiled loop (compiled/walk.py) behind the stepping contract.

`CompiledStepper.advance(position, end, torques)` keeps the contract of stepping.ScipyStepper:
start from `position`, integrate with the torques held to exactly `end`, stopping on every
contact switch, contact loss and regain; the result depends only on the position passed in, so
a saved position re-runs identically. One call is one pass through compiled code, however many
switches the span holds, and through any number of sample times: `sample` (compiled/walk.py's
`advance`, the one loop every drive runs) writes the outputs at each into a row of an array,
stopping there as a call of its own would, to the bit, or where the segment is exact, taking
them from its exact solution inside the step that passes them. A caller that steps on and on
(the FMU) keeps a `Run` instead, which `run_to` advances in place, and takes a Position of it
only to save it.

Methods (`method`):
- "dop853": explicit, order 8. Its steps are held to h·|λ|max <= 3.5 (|λ|max the fastest
  eigenvalue), inside its stability bound of about 6/|λ|max: near that bound its error estimate
  no longer sees the fastest mode's error. This costs nothing while accuracy asks for shorter
  steps anyway, as it does after every switch.
- "radau": Radau IIA, implicit and L-stable, order 5. Its step is set by accuracy alone, so it
  wins where ω_max is far above what the outputs need resolved (very stiff bearings on light
  bodies); it costs a Jacobian and two LU factorizations per segment.
- "exponential": each segment whose contact set is linear and time-invariant (the symmetric
  scenes: compiled/exponential.py says when) propagated exactly by its modal solution, its
  steps serving the events only; the other segments by DOP853 as above.
- "auto": see `choose_method`.
"""
from __future__ import annotations

import functools
import math
import os
import time

import numba
import numpy as np

from ..arguments import COMPILED_DEFAULT_TOLERANCE, COMPILED_METHODS, check_compiled_run
from ..model.assembly import GearTrainModel
from ..model.equations import PeriodTable
from .compiled import buffers, dop853, exponential, walk
from .contract import IntegrationError, Position
from .segments import Segment, chatter_message

METHODS = COMPILED_METHODS  # their home: arguments.py, with the allowed tolerances
DEFAULT_TOLERANCE = COMPILED_DEFAULT_TOLERANCE  # its home: arguments.py
# "auto" takes the implicit method when the fastest eigenvalue of the linearized train is this
# many times faster than the fastest oscillating one: the excess is overdamped motion that an
# explicit method must follow for stability alone.
STIFFNESS_RATIO = 10.0
# "auto" takes the exponential method over DOP853 where at least this share of the contact sets
# of the mesh period are exact (see choose_method)
EXACT_SHARE = 0.5
# DOP853's steps are held to h·|λ|max <= this, well inside its stability region (about 5.9 on
# the imaginary axis): near the region's edge its embedded error estimate no longer follows
# the true error of the fastest mode. The margin covers the stiffest contact set, about 20 %
# stiffer than the mean the eigenvalues are taken at.
EXPLICIT_STEP_BOUND = 3.5
# Within that bound the step is held where the method integrates every mode true to its own
# eigenvalue (`explicit_step_bound`): a mode rings for as long as its damping lets it, so the
# method's error in its decay rate and frequency adds up over the ringing, where the per-step
# error estimate cannot see it. A mode's eigenvalue may be off by this fraction of its decay
# rate per unit of the tolerance, plus the tolerance times its frequency (which bounds an
# undamped mode).
EIGENVALUE_ERROR_PER_TOLERANCE = 3e4
FREQUENCY_ERROR_PER_TOLERANCE = 1.0
# A step's error adds up over the ringing of the mode it lands in, about 1/ζ radians, so a
# train whose fast modes are lightly damped takes its steps at the tolerance times
# ζ/LIGHT_DAMPING, ζ the least damping ratio of the oscillating modes within
# FAST_MODE_FRACTION of |λ|max (the ones whose steps make the error), but no tighter than
# LEAST_RINGING_FACTOR times it, which holds the designed accuracy over some 17 000 radians of
# ringing (ζ = 6e-5): undamped bearings ring thousands of radians in a 10 ms run, and `auto`
# takes no more steps for it on any shipped scene (docs/integrator.md, Methods).
LIGHT_DAMPING = 0.02
FAST_MODE_FRACTION = 0.1
LEAST_RINGING_FACTOR = 0.003
# ... and no tighter than this step tolerance, where DOP853's error estimate meets rounding
# (measured: 5e-14 fails at the first step on tests/regression/found_b94916f10b.toml, 1e-13
# runs on every scene tried); a tolerance asked for below it is taken as it is
RINGING_CUT_FLOOR = 1e-13
# A switch located δt late or early leaves a force error of about |λ|max·δt times the force that
# switched (at most the static mesh force): events are located to this fraction of the tolerance
# over |λ|max, so that what they add is a hundredth of a step's error.
EVENT_ERROR_FRACTION = 1e-2


def choose_method(model: GearTrainModel, method: str = "auto", modes=None) -> str:
    """The method "auto" stands for on this model; the others are returned as they are.

    The exponential method wherever every contact set of the mesh period is exact (with all
    its points loaded): its cost does not depend on the train's stiffness (while the modal
    forms can be made: a mesh stiff enough makes them too ill-conditioned for the run's
    tolerance, exponential.condition_limit, and DOP853 or Radau IIA takes over, as
    `method_note` says), and it was the
    cheapest on every such shipped scene. Where only some are, it steps the others by DOP853,
    bit for bit as DOP853 would: it is taken there too where `runge_kutta_method` would take
    DOP853 and at least EXACT_SHARE of the sets are exact (measured: half of them, low_speed,
    4.6 times faster than DOP853; a quarter, staggered, as fast). Otherwise
    `runge_kutta_method`'s choice. docs/exponential-integrator.md has the figures. `modes`:
    the model's eigenvalues, if already at hand."""
    if method not in METHODS:
        raise ValueError(f"method {method!r}: allowed are {', '.join(METHODS)}")
    if method != "auto":
        return method
    exact = exponential.exact_sets(model.system, model.mesh.period_table())[
        :, exponential.ALL_LOADED]
    if exact.all():
        return "exponential"
    choice = runge_kutta_method(model.eigenvalues() if modes is None else modes)
    return "exponential" if choice == "dop853" and exact.mean() >= EXACT_SHARE else choice


def auto_note(model: GearTrainModel, method: str, modes) -> str:
    """Why "auto" took `method` (choose_method's answer) where it did not take the
    exponential method, for a run's summary ("" where it did, or where `method` was asked
    for by name)."""
    if method == "exponential":
        return ""
    exact = exponential.exact_sets(model.system, model.mesh.period_table())[
        :, exponential.ALL_LOADED]
    sets = (f"{int(exact.sum())} of {len(exact)} contact sets are exact, where the exponential "
            f"method needs at least {EXACT_SHARE:.0%} (a lead error, an edge ramp or halves "
            "that differ make a set's equations change as its points travel)")
    if method == "radau":
        return ("the train's fastest modes are overdamped, which cost an explicit method steps "
                f"for stability alone, and {sets}")
    return sets


def runge_kutta_method(modes) -> str:
    """DOP853 or Radau IIA for a train with these eigenvalues (1/s). An explicit step is
    bounded by stability to about 6/max|λ| (and held to 3.5/max|λ|). Oscillating modes
    (|Im λ| > |Re λ|, damping ratio below 0.7) have to be followed by any method, to be
    accurate; modes faster than those and overdamped (very stiff bearings with strong damping)
    only cost the explicit method steps, so then Radau IIA is the cheaper one."""
    oscillating = modes[np.abs(modes.imag) > np.abs(modes.real)]
    fastest_oscillation = np.abs(oscillating).max() if len(oscillating) else 0.0
    return "radau" if np.abs(modes).max() > STIFFNESS_RATIO * fastest_oscillation else "dop853"


def ringing_factor(modes) -> float:
    """What the tolerance is multiplied by for the steps of a train with these eigenvalues:
    ζ/LIGHT_DAMPING of its least damped fast oscillating mode, within [LEAST_RINGING_FACTOR,
    1] (see LIGHT_DAMPING)."""
    fastest = np.abs(modes).max()
    fast = modes[(np.abs(modes) >= FAST_MODE_FRACTION * fastest)
                 & (np.abs(modes.imag) > np.abs(modes.real))]
    if not len(fast):
        return 1.0
    least_damping = float((-fast.real / np.abs(fast)).min())
    return float(np.clip(least_damping / LIGHT_DAMPING, LEAST_RINGING_FACTOR, 1.0))


def step_tolerance_factor(model: GearTrainModel, modes) -> float:
    """What the tolerance is multiplied by for the steps of this train: ringing_factor of its
    engaged modes (`modes`, GearTrainModel.eigenvalues'), and where contact can be lost, of
    its free flight's too (shafts and bearings alone, GearTrainModel.free_flight_matrices),
    the smaller. In flight a mode the mesh damped may not be damped at all (undamped
    bearings): a step's error then rings on until the next landing, at a frequency the
    engaged modes do not show (tests/regression/found_6be024234d.toml: 33 to 72 kHz
    undamped; with the engaged modes' factor alone its compiled error was 1800 times the
    tolerance)."""
    factor = ringing_factor(modes)
    if model.contact_loss:
        factor = min(factor, ringing_factor(model.eigenvalues(*model.free_flight_matrices())))
    return factor


def explicit_step_bound(modes, tolerance: float) -> float:
    """The longest DOP853 step (s) that integrates each mode λ of `modes` with an eigenvalue
    error |ln R(h·λ)/h − λ| of at most EIGENVALUE_ERROR_PER_TOLERANCE·tolerance times its decay
    rate −Re λ plus tolerance·|λ|, and no longer than EXPLICIT_STEP_BOUND/|λ|max. The error
    grows with h over that range, so it is found by bisection. The rigid rotation (λ = 0) and
    what rounding leaves of it are not modes that ring."""
    fastest = np.abs(modes).max()
    modes = modes[(modes.imag >= 0.0) & (np.abs(modes) > 1e-6 * fastest)]
    allowed = (EIGENVALUE_ERROR_PER_TOLERANCE * tolerance * -modes.real
               + FREQUENCY_ERROR_PER_TOLERANCE * tolerance * np.abs(modes))

    def true_to_modes(h):
        error = np.abs(np.log(dop853.stability_function(h * modes)) / h - modes)
        return bool(np.all(error <= allowed))

    low, high = 0.0, EXPLICIT_STEP_BOUND / fastest
    if true_to_modes(high):
        return high
    for _ in range(50):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if true_to_modes(middle) else (low, middle)
    return low


# what each failing walk.Status means, for the error raised (CHATTER: segments.chatter_message)
FAILURES = {walk.Status.STALLED: "contact switches without progress (grazing contact)",
            walk.Status.STEP_TOO_SMALL: "the step size fell below the time's resolution",
            walk.Status.NOT_FINITE: "the state is no longer finite",
            walk.Status.CONTACT_VIOLATED: "a point carried tension, or penetrated without load, "
                                          "inside a step (contact check of a debug run)",
            walk.Status.LEFT_INTERVAL: "the pinion left its contact interval unseen (the state "
                                       "is beyond the integrator's resolution)"}

NO_STEP_BUDGET = 2**62  # run_to's max_steps when it has none
# run_to's samples: none (walk.advance's times and rows, of the types `sample` hands it, so
# that both drives run one compiled loop)
NO_TIMES = np.empty(0)
NO_ROWS = np.empty((0, 0))
# Samples per compiled call of walk.advance (`sample`): a callback (on_sample) is handed
# them after the call, so a progress bar or a budget watch lags this many samples; the call's
# own cost (a few µs) and the step that ends on its last time are shared by as many
SAMPLES_PER_CALL = 64
# Runaway guard: a run over h s (a doStep, a call of walk.advance) may take
# STEP_BUDGET_FLOOR + STEP_BUDGET_PER_MODE·h·|λ|max internal steps (|λ|max the fastest
# eigenvalue). Measured on the shipped scenes at the default
# tolerance: at most 2·h·|λ|max + 10 (from_rest), so the bound leaves 50 times that, and a
# tolerance of 1e-12 (about 4.5 times the steps of 1e-7 for an order-8 method) fits. A stalled
# run stops after about 0.04 s + 0.35 ms per h·|λ|max of wall time (20 000 steps: 0.07 s).
STEP_BUDGET_FLOOR = 10_000
STEP_BUDGET_PER_MODE = 100
# and, with max_step set, twice the steps it forces (h/max_step); a budget at most this (the
# compiled loop counts in 64 bits)
STEP_BUDGET_PER_MAX_STEP = 2
MOST_STEPS = 2**62
# Radau IIA (order 5) follows a lightly damped mode in more steps than DOP853, the more the
# tighter the tolerance: over 0.01 s of the shipped scenes at most 24 steps per h·|λ|max at
# 1e-7, 135 at 1e-10 and 177 at 1e-12 (undamped; DOP853 5.4 at most). Below the default
# tolerance its bound grows as tolerance^(-1/4), four times that need at 1e-7 and 1e-10 and
# ten at 1e-12 (1 778); at the default it stays DOP853's, since each of its steps costs more
# and a runaway under it holds the host the longer (docs/hosts.md has the times).
RADAU_BUDGET_EXPONENT = 0.25


def step_budget(span, fastest_rate, max_step, per_mode=STEP_BUDGET_PER_MODE) -> int:
    """Internal steps a run over `span` s may take before it counts as a runaway:
    STEP_BUDGET_FLOOR + `per_mode`·h·|λ|max (`fastest_rate`, 1/s; `per_mode`: the method's,
    CompiledStepper.budget_per_mode), and with a `max_step` (s; 0 or inf: none)
    STEP_BUDGET_PER_MAX_STEP·h/max_step more; at most MOST_STEPS."""
    steps = per_mode * span * fastest_rate
    if 0.0 < max_step < math.inf:
        steps += STEP_BUDGET_PER_MAX_STEP * span / max_step
    return int(min(STEP_BUDGET_FLOOR + steps, MOST_STEPS))


COMPLETED = int(walk.Status.OK)  # as an int: compared after every call, unlike an enum's lookup


class StepBudgetExceeded(IntegrationError):
    """run_to took its `max_steps` steps without reaching its end (the run stays usable)."""


class Run:
    """A run on the compiled loop, held in the buffers walk.advance updates in place
    (walk.pack_run), so that a communication step allocates nothing. It is mutable and has one
    owner (the FMU slave keeps one); `CompiledStepper.position` takes an immutable snapshot of
    it, for saving and restoring, and `CompiledStepper.start` makes a run from one. Its
    position's arrays are views of the buffers: clock, [time (s), step size to try next (s)];
    place, [contact interval, mesh cycle]; state, [y, ẏ]; loaded, per point of the set
    (padded to the widest set), 1 loaded, 0 not; first_steps, per contact interval, its first
    step size (0: none); outputs, equations.outputs at the run's position
    (model.output_layout). `workspace`, the loop's scratch (walk.Workspace), is not part of
    the position."""

    __slots__ = ("buffers", "implicit", "clock", "place", "state", "loaded", "first_steps",
                 "outputs", "workspace")

    def __init__(self, packed, implicit, exact):
        self.buffers = packed  # walk.pack_run's (the parameter's name leaves the module's free)
        self.implicit = implicit  # walk.allocate_implicit's
        arrays, self.workspace = walk.run_records(packed, implicit, exact)
        (self.clock, self.place, self.state, self.loaded, self.first_steps,
         self.outputs) = arrays

    @property
    def time(self) -> float:
        """The run's time, s."""
        return float(self.clock[0])

    @property
    def trial_steps(self) -> int:
        """Trial steps the run has taken (to locate events, probe for grazing, check contact),
        beside its accepted steps: for benchmarks."""
        return int(self._counters[walk.Counter.TRIAL_STEPS])

    @property
    def events(self) -> int:
        """Events (contact switches, lift-offs, landings) the run has located: for benchmarks."""
        return int(self._counters[walk.Counter.EVENTS])

    @property
    def switches_chained(self) -> int:
        """Of the events, the phase switches taken one after another without the loop's
        general iteration (walk.chain_switches): for benchmarks and tests."""
        return int(self._counters[walk.Counter.SWITCHES_CHAINED])

    @property
    def contacts_chained(self) -> int:
        """Of the events, the landings and lift-offs taken one after another without the
        loop's general iteration (walk.chain_switches): for benchmarks and tests."""
        return int(self._counters[walk.Counter.CONTACTS_CHAINED])

    @property
    def rejected_steps(self) -> int:
        """Steps the run has rejected (by error control; exact steps it could not certify),
        beside its accepted steps: for benchmarks."""
        return int(self._counters[walk.Counter.REJECTED_STEPS])

    @property
    def _counters(self):
        return self.workspace.counters


class CompiledStepper:
    """The FMU's integrator (the Stepper contract of integrate/contract.py): the compiled loop
    of compiled/walk.py with DOP853 or Radau IIA inside, stopping on every contact switch."""

    def __init__(self, model: GearTrainModel, tolerance: float, method: str = "auto",
                 max_step: float = math.inf, event_time_tolerance: float | None = None,
                 check_contact: bool | None = None):
        """event_time_tolerance: how far past an event a segment may end, in seconds (default:
        EVENT_ERROR_FRACTION of the tolerance over |λ|max). check_contact (default: the
        environment variable HERRINGBONE_CHECK_CONTACT set to 1): a debug run, which looks
        inside every step for a point in tension or penetrating without load, beyond what a
        tolerance's share of the force scale on one point allows, and fails the run
        if it finds one (seven times the cost)."""
        self.model = model
        self.tolerance = float(tolerance)
        modes = model.eigenvalues()
        self.method = choose_method(model, method, modes)
        # why "auto" took what it took, or what the method does otherwise than its name says
        # ("": nothing to say), for a run's summary
        self.method_note = auto_note(model, self.method, modes) if method == "auto" else ""
        # the tolerance each step is held to: tighter where lightly damped modes ring on
        self.step_tolerance = max(self.tolerance * step_tolerance_factor(model, modes),
                                  min(self.tolerance, RINGING_CUT_FLOOR))
        exact_tables = None
        if self.method == "exponential":
            exact_tables = self._exact_tables(model, method, modes, self.step_tolerance)
        self.method_code = {"radau": walk.Method.IMPLICIT, "dop853": walk.Method.EXPLICIT,
                            "exponential": walk.Method.EXPONENTIAL}[self.method]
        fastest = np.abs(modes).max()  # |λ|max, 1/s
        self.fastest_rate = float(fastest)
        # a tenth of the fastest time scale: the controller adjusts it within a few steps
        self.first_step = 0.1 / fastest
        self.absolute_tolerance = self.step_tolerance * model.state_scales()
        self.max_step = float(max_step)
        # (the exponential method steps its segments that are not exact by DOP853)
        if self.method_code != walk.Method.IMPLICIT:
            self.max_step = min(self.max_step, explicit_step_bound(modes, self.step_tolerance))
        self.event_time_tolerance = (EVENT_ERROR_FRACTION * self.step_tolerance / fastest
                                     if event_time_tolerance is None
                                     else float(event_time_tolerance))
        if check_contact is None:
            check_contact = os.environ.get("HERRINGBONE_CHECK_CONTACT") == "1"
        self.contact_slack = (self.tolerance * model.force_scale() / model.mesh.c_point
                              if check_contact else -1.0)
        self.mesh = PeriodTable(*model.mesh.period_table())
        self.lengths, self.counts, self.tables = self.mesh
        # the longest exact step taken uncertified: the loop's checks of its ends and of
        # grazing need h·|λ|max <= EXPLICIT_STEP_BOUND; DOP853's tighter bound for lightly
        # damped modes (explicit_step_bound) is for its own error, and an exact step makes none
        self.exact_floor = min(float(max_step), EXPLICIT_STEP_BOUND / fastest)
        self.settings = walk.pack_settings(self.step_tolerance, self.max_step,
                                           self.event_time_tolerance, self.contact_slack,
                                           self.absolute_tolerance, float(max_step),
                                           self.exact_floor)
        # walk.advance's constants
        self.constants = buffers.pack_constants(model.packed_system, self.mesh, self.settings)
        self.exact_tables = exact_tables
        self.exact_buffers = (exponential.pack_tables(self.exact_tables)
                              if self.exact_tables is not None else None)
        self.accepted_steps = 0  # over the stepper's life, for benchmarks
        self.loop = walk.advance  # run_to's: after its first call, its compiled entry

    def __getstate__(self):
        """What pickle and copy take of the stepper: all of it but its loop's compiled entry
        (compiled_entry), which is code of this process, not data; the copy finds its own."""
        state = self.__dict__.copy()
        state["loop"] = walk.advance
        return state

    def _exact_tables(self, model, method, modes, step_tolerance):
        """The exponential method's modal forms of every contact set; where a set's linear
        system has no such form (free bodies whose zero eigenvalues rounding splits, with
        eigenvectors too nearly parallel; a mesh so stiff that the form's rounding would show
        at the run's tolerance: exponential.condition_limit), "auto" takes
        `runge_kutta_method`'s choice instead (its rule was measured on scenes with every
        form), and an explicit "exponential" steps that set by DOP853, as it does every set
        that is not exact."""
        force = model.force_scale()
        torque_scales = (force * model.geometry.radius_pinion, force * model.geometry.radius_wheel)
        build = functools.partial(exponential.build_tables, model.system,
                                  model.mesh.period_table(), model.state_scales(),
                                  torque_scales, step_tolerance, self.tolerance)
        try:
            return build()
        except np.linalg.LinAlgError as refused:
            if method == "exponential":
                self.method_note = (f"a contact set's modal form refused ({refused}): such "
                                    "sets stepped by DOP853")
                return build(skip_defective=True)
            self.method = runge_kutta_method(modes)
            self.method_note = (f"the exponential method's modal forms refused ({refused}): "
                                f"{self.method} instead")
            return None

    @functools.cached_property
    def budget_per_mode(self) -> float:
        """The steps per h·|λ|max a run of this stepper's method and tolerance may take
        before it counts as a runaway (step_budget)."""
        if self.method != "radau" or self.tolerance >= DEFAULT_TOLERANCE:
            return float(STEP_BUDGET_PER_MODE)
        return STEP_BUDGET_PER_MODE * (DEFAULT_TOLERANCE / self.tolerance) \
            ** RADAU_BUDGET_EXPONENT

    def start(self, position: Position) -> Run:
        """A run from a position (which it does not change)."""
        contact_set = position.segment.contact_set
        loaded = np.zeros(self.tables.shape[2])
        loaded[:len(contact_set)] = position.segment.loaded
        h = position.step_hint if position.step_hint is not None else self.first_step
        outputs = (position.outputs.copy() if position.outputs is not None else
                   self.model.output_vector(position.state, contact_set,
                                            position.segment.loaded))
        first_steps = (position.first_steps.copy() if position.first_steps is not None
                       else np.zeros(len(self.lengths)))
        return Run(walk.pack_run([position.time, h], [contact_set.index, contact_set.cycle],
                                 position.state, loaded, first_steps, outputs,
                                 self.tables.shape[2]),
                   walk.allocate_implicit(self.method_code, len(position.state)),
                   self.exact_buffers)

    def position(self, run: Run) -> Position:
        """A snapshot of the run: its own copies, unchanged by the run going on."""
        interval, cycle = (int(k) for k in run.place)
        contact_set = self.model.mesh.contact_set(cycle, interval)
        return Position(run.time, run.state.copy(),
                        Segment(contact_set, run.loaded[:len(contact_set)].copy()),
                        float(run.clock[1]), run.outputs.copy(), run.first_steps.copy())

    def run_to(self, run: Run, end: float, torques: tuple[float, float],
               max_steps: int | None = None) -> None:
        """Integrate the run to `end` with the torques held, in place. Raises IntegrationError
        where the integration fails, StepBudgetExceeded (the run left consistent where it
        stopped) after `max_steps` internal steps (None: no bound)."""
        if end <= run.clock.item(0):
            return
        # float(): an int would make numba compile another version
        arguments = (self.constants, self.exact_buffers, run.implicit, run.buffers, NO_TIMES,
                     NO_ROWS, float(end), float(torques[0]), float(torques[1]),
                     NO_STEP_BUDGET if max_steps is None else int(max_steps))
        status, steps, _ = self.loop(*arguments)
        if self.loop is walk.advance:
            self.loop = compiled_entry(walk.advance, arguments)
        self.accepted_steps += steps
        if status != COMPLETED:
            self._fail(status, run, steps, end)

    def sample(self, run: Run, times: np.ndarray, rows: np.ndarray, end: float,
               torques: tuple[float, float], max_steps: int | None = None,
               on_sample=None) -> None:
        """Integrate the run through `times` (s, rising, in [run's time, end]) to `end` with
        the torques held, in place, in one call of compiled code (walk.advance): rows[k]
        gets the outputs (model.output_layout) at times[k]. Where the run's segments are exact
        (the exponential method), a sample comes from the exact solution inside the step that
        passes it, and the steps are those of run_to straight to `end`; elsewhere the run and
        the rows are to the bit those of run_to to each time in turn, then to `end`. A time not
        past the run's takes the outputs the run holds. Raises as run_to would (a budget of
        `max_steps` steps for the whole call), once on_sample(t, outputs by name), if given,
        has been called for every row written before the failure. `rows`: C-contiguous,
        len(times) rows of the run's outputs' length. ValueError, before any step, for rows of
        another shape and for times that fall or reach past `end` (the run would stop at `end`
        with their rows unwritten)."""
        times = np.ascontiguousarray(times, dtype=float)
        if rows.shape != (len(times), len(run.outputs)) or not rows.flags.c_contiguous:
            raise ValueError(f"rows: {rows.shape}, C-contiguous {rows.flags.c_contiguous}; "
                             f"allowed: a C-contiguous {(len(times), len(run.outputs))} array")
        if len(times) and not (times[-1] <= end and np.all(times[1:] >= times[:-1])):
            raise ValueError(f"times: {_unordered(times, end)}; allowed: rising times, none "
                             f"past end")
        # numba's dispatcher, not run_to's compiled entry: the caller's times and rows may be
        # of other types (read-only, say), which the entry would not check
        status, steps, written = walk.advance(
            self.constants, self.exact_buffers, run.implicit, run.buffers, times, rows,
            float(end), float(torques[0]), float(torques[1]),
            NO_STEP_BUDGET if max_steps is None else int(max_steps))
        self.accepted_steps += steps
        if on_sample is not None:
            for t, row in zip(times[:written], rows):
                on_sample(t, self.model.named_outputs(row))
        if status != COMPLETED:
            self._fail(status, run, steps, times[written] if written < len(times) else end)

    def _fail(self, status: int, run: Run, steps: int, end: float) -> None:
        """Raise what walk.advance's `status` (not OK) says: StepBudgetExceeded, or
        IntegrationError naming the failure (a chatter as the train's: chatter_message)."""
        if status == walk.Status.OVER_BUDGET:
            raise StepBudgetExceeded(f"stopped at t = {run.time:.9g} s after {steps} internal "
                                     f"steps short of t = {end:.9g} s")
        failure = (chatter_message(self.model) if status == walk.Status.CHATTER
                   else FAILURES[walk.Status(status)])
        raise IntegrationError(f"integration failed at t = {run.time:.9g} s: {failure}")

    def advance(self, position: Position, end: float, torques: tuple[float, float],
                sample_times=(), on_sample=None) -> Position:
        """Integrate to `end`; for every t in `sample_times` (rising) with position.time <= t <
        end, call on_sample(t, outputs) with the outputs at t. The samples are taken as
        advance_sampled takes them, to the bit: SAMPLES_PER_CALL at a time in one compiled call
        (`sample`), and handed to on_sample after it."""
        run = self.start(position)
        times = np.asarray(sample_times, dtype=float)
        times = times[(position.time <= times) & (times < end)]
        self._sample_in_calls(run, times, None, end, torques, on_sample)
        return self.position(run)

    def advance_sampled(self, position: Position, end: float, torques: tuple[float, float],
                        times: np.ndarray, rows: np.ndarray, on_progress=None) -> Position:
        """Integrate to `end`; rows[k] gets the outputs (model.output_layout) at times[k]
        (rising, in [position.time, end)), SAMPLES_PER_CALL at a time in one compiled call
        (`sample`); on_progress(t), if given, after each call with the time it reached (s)."""
        run = self.start(position)
        self._sample_in_calls(run, times, rows, end, torques, on_progress=on_progress)
        return self.position(run)

    def _sample_in_calls(self, run: Run, times: np.ndarray, rows: np.ndarray | None,
                         end: float, torques: tuple[float, float], on_sample=None,
                         on_progress=None) -> None:
        """`sample` over SAMPLES_PER_CALL times at a time, each call ending at the next one's
        first time (so that a run sampled with a callback and one sampled into an array take
        the same steps): into `rows`, or where None, into rows of scratch; on_progress(t), if
        given, after each call."""
        scratch = np.empty((min(len(times), SAMPLES_PER_CALL), len(run.outputs)))
        for first in range(0, max(len(times), 1), SAMPLES_PER_CALL):
            chunk, after = times[first:first + SAMPLES_PER_CALL], first + SAMPLES_PER_CALL
            call_end = times[after] if after < len(times) else end
            budget = step_budget(call_end - run.time, self.fastest_rate, self.max_step,
                                 self.budget_per_mode)
            try:
                self.sample(run, chunk,
                            scratch[:len(chunk)] if rows is None else rows[first:after],
                            call_end, torques, max_steps=budget, on_sample=on_sample)
            except StepBudgetExceeded:
                raise StepBudgetExceeded(
                    f"stopped at t = {run.time:.9g} s, short of t = {call_end:.9g} s, after "
                    f"{budget} internal steps (the bound: {STEP_BUDGET_FLOOR} + "
                    f"{self.budget_per_mode:.0f}·h·|λ|max, |λ|max = {self.fastest_rate:.3g} 1/s): "
                    f"the train runs away; check the torques M_motor = {torques[0]:g} and "
                    f"M_load = {torques[1]:g} N.m") from None
            if on_progress is not None:
                on_progress(run.time)


def _unordered(times: np.ndarray, end: float) -> str:
    """What is wrong with sample times that are not rising or reach past `end`: the first
    culprit, by index and value."""
    if np.isnan(times).any():
        return f"times[{int(np.argmax(np.isnan(times)))}] is not a number"
    falling = np.flatnonzero(times[1:] < times[:-1])
    if len(falling):
        k = int(falling[0]) + 1
        return (f"times[{k}] = {float(times[k])!r} s falls below "
                f"times[{k - 1}] = {float(times[k - 1])!r} s")
    k = int(np.argmax(times > end))
    return f"times[{k}] = {float(times[k])!r} s is past end = {float(end)!r} s"


def compiled_entry(function, arguments):
    """The compiled code that the numba function `function`, once called with `arguments`,
    runs for arguments of their types, to be called directly with arguments of the same types:
    numba's dispatcher types every argument of every call to choose it, and a stepper's calls
    of its loop (the FMU's communication steps) all have the same types, its own buffers, so
    that work is done once here. `function` itself where numba has no such entry for them."""
    try:
        return function.overloads[tuple(numba.typeof(a) for a in arguments)].entry_point
    except (AttributeError, KeyError, TypeError, ValueError):
        return function


def warm_up(stepper: CompiledStepper, position: Position) -> float | None:
    """Load the compiled loop (walk.advance, which every drive runs: the FMU's steps, the
    sweeps, herringbone.simulate) before the first step, from the cache or by compiling it
    the first time, by a run of a nanosecond from `position` whose steps the stepper does not
    count; returns the seconds spent compiling, or None if it came from the cache."""
    started = time.perf_counter()
    steps = stepper.accepted_steps
    stepper.run_to(stepper.start(position), position.time + 1e-9, (0.0, 0.0))
    stepper.accepted_steps = steps
    compiled = any(walk.advance.stats.cache_misses.values())
    return time.perf_counter() - started if compiled else None


def simulate(scene, stop_time=None, output_interval=None, tolerance=DEFAULT_TOLERANCE,
             method="auto", max_step=math.inf):
    """Simulate a scene with the compiled integrator, what the FMU runs (reference_simulate's
    twin).

    The first call on a machine for a method (the one `method` names or "auto" picks) compiles
    the integrator's loop: minutes on two cores, announced on stderr as it starts, every 10 s
    and at its end (first_start.announce_compiles hands the lines to a function of the
    caller's instead); later calls, in any process, load it from the cache in about a second
    (docs/integrator.md, First start).

    Parameters
    ----------
    scene : Scene
    stop_time, output_interval : float or None
        Simulated seconds, and seconds between samples (at most stop_time); None: the scene's.
    tolerance : float
        The error allowed per internal step in the forces, relative to the force scale (the
        static mesh force); [1e-12, 1e-2]. Steps are held tighter where the train's fast modes
        ring long (docs/integrator.md).
    method : str
        "auto" (the default: `choose_method` says which), "dop853", "radau" or "exponential".
    max_step : float
        The longest internal step, s (inf: no bound beyond the method's own).

    Returns
    -------
    Result
        {"time": …, output name: …} sampled every output_interval, SI units; its `steps`,
        the integrator's internal steps.

    Raises
    ------
    ValueError
        An argument outside arguments.check_compiled_run's ranges, before any work
        (SceneError, a ValueError, for something that is not a Scene).
    IntegrationError
        The run cannot go on (it says where and why); StepBudgetExceeded is one.

    Examples
    --------
    >>> import herringbone
    >>> scene = herringbone.load_scene("reference")
    >>> result = herringbone.simulate(scene, stop_time=0.01)  # every 1e-4 s: the scene's
    >>> len(result["time"]), result.units["F_mesh"], round(float(result["F_mesh"].max()), 1)
    (101, 'N', 34705.1)
    >>> result.steps  # one an exact segment between contact switches: the exponential method
    18
    """
    from .contract import simulate_with

    check_compiled_run(scene, stop_time, output_interval, tolerance, method, max_step)

    stepper = CompiledStepper(GearTrainModel(scene), tolerance, method, max_step)
    return simulate_with(stepper, scene, stop_time, output_interval)
