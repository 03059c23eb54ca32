"""One point of a sweep: a scene run at constant torques past its start-up transient, then
recorded over whole mesh periods, and the figures a drivetrain engineer reads off that window.

The protocol (`Protocol`, `timing`):
- settle: the least-damped mode of the train (linearized at the period-mean stiffness,
  GearTrainModel.eigenvalues) decays like exp(−σ·t); the start-up transient is run for
  ln(1/settle_residual)/σ, rounded up to whole mesh periods, so it has decayed to
  `settle_residual` of its initial amplitude (or for a given `settle_time`, also rounded up);
- window: `window_periods` mesh periods T = 2π/(z_pinion·|w0_pinion|), recorded
  `samples_per_period` times per period, the samples at settle + i·T/samples_per_period for
  i = 0 … N−1 (N = window_periods·samples_per_period: the window's end is its start one whole
  number of periods later, so it is left out): what the spectra and the waterfall take;
- figures: every contact switch sets the train's fastest modes ringing (4-13 kHz on the
  reference scene), and the peaks of that ringing fall between samples taken 64 times a mesh
  period (K_v 1.041 where the force peaks at 1.477 at 10 rad/s). So the figures
  (`window_figures`) are taken over the same window sampled `refinement` times finer, a whole
  number chosen so that the fastest mode has at least FASTEST_MODE_SAMPLES samples a period
  (`figure_refinement`); the recorded samples are every refinement-th of those. They are
  taken chunk by chunk (FIGURE_CHUNK_SAMPLES at a time), each chunk one compiled call
  (CompiledStepper.sample), and summed up as they come (`WindowStatistics`), so memory stays
  bounded however many there are (10 rad/s: about 1.3 million a point).
The settle is integrated without stops.

Everything here is a plain function of its arguments, so a sweep can run it in any process.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..arguments import (
    COMPILED_TOLERANCE_ARGUMENT,
    SAMPLES_PER_PERIOD,
    SETTLE_RESIDUAL,
    SETTLE_TIME,
    WINDOW_PERIODS,
)
from ..integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper
from ..integrate.contract import Position, start_position
from ..model.assembly import GearTrainModel
from ..model.parameters import RPM_PER_RAD_S
from ..shipped import named_as_typed

RIGID_FRACTION = 1e-6  # eigenvalues below this fraction of the largest are the rigid rotation
# Samples a period of the train's fastest mode that the figures take. A ringing sampled N
# times a period is read short of its peak by at most 1 − cos(π/N) of its amplitude: 0.48 %
# at 32, and 0.58 % for the stiffest contact set, whose modes ring up to 10 % faster than the
# mean set's the frequency is taken at (26 % at 8, 1.9 % at 16). With the switches sampled
# finer (SWITCH_SAMPLES), K_v, F_mesh min and a bearing peak of the reference scene lie within
# 2e-3 of the static force of runs sampled every 0.1 µs at 30 and 490 rad/s
# (tests/analysis/test_sweep.py); the ringing there is about half the static force.
FASTEST_MODE_SAMPLES = 32
# samples per compiled call while the figures are taken: their rows (22 outputs on the
# reference scene, 8 bytes each) take 5.8 MB
FIGURE_CHUNK_SAMPLES = 2**15
# At a contact switch of sharp face edges the mesh stiffness jumps (by a third on the
# reference scene) and the mesh force with it, while the deflection stays: its peak is the
# force just after the jump, which then falls with the ringing (at about 0.9 % of the static
# force a µs on the reference scene at 100 rad/s). Samples of the fastest mode (2.4 µs apart
# there) miss it by up to 2 %, so every interval of them over which the count of loaded
# points changed is sampled again this many times finer, from a run of its own
# (`switch_samples`): 37 ns apart, 3e-4 of the static force at most
SWITCH_SAMPLES = 64
SWITCH_CHUNK_INTERVALS = FIGURE_CHUNK_SAMPLES // SWITCH_SAMPLES  # switch intervals a call
BEARINGS = tuple(f"F_brg_{gear}_{side}" for gear in ("pinion", "wheel")
                 for side in ("left", "right"))
HALF_FORCES = ("F_mesh_left", "F_mesh_right")


@dataclass(frozen=True)
class Protocol:
    """How each point is run. settle_time (s), if given, replaces the derived settle."""

    settle_residual: float = 1e-3
    settle_time: float | None = None
    window_periods: int = 50
    samples_per_period: int = 64
    tolerance: float = DEFAULT_TOLERANCE
    floquet: bool = True

    def __post_init__(self):
        """ValueError naming the first setting outside its range (arguments.py has them)."""
        settings = [(SETTLE_RESIDUAL, self.settle_residual), (WINDOW_PERIODS, self.window_periods),
                    (SAMPLES_PER_PERIOD, self.samples_per_period),
                    (COMPILED_TOLERANCE_ARGUMENT, self.tolerance)]
        if self.settle_time is not None:
            settings.append((SETTLE_TIME, self.settle_time))
        for argument, value in settings:
            argument.check(value)


@dataclass(frozen=True)
class Timing:
    """Where a point's window lies: settle (s), interval of the recorded samples (s), their
    count, and how many times finer the figures sample it (`refinement`, a whole number)."""

    mesh_period: float
    settle: float
    interval: float
    samples: int
    refinement: int = 1

    @property
    def window(self) -> float:
        """The span of the recorded samples, s."""
        return self.samples * self.interval

    @property
    def figure_interval(self) -> float:
        """The interval (s) of the samples the figures are taken from."""
        return self.interval / self.refinement

    @property
    def figure_samples(self) -> int:
        """How many samples the figures are taken from."""
        return self.samples * self.refinement

    def sample_times(self) -> np.ndarray:
        """The times (s) of the recorded samples, after the settling time."""
        return self.settle + np.arange(self.samples) * self.interval


# The longest settle (s of simulated time) the protocol works out for itself: the shipped
# scenes take 3.1 to 3.6 s, examples/parametric_resonance.toml 155 s; a train without damping
# (models/undamped.toml: its slowest mode decays at 8e-13 1/s) would take 8e12 s, and a sweep
# of it would not end
LONGEST_DERIVED_SETTLE = 1000.0


def settle_problem(protocol: Protocol, decay_rate: float) -> str | None:
    """Why the protocol cannot work out a settle for a train whose least-damped mode decays at
    `decay_rate` (1/s: least_damped_decay_rate): it would pass LONGEST_DERIVED_SETTLE; None
    where it can or the protocol gives the settle."""
    if protocol.settle_time is not None:
        return None
    settle = math.log(1.0 / protocol.settle_residual) / decay_rate if decay_rate > 0.0 \
        else math.inf
    if settle <= LONGEST_DERIVED_SETTLE:
        return None
    return (f"its least-damped mode decays at {decay_rate:.3g} 1/s, so the settle to "
            f"{protocol.settle_residual:g} of the start's transient would be {settle:.3g} s of "
            f"simulated time; allowed: up to {LONGEST_DERIVED_SETTLE:g} s: give the settle "
            "(--settle-time, Protocol(settle_time=...)) for a train this lightly damped")


def least_damped_decay_rate(scene, model: GearTrainModel | None = None) -> float:
    """σ (1/s) of the slowest-decaying mode other than the rigid rotation (the train's
    eigenvalues at the period-mean stiffness and damping; rigid: |λ| < 1e-6·|λ|max). The rigid
    rotation's eigenvalue is a defective double zero, which rounding moves by about
    √ε·|λ|max (1.2e-9·|λ|max on the gear pair alone, models/jump_resonance.toml), not ε·|λ|max.
    `model`: the scene's GearTrainModel, if already at hand."""
    return _least_damped((GearTrainModel(scene) if model is None else model).eigenvalues())


