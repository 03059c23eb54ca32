"""One point of a sweep: a scene run at constant torques past its start-up transient, then
recorded over whole mesh periods, and the figures a drivetrain engineer reads off that window.

The protocol (`Protocol`, `timing`):
- settle: the least-damped mode of the train (linearized at the period-mean stiffness,
  GearTrainModel.eigenvalues) decays like exp(−σ·t); the start-up transient is run for
  ln(1/settle_residual)/σ, rounded up to whole mesh periods, so it has decayed to
  `settle_residual` of its initial amplitude (or for a given `settle_time`, also rounded up);
- window: `window_periods` mesh periods T = 2π/(z_pinion·|w0_pinion|), sampled
  `samples_per_period` times per period, the samples at settle + i·T/samples_per_period for
  i = 0 … N−1 (N = window_periods·samples_per_period: the window's end is its start one whole
  number of periods later, so it is left out).
The settle is integrated without stops; each sample is a stop of the compiled integrator.

Everything here is a plain function of its arguments, so a sweep can run it in any process.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

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

RIGID_FRACTION = 1e-6  # eigenvalues below this fraction of the largest are the rigid rotation
BEARINGS = tuple(f"F_brg_{gear}_{side}" for gear in ("pinion", "wheel")
                 for side in ("left", "right"))


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
    """Where a point's window lies: settle (s), sample interval (s), sample count."""

    mesh_period: float
    settle: float
    interval: float
    samples: int

    @property
    def window(self) -> float:
        """The span of the recorded samples, s."""
        return self.samples * self.interval

    def sample_times(self) -> np.ndarray:
        """The times (s) of the recorded samples, after the settling time."""
        return self.settle + np.arange(self.samples) * self.interval


def least_damped_decay_rate(scene) -> float:
    """σ (1/s) of the slowest-decaying mode other than the rigid rotation (the train's
    eigenvalues at the period-mean stiffness and damping; rigid: |λ| < 1e-6·|λ|max). The rigid
    rotation's eigenvalue is a defective double zero, which rounding moves by about
    √ε·|λ|max (1.2e-9·|λ|max on the gear pair alone, models/jump_resonance.toml), not ε·|λ|max."""
    modes = GearTrainModel(scene).eigenvalues()
    elastic = modes[np.abs(modes) > RIGID_FRACTION * np.abs(modes).max()]
    return float(np.abs(elastic.real).min())


def mesh_period(scene) -> float:
    """T = 2π/(z_pinion·|w0_pinion|), s; the pinion must turn."""
    speed = abs(scene.parameters["w0_pinion"])
    if speed == 0.0:
        raise ValueError("w0_pinion is 0: a sweep point needs a turning pinion "
                         "(allowed: w0_pinion != 0 rad/s)")
    return 2.0 * math.pi / (scene.parameters["z_pinion"] * speed)


def timing(scene, protocol: Protocol) -> Timing:
    """The settle and the window of a scene under a protocol (module docstring)."""
    period = mesh_period(scene)
    settle = protocol.settle_time
    if settle is None:
        settle = math.log(1.0 / protocol.settle_residual) / least_damped_decay_rate(scene)
    # 1e-9: a settle given as whole periods stays that many periods despite rounding
    periods = math.ceil(settle / period - 1e-9)
    return Timing(period, periods * period, period / protocol.samples_per_period,
                  protocol.window_periods * protocol.samples_per_period)


def run_window(scene, protocol: Protocol) -> dict[str, np.ndarray]:
    """The outputs at the window's samples, {"time": …, output: …}, from the compiled
    integrator: the scene's constant torques from its static start at w0_pinion."""
    return run_window_from(scene, protocol)[0]


def run_window_from(scene, protocol: Protocol, start: Position | None = None):
    """run_window from a given start (None: the static start at w0_pinion), and the position
    at the window's end. A start is taken as it is, its time counted as 0 (a sweep that starts
    each point from the last one's end moves the rigid speed to the point's first:
    `at_speed`)."""
    if len(scene.inputs.times) != 1:
        raise ValueError(f"{scene.source}: a sweep point needs constant input torques; "
                         "the scene has an input table (allowed: [inputs] M_motor, M_load)")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, protocol.tolerance)
    torques = scene.inputs.at(0.0)
    if start is None:
        start = start_position(model, torques[0])
    run = stepper.start(Position(0.0, start.state, start.segment, start.step_hint))
    when = timing(scene, protocol)
    times = when.sample_times()
    values = np.empty((len(times), model.output_layout_size))
    for i, t in enumerate(times):
        stepper.run_to(run, float(t), torques)
        values[i] = run.outputs
    window = {"time": times, **{name: values[:, i] for name, i in model.output_layout}}
    return window, stepper.position(run)


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


def window_figures(window: dict, static_force: float) -> dict[str, float]:
    """The figures of a recorded window (samples over whole mesh periods):
    K_v = max F_mesh / static mesh force; F_mesh min and max; peak |F| and rms of each bearing
    reaction; dte mean, rms about that mean and peak-to-peak (µm); contact_lost_share, the
    share of samples at which a helix half carries no load (F_mesh_left or F_mesh_right <= 0:
    its teeth have separated)."""
    force = window["F_mesh"]
    figures = {"K_v": float(force.max() / static_force),
               "F_mesh_min_N": float(force.min()), "F_mesh_max_N": float(force.max())}
    for name in BEARINGS:
        if name in window:
            figures[f"{name}_peak_N"] = float(np.abs(window[name]).max())
            figures[f"{name}_rms_N"] = float(np.sqrt(np.mean(window[name] ** 2)))
    dte = window["dte"] * 1e6
    figures.update(dte_mean_um=float(dte.mean()),
                   dte_rms_um=float(np.sqrt(np.mean((dte - dte.mean()) ** 2))),
                   dte_p2p_um=float(dte.max() - dte.min()))
    separated = (window["F_mesh_left"] <= 0.0) | (window["F_mesh_right"] <= 0.0)
    figures["contact_lost_share"] = float(separated.mean())
    return figures


def floquet_largest(scene) -> float:
    """|λ|max of the linear mesh at w0_pinion (herringbone.analysis.stability)."""
    from .stability import largest_multiplier

    return float(largest_multiplier(scene, abs(scene.parameters["w0_pinion"])))


def point_row(scene, window: dict, protocol: Protocol) -> dict[str, float]:
    """A table row: the point's timing, static force, window figures and Floquet |λ|max."""
    when = timing(scene, protocol)
    speed = scene.parameters["w0_pinion"]
    static_force = static_mesh_force(scene)
    row = {"speed_rpm": speed * RPM_PER_RAD_S,
           "mesh_frequency_Hz": 1.0 / when.mesh_period,
           "settle_time_s": when.settle, "window_time_s": when.window,
           "samples": when.samples, "static_mesh_force_N": static_force,
           **window_figures(window, static_force)}
    row["floquet_max"] = floquet_largest(scene) if protocol.floquet else math.nan
    return row