def _least_damped(modes: np.ndarray) -> float:
    """least_damped_decay_rate of the train's eigenvalues `modes` (1/s)."""
    elastic = modes[np.abs(modes) > RIGID_FRACTION * np.abs(modes).max()]
    return float(np.abs(elastic.real).min())


def fastest_ringing(model: GearTrainModel, modes: np.ndarray | None = None) -> float:
    """The highest natural frequency (Hz) the train rings at: of its modes at the mean mesh
    stiffness (`modes`, its eigenvalues, 1/s, if already at hand) and, where contact can be
    lost, of its free flight (shafts and bearings alone, whose modes the mesh no longer holds:
    they may be faster)."""
    modes = model.eigenvalues() if modes is None else modes
    if model.contact_loss:
        modes = np.concatenate([modes, model.eigenvalues(*model.free_flight_matrices())])
    return float(np.abs(modes.imag).max() / (2.0 * math.pi))


def figure_refinement(fastest: float, period: float, samples_per_period: int) -> int:
    """How many figure samples to each of `samples_per_period` recorded samples a mesh period
    (`period`, s), so that the fastest mode (`fastest`, Hz: fastest_ringing) has
    FASTEST_MODE_SAMPLES a period of its own: a whole number >= 1."""
    needed = FASTEST_MODE_SAMPLES * fastest * period
    return max(1, math.ceil(needed / samples_per_period - 1e-9))


def mesh_period(scene) -> float:
    """T = 2π/(z_pinion·|w0_pinion|), s; the pinion must turn."""
    speed = abs(scene.parameters["w0_pinion"])
    if speed == 0.0:
        raise ValueError("w0_pinion is 0: a sweep point needs a turning pinion "
                         "(allowed: w0_pinion != 0 rad/s)")
    return 2.0 * math.pi / (scene.parameters["z_pinion"] * speed)


def timing(scene, protocol: Protocol, model: GearTrainModel | None = None) -> Timing:
    """The settle and the window of a scene under a protocol (module docstring); `model`: the
    scene's GearTrainModel, if already at hand (its eigenvalues give both the settle and the
    figures' refinement). ValueError where the derived settle is too long (settle_problem)."""
    period = mesh_period(scene)
    model = GearTrainModel(scene) if model is None else model
    modes = model.eigenvalues()
    settle = protocol.settle_time
    if settle is None:
        rate = _least_damped(modes)
        problem = settle_problem(protocol, rate)
        if problem is not None:
            raise ValueError(f"{named_as_typed(scene)}: {problem}")
        settle = math.log(1.0 / protocol.settle_residual) / rate
    # 1e-9: a settle given as whole periods stays that many periods despite rounding
    periods = math.ceil(settle / period - 1e-9)
    return Timing(period, periods * period, period / protocol.samples_per_period,
                  protocol.window_periods * protocol.samples_per_period,
                  figure_refinement(fastest_ringing(model, modes), period,
                                    protocol.samples_per_period))


def run_window(scene, protocol: Protocol) -> Window:
    """The outputs at the window's samples, {"time": …, output: …}, from the compiled
    integrator: the scene's constant torques from its static start at w0_pinion. It carries
    the statistics of the finer sampling its figures come from (`Window`)."""
    return run_window_from(scene, protocol)[0]


def run_window_from(scene, protocol: Protocol, start: Position | None = None):
    """run_window from a given start (None: the static start at w0_pinion), and the position
    at the window's end (its last sample). A start is taken as it is, its time counted as 0
    (a sweep that starts each point from the last one's end moves the rigid speed to the
    point's first: `at_speed`). Unless the protocol gives the settle, a window that has not
    settled (`window_drift` over SETTLED_DRIFT) is recorded again from its end, up to
    MORE_WINDOWS times: the window's `settle` is where the one kept begins."""
    if len(scene.inputs.times) != 1:
        raise ValueError(f"{named_as_typed(scene)}: a sweep point needs constant input torques; "
                         "the scene has an input table (allowed: [inputs] M_motor, M_load)")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, protocol.tolerance)
    torques = scene.inputs.at(0.0)
    if start is None:
        start = start_position(model, torques[0])
    run = stepper.start(Position(0.0, start.state, start.segment, start.step_hint))
    when = timing(scene, protocol, model)
    stepper.run_to(run, when.settle, torques)
    window = record_window(stepper, run, torques, when)
    static_force = model.static_mesh_force()
    for _ in range(MORE_WINDOWS if protocol.settle_time is None and static_force else 0):
        if not window_drift(window, protocol, static_force) > SETTLED_DRIFT:
            break
        when = replace(when, settle=when.settle + when.window)
        window = record_window(stepper, run, torques, when)
    return window, stepper.position(run)


def record_window(stepper: CompiledStepper, run, torques, when: Timing) -> Window:
    """The window of `when` recorded from `run` (in place; it must not have passed the
    window's start): its samples and the statistics of its figures' finer sampling."""
    model = stepper.model
    recorded = np.empty((when.samples, model.output_layout_size))
    statistics = WindowStatistics(model.output_layout)
    for first, rows, switches in sample_chunks(stepper, run, torques, when.figure_samples,
                                               lambda k: when.settle + k * when.figure_interval):
        statistics.add(rows)
        statistics.add_extremes(switches)
        # the recorded samples are the figure samples whose index is a multiple of refinement
        kept = rows[-first % when.refinement::when.refinement]
        at = -(-first // when.refinement)
        recorded[at:at + len(kept)] = kept
    return Window({"time": when.sample_times(),
                   **{name: recorded[:, i] for name, i in model.output_layout}},
                  statistics, when.settle)


def sample_chunks(stepper: CompiledStepper, run, torques, count: int, time_of,
                  max_steps: int | None = None):
    """Sample `run` (in place) at count rising times, FIGURE_CHUNK_SAMPLES at a time, each
    chunk one compiled call (CompiledStepper.sample) that ends on the next chunk's first time
    (the last on its own last time). Yields (index of the chunk's first sample, its rows of
    outputs (model.output_layout), the rows of its switch samples (`switch_samples`)); the
    arrays are reused by the next chunk. time_of(indices): their times, s; max_steps: the step
    budget of each call for the span it integrates (None: none), to which the call adds one
    step for each sample it asks (`sample_budget`)."""
    rows = np.empty((min(count, FIGURE_CHUNK_SAMPLES), len(run.outputs)))
    for first in range(0, count, FIGURE_CHUNK_SAMPLES):
        indices = np.arange(first, min(first + FIGURE_CHUNK_SAMPLES, count))
        times = time_of(indices)
        end = float(time_of(indices[-1:] + 1)[0]) if indices[-1] + 1 < count else times[-1]
        chunk = rows[:len(indices)]
        before = stepper.position(run)
        stepper.sample(run, times, chunk, end, torques, sample_budget(max_steps, len(times)))
        yield first, chunk, switch_samples(stepper, before, times, chunk, end, torques,
                                           max_steps)


def sample_budget(max_steps: int | None, samples: int) -> int | None:
    """The step budget of a compiled call that asks for `samples` samples over a span whose
    own budget is `max_steps` (None: none): a sample ends the step that reaches it (but for
    the exponential method's exact segments), so each may cost one step more."""
    return None if max_steps is None else max_steps + samples


def switch_samples(stepper: CompiledStepper, before: Position, times: np.ndarray,
                   rows: np.ndarray, end: float, torques, max_steps: int | None = None):
    """The outputs at SWITCH_SAMPLES − 1 evenly spaced times inside every interval of `times`
    over which n_contacts (the loaded points of nonzero stiffness) changed, from a run of its
    own from `before` (where the chunk's run started) to `end`, their rows in the order of
    their times. With sharp face edges every point weighs the same, so n_contacts changes
    exactly where the mesh stiffness jumps (a contact switch, lift-off or landing), and the
    mesh force with it: its extremes lie just after the jump. With an edge ramp the stiffness
    changes smoothly while a point crosses the ramp, a good share of all intervals (225 of
    896 a period on the reference scene with a 1 mm ramp), and the samples of the fastest
    mode resolve its ringing there; n_contacts changes only where a point enters or leaves
    (4 of them). SWITCH_CHUNK_INTERVALS intervals at a time, so that memory stays bounded;
    max_steps: as sample_chunks'."""
    contacts = rows[:, dict(stepper.model.output_layout)["n_contacts"]]
    switched = np.flatnonzero(contacts[1:] != contacts[:-1])
    fractions = np.arange(1, SWITCH_SAMPLES) / SWITCH_SAMPLES
    burst = np.empty((0, rows.shape[1]))
    if not len(switched):
        return burst
    run = stepper.start(before)
    kept = []
    for group in range(0, len(switched), SWITCH_CHUNK_INTERVALS):
        at = switched[group:group + SWITCH_CHUNK_INTERVALS]
        inside = (times[at, None] + fractions * (times[at + 1] - times[at])[:, None]).ravel()
        following = group + SWITCH_CHUNK_INTERVALS
        until = times[switched[following]] if following < len(switched) else end
        burst = np.empty((len(inside), rows.shape[1]))
        stepper.sample(run, inside, burst, float(until), torques,
                       sample_budget(max_steps, len(inside)))
        kept.append(burst)
    return kept[0] if len(kept) == 1 else np.concatenate(kept)


def at_speed(model: GearTrainModel, position: Position, pinion_speed: float) -> Position:
    """The position with the rigid rotation's speed changed to `pinion_speed` (rad/s): the
    pinion's rate moved by the difference of the mass-weighted mean speeds (the other rates are
    relative to the rigid rotation and stay), so the elastic motion carries over."""
    state = position.state.copy()
    weights = model.mass * model.rigid_rotation
    mean_speed = (weights @ (state[model.size:] + model.rigid_rotation
                             * state[model.size + model.pinion])
                  - weights[model.pinion] * state[model.size + model.pinion]) \
        / (weights @ model.rigid_rotation)
    state[model.size + model.pinion] += pinion_speed - mean_speed
    return Position(position.time, state, position.segment, position.step_hint)


def static_mesh_force(scene) -> float:
    """M_motor/Rp: the mesh force of the train at rest under its motor torque, N."""
    force = GearTrainModel(scene).static_mesh_force()
    if force == 0.0:
        raise ValueError("M_motor is 0: the dynamic factor needs a static mesh force "
                         "(allowed: M_motor != 0)")
    return force


class WindowStatistics:
    """What window_figures takes from a window, summed up chunk by chunk of samples (`add`)
    so that the samples need not be kept: extremes, counts, sums for the means and the rms
    values (dte about its first chunk's mean, so that the sums do not cancel)."""

    def __init__(self, layout):
        """layout: (output name, column) pairs of the rows `add` takes (model.output_layout)."""
        self.columns = dict(layout)
        self.count = 0
        self.force_max, self.force_min = -math.inf, math.inf
        self.half_max = dict.fromkeys(HALF_FORCES, -math.inf)  # N
        self.force_sum = self.left_sum = 0.0  # of F_mesh and F_mesh_left, N
        self.bearings = [name for name in BEARINGS if name in self.columns]
        self.bearing_peak = dict.fromkeys(self.bearings, 0.0)
        self.bearing_squares = dict.fromkeys(self.bearings, 0.0)
        self.dte_shift: float | None = None  # µm
        self.dte_sum = self.dte_squares = 0.0  # of dte − dte_shift, µm and µm²
        self.dte_max, self.dte_min = -math.inf, math.inf
        self.separated = 0

    def _columns(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """The columns the figures need, each contiguous (a column of the rows is strided,
        which makes numpy's reductions over it several times slower)."""
        names = ["F_mesh", *HALF_FORCES, "dte", *self.bearings]
        taken = np.ascontiguousarray(rows[:, [self.columns[name] for name in names]].T)
        return dict(zip(names, taken))

    def add(self, rows: np.ndarray) -> None:
        """Take a chunk of evenly spaced samples: rows of outputs, columns as `layout`."""
        if not len(rows):
            return
        column = self._columns(rows)
        self._extremes(column)
        self.count += len(rows)
        self.force_sum += float(column["F_mesh"].sum())
        self.left_sum += float(column["F_mesh_left"].sum())
        for name in self.bearings:
            # a sum, not `x @ x`: BLAS threads took 7 ms a chunk on a shared machine
            self.bearing_squares[name] += float(np.sum(column[name] ** 2))
        dte = column["dte"] * 1e6
        if self.dte_shift is None:
            self.dte_shift = float(dte.mean())
        deviation = dte - self.dte_shift
        self.dte_sum += float(deviation.sum())
        self.dte_squares += float(np.sum(deviation ** 2))
        self.separated += int(np.count_nonzero((column["F_mesh_left"] <= 0.0)
                                               | (column["F_mesh_right"] <= 0.0)))

    def add_extremes(self, rows: np.ndarray) -> None:
        """Take samples at times off the even sampling (`switch_samples`'): into the extremes
        alone (the means, rms values and shares are of evenly spaced samples)."""
        if len(rows):
            self._extremes(self._columns(rows))

    def _extremes(self, column: dict[str, np.ndarray]) -> None:
        """The extremes updated with columns of samples (`_columns`')."""
        force = column["F_mesh"]
        self.force_max = max(self.force_max, float(force.max()))
        self.force_min = min(self.force_min, float(force.min()))
        for name in HALF_FORCES:
            self.half_max[name] = max(self.half_max[name], float(column[name].max()))
        for name in self.bearings:
            self.bearing_peak[name] = max(self.bearing_peak[name],
                                          float(np.abs(column[name]).max()))
        dte = column["dte"] * 1e6
        self.dte_max, self.dte_min = max(self.dte_max, float(dte.max())), \
            min(self.dte_min, float(dte.min()))

    def figures(self, static_force: float) -> dict[str, float]:
        """window_figures' figures of the samples taken (static_force: M_motor/Rp, N)."""
        n = self.count
        left, right = (self.half_max[name] for name in HALF_FORCES)
        figures = {"K_v": self.force_max / static_force,
                   "K_v_half": max(left, right) / (0.5 * static_force),
                   "F_mesh_min_N": self.force_min, "F_mesh_max_N": self.force_max,
                   "F_mesh_left_max_N": left, "F_mesh_right_max_N": right,
                   "load_share_left": (self.left_sum / self.force_sum if self.force_sum
                                       else math.nan)}
        for name in self.bearings:
            figures[f"{name}_peak_N"] = self.bearing_peak[name]
            figures[f"{name}_rms_N"] = math.sqrt(self.bearing_squares[name] / n)
        mean_deviation = self.dte_sum / n
        figures.update(dte_mean_um=(self.dte_shift or 0.0) + mean_deviation,
                       dte_rms_um=math.sqrt(max(self.dte_squares / n - mean_deviation ** 2, 0.0)),
                       dte_p2p_um=self.dte_max - self.dte_min,
                       contact_lost_share=self.separated / n)
        return figures


class Window(dict):
    """A recorded window {"time": …, output: …}, the statistics of the finer sampling its
    figures are taken from (`statistics`: WindowStatistics) and the settle before it (s)."""

    def __init__(self, samples: dict, statistics: WindowStatistics, settle: float):
        super().__init__(samples)
        self.statistics = statistics
        self.settle = settle


def figure_samples(window: dict) -> int:
    """How many samples window_figures takes the figures of `window` from."""
    statistics = getattr(window, "statistics", None)
    return len(window["time"]) if statistics is None else statistics.count


def window_figures(window: dict, static_force: float) -> dict[str, float]:
    """The figures of a recorded window (samples over whole mesh periods):
    K_v = max F_mesh / static mesh force; K_v_half = the larger of max F_mesh_left and max
    F_mesh_right over half the static force (the dynamic factor of the more loaded helix half:
    K_v where the halves share the load evenly, above it where a lead error loads one more);
    F_mesh min and max and each half's max (N); load_share_left = mean F_mesh_left / mean
    F_mesh (0.5: even); peak |F| and rms of each bearing reaction (N); dte mean, rms about that
    mean and peak-to-peak (µm); contact_lost_share, the share of samples at which a helix half
    carries no load (F_mesh_left or F_mesh_right <= 0: its teeth have separated). A `Window`
    (run_window's) gives them from the finer sampling it carries (its switch samples into the
    extremes alone, the means of the even samples); any other dict {output name: samples},
    from its own samples."""
    statistics = getattr(window, "statistics", None)
    if statistics is None:
        names = [name for name in window if name != "time"]
        statistics = WindowStatistics((name, i) for i, name in enumerate(names))
        statistics.add(np.column_stack([np.asarray(window[name], dtype=float)
                                        for name in names]))
    return statistics.figures(static_force)


# A window has settled where its mesh force repeats an even number of mesh periods on (a
# period-2 orbit repeats too) to this share of the static force. Settled points of ten shipped
# scenes at their own speeds repeat to 2e-6 to 2e-5 of it, jump_resonance's upper branch to
# 1e-3; near its folds, where the branch's multiplier nears 1 and the start's transient dies
# slowly, points read 2e-2 to 1.2
SETTLED_DRIFT = 1e-2
# How many times a window that has not settled is recorded again from its end (run_window_from)
# unless the settle is given: the least-damped linear mode sets the settle, but where contact
# is lost the start's transient can last longer (jump_resonance at its own speed repeats to
# 1.9e-2 after the 5.6 ms that mode asks for, and to 8e-9 after 20 ms). Points near a fold,
# whose transient dies slowly, keep their flag after these and cost as many windows more
MORE_WINDOWS = 4


def window_drift(window: dict, protocol: Protocol, static_force: float) -> float:
    """How far the window's mesh force is from repeating: max |F_mesh(t + L·T) − F_mesh(t)|
    over its recorded samples, L the largest even number of mesh periods T under
    window_periods, as a share of the static force (N); NaN for a window under 3 periods."""
    lag = 2 * ((protocol.window_periods - 1) // 2) * protocol.samples_per_period
    force = np.asarray(window["F_mesh"], dtype=float)
    if lag == 0 or lag >= len(force):
        return math.nan
    return float(np.abs(force[lag:] - force[:-lag]).max() / abs(static_force))


def floquet_largest(scene) -> float:
    """|λ|max of the linear mesh at w0_pinion, every point loaded
    (herringbone.analysis.stability)."""
    from .stability import largest_multiplier

    return float(largest_multiplier(scene, abs(scene.parameters["w0_pinion"])))


def point_row(scene, window: dict, protocol: Protocol) -> dict[str, float]:
    """A table row: the point's timing, static force, window figures, how far its window is
    from repeating (window_drift) and linear_floquet_max, |λ|max of the linear mesh at the
    point's speed with every point loaded (the parametric stability `herringbone stability`
    charts; not the multiplier of the motion the window settled on, which a sweep by shooting
    gives as floquet_max)."""
    when = timing(scene, protocol)
    settle = getattr(window, "settle", when.settle)
    speed = scene.parameters["w0_pinion"]
    static_force = static_mesh_force(scene)
    row = {"speed_rpm": speed * RPM_PER_RAD_S,
           "mesh_frequency_Hz": 1.0 / when.mesh_period,
           "settle_time_s": settle, "window_time_s": when.window,
           "samples": when.samples, "figure_samples": figure_samples(window),
           "static_mesh_force_N": static_force,
           **window_figures(window, static_force),
           "window_drift": window_drift(window, protocol, static_force)}
    row["linear_floquet_max"] = floquet_largest(scene) if protocol.floquet else math.nan
    return row
