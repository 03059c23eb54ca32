"""The periodic steady state directly: Newton shooting on the mesh period.

Under constant torques that balance (M_load = u·M_motor) the train is autonomous: the mesh
depends on the pinion angle φp, a state, not on time. The rigid rotation's momentum
p = rᵀ·M·q̇ = R·θ̇ (R = rᵀ·M·r, θ = rᵀ·M·q/R the mass-weighted rigid angle) is conserved, since no
element deforms under r and the torques balance: θ advances at exactly ω = p/R. We fix p by the
pinion speed ω of the point (a time sweep, started in rigid rotation at w0_pinion, has the same
p), so a steady state that repeats every k mesh periods has the period T = k·(2π/z_pinion)/ω,
and after T the rigid angle has advanced exactly k pitches.

The section. A state on the orbit is taken where φp is halfway through the first contact
interval of a mesh period (no switch there, so which points exist is never ambiguous). The
unknowns z are the state's other entries — the relative coordinates y_i and rates ẏ_i of every
coordinate but the pinion's — with ẏ_pinion given by p; 2(n−1) of them, scaled by
`state_scales` so that a unit is a force of the size of the static mesh force. The map
z -> z(T) (the compiled integrator over the fixed time T) has the orbit as a fixed point, and
at a fixed point φp is back on the section by itself (θ advanced k pitches, the y_i are back).
Newton solves G(z) = z(T) − z = 0 with the Jacobian A − I, A = ∂z(T)/∂z the monodromy of the
map: by default from the variational equations through the segments of the period, with the
saltation of the sensitivities at each event (integrate/variational.py, docs/monodromy.md), one
integration of the state and its 2(n−1) sensitivities; `jacobian_method="differences"` takes
forward differences of the compiled map instead (one period integration an unknown), the
check. Started from the static deflection, the first Newton step is
the linear mesh's periodic solution (I − A)⁻¹·b exactly where the map is affine (no contact
loss); a continuation starts each point from its predictor instead.

Floquet multipliers. The fixed-time map's Jacobian A is not the Poincaré map's: a perturbation
also moves where on the orbit the state is after T. The Poincaré map's Jacobian (return to the
section φp = const) is A − (P·f)·(∂φp(T)/∂z)/φ̇p, f the vector field at the orbit point and P
the projection on the unknowns; its 2(n−1) eigenvalues are the orbit's nontrivial Floquet
multipliers (the trivial pair 1, 1 — phase and momentum — is left out).

The figures of an orbit are those of a time sweep's window (sweep_point.window_figures),
sampled at the same phases of θ as the time protocol samples its figures: its samples lie at
θ_start + (whole pitches) + j·pitch/(samples_per_period·refinement), θ_start the rigid angle
of its start and refinement sweep_point.figure_refinement's (the fastest mode resolved), with
each contact switch sampled finer (sweep_point.switch_samples).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from ..arguments import check_scene
from ..integrate.compiled_stepper import EXPLICIT_STEP_BOUND, CompiledStepper
from ..integrate.contract import IntegrationError, Position, start_position
from ..integrate.segments import Segment, begin, contact_band, point_approaches
from ..integrate.variational import VariationalFlow, multiplier_step
from ..model import equations
from ..model.assembly import GearTrainModel
from ..model.geometry import GearGeometry
from ..shipped import named_as_typed
from .sweep_point import (
    WindowStatistics,
    fastest_ringing,
    figure_refinement,
    sample_chunks,
    static_mesh_force,
)

# the compiled integrator's tolerance for the period integrations. The map it computes is one
# smooth discrete map (a perturbation of 1e-6 takes the same steps), so Newton and the
# differences converge on it at any tolerance; its orbits' figures and multipliers differ from
# those at 1e-10 by at most 2.3e-9 (K_v), 1.4e-8 (dte peak-to-peak) and 5.7e-8 (|λ|) on the
# reference scene at 100-3000 rad/s, and cost 27 % less (measured: docs/steady-state.md)
SHOOTING_TOLERANCE = 1e-8
# Newton stops when every entry of z(T) − z is within this fraction of its state scale (a force
# error of this fraction of the static mesh force)
NEWTON_TOLERANCE = 1e-8
NEWTON_ITERATIONS = 12
DIFFERENCE_STEP = 1e-6  # forward-difference step, in state scales
# how PeriodMap.jacobian takes A = ∂z(T)/∂z: "variational" (the variational equations through
# the segments with the saltation at each event, docs/monodromy.md) or "differences" (forward
# differences of the map, one period integration an unknown: the check)
JACOBIAN_METHODS = ("variational", "differences")
# A period-2 branch leaves its doubling along a line of orbits (while no contact is lost the map
# over 2T is affine, with a multiplier +1) up to the orbit whose teeth first touch zero load,
# where it turns off at a corner. The variational A there is the one-sided derivative of the
# affine side, whose tangent runs on along the line, and the continuation's steps past the
# corner fail; the differences' secant straddles it and leads round. So maps over several mesh
# periods take the differences by default (docs/monodromy.md).
MULTI_PERIOD_JACOBIAN = "differences"
# the variational run's fixed steps keep each mode's multiplier within this of its value, by
# DOP853's error constant (integrate/variational.multiplier_step), with STEP_MARGIN for the
# stiffest contact set, whose modes are faster than the mean set's; and they stay within
# DOP853's stability bound (EXPLICIT_STEP_BOUND/|λ|max). Measured: docs/monodromy.md.
MULTIPLIER_ERROR = 1e-6
STEP_MARGIN = 0.8
# a multiplier is on the unit circle (neither stable nor unstable) within this much
UNIT_CIRCLE_BAND = 1e-6
SAMPLES_PER_PERIOD = 64  # as sweep_point.Protocol's default (refined: figure_refinement)
# A period integration gives up (StepBudgetExceeded, an IntegrationError: the iterate fails)
# past this many steps per radian of the fastest mode, plus LEAST_STEP_BUDGET: a Newton iterate
# far from the orbit may lose and regain contact over and over (the gear pair alone at 700 rad/s
# took 18.9 million steps, 154 s, for one period where an orbit takes 550). DOP853 takes at
# least 1/3.5 of a step per radian of it (compiled_stepper.EXPLICIT_STEP_BOUND).
STEP_BUDGET_PER_FASTEST = 50.0
LEAST_STEP_BUDGET = 5000


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic steady state at one pinion speed, at the section (module docstring)."""

    pinion_speed: float  # ω, rad/s
    mesh_periods: int  # k: the orbit repeats every k mesh periods
    period: float  # k·(2π/z_pinion)/ω, s
    state: np.ndarray  # [y, ẏ] at the section, relative coordinates (model docstring)
    multipliers: np.ndarray  # nontrivial Floquet multipliers, largest modulus first
    residual: float  # max |z(T) − z| in state scales (fraction of the static mesh force)
    iterations: int  # Newton iterations taken
    converged: bool
    figures: dict = field(default_factory=dict)  # window_figures of one orbit period

    @property
    def stable(self) -> bool:
        """Every nontrivial multiplier inside the unit circle."""
        return bool(np.abs(self.multipliers).max() < 1.0 - UNIT_CIRCLE_BAND)

    @property
    def largest_exponent(self) -> float:
        """ln|λ|max / T (1/s): the growth rate of the fastest-growing disturbance (< 0:
        stable; −σ of the least-damped disturbance)."""
        return float(math.log(np.abs(self.multipliers).max()) / self.period)


class ShootingError(ValueError):
    """A scene the shooting method cannot take (it says why and what is allowed)."""


def gear_ratio(scene) -> float:
    """u = z_wheel/z_pinion of the scene, from its geometry alone (no train assembled: a
    continuation in a torque asks for it at every value)."""
    return GearGeometry.from_parameters(scene.parameters).ratio


def check_balanced(scene) -> tuple[float, float]:
    """The scene's constant torques (M_motor, M_load), which must balance (M_load =
    u·M_motor, to 1e-9 of it): else the train accelerates and has no steady state."""
    if len(scene.inputs.times) != 1:
        raise ShootingError(f"{named_as_typed(scene)}: a steady state needs constant input "
                            "torques; the scene has an input table (allowed: [inputs] "
                            "M_motor, M_load)")
    motor, load = (float(t) for t in scene.inputs.at(0.0))
    unbalanced = unbalance(scene)
    if unbalanced is not None:
        balanced = gear_ratio(scene) * motor
        raise ShootingError(f"{unbalanced}: the train accelerates and has no periodic steady "
                            f"state; allowed: M_load = u·M_motor = {balanced:g} N·m")
    return motor, load


def unbalance(scene) -> str | None:
    """"M_load = … N·m does not balance M_motor = … N·m (u = …)" where the scene's torques
    are constant and M_load is not u·M_motor (to 1e-9 of it); None where they balance or
    follow an input table (whose steps are the run's own)."""
    if len(scene.inputs.times) != 1:
        return None
    motor, load = (float(t) for t in scene.inputs.at(0.0))
    ratio = gear_ratio(scene)
    if abs(load - ratio * motor) <= 1e-9 * max(abs(load), abs(ratio * motor), 1e-300):
        return None
    return (f"M_load = {load:g} N·m does not balance M_motor = {motor:g} N·m "
            f"(u = {ratio:g})")


def unbalance_lines(scene) -> list[str]:
    """What `info` and a run's summary say of torques that do not balance (unbalance): the
    train accelerates, as a scene that gives M_motor alone and keeps the reference's M_load
    does, or one whose input table steps one torque alone; [] where they balance."""
    if len(scene.inputs.times) > 1:
        return _table_unbalance_lines(scene)
    unbalanced = unbalance(scene)
    if unbalanced is None:
        return []
    return [f"{unbalanced}: the train accelerates (steady running needs M_load = u·M_motor = "
            f"{gear_ratio(scene) * scene.inputs.at(0.0)[0]:g} N·m)"]


def _table_unbalance_lines(scene) -> list[str]:
    """unbalance_lines of a scene with an input table: the first row whose torques do not
    balance (to 1e-9), and how many more there are."""
    ratio, inputs = gear_ratio(scene), scene.inputs
    rows = [(float(t), float(m), float(load))
            for t, m, load in zip(inputs.times, inputs.M_motor, inputs.M_load)
            if abs(load - ratio * m) > 1e-9 * max(abs(load), abs(ratio * m), 1e-300)]
    if not rows:
        return []
    time, motor, load = rows[0]
    more = f", and in {len(rows) - 1} later rows" if len(rows) > 1 else ""
    return [f"from t = {time:g} s M_load = {load:g} N·m does not balance M_motor = {motor:g} "
            f"N·m (u = {ratio:g}{more}): the train accelerates while they hold (steady "
            "running needs M_load = u·M_motor)"]


def balanced_torques(scene, name: str, value: float) -> dict[str, float]:
    """Both input torques where one of them (`name`, "M_motor" or "M_load") is set to `value`
    and the other follows so that they balance (M_load = u·M_motor): the transmitted torque
    set by either end, as a sweep or continuation in a torque of a balanced scene takes it."""
    ratio = gear_ratio(scene)
    if name == "M_motor":
        return {"M_motor": value, "M_load": ratio * value}
    return {"M_motor": value / ratio, "M_load": value}


def unknown_scales(model: GearTrainModel) -> np.ndarray:
    """For each state entry, the change that moves its generalized elastic force by the
    static mesh force's share in that coordinate: F·Rp on the motor and pinion angles, F·Rw on
    the wheel and load angles, F on displacements, F times the widest lever arm on tilts,
    divided by the coordinate's mean stiffness; a rate by its ω_i = √(K_ii/M_ii) times that.
    (model.state_scales takes F itself on every coordinate: on the soft motor shaft a unit
    would wind it up 40 times its static torque, which makes the map strongly nonlinear per
    unit there.)"""
    force = model.force_scale()
    g = model.geometry
    lever = float(np.abs(model.mesh.period_table()[2][:, equations.LEVER_ARM0]).max())
    levers = {"phi_motor": g.radius_pinion, "phi_pinion": g.radius_pinion,
              "phi_wheel": g.radius_wheel, "phi_load": g.radius_wheel,
              "psi_pinion": lever, "psi_wheel": lever, "x_pinion": 1.0, "x_wheel": 1.0}
    stiffness = np.diag(model.mean_stiffness_matrix())
    deflection = force * np.array([levers[c] for c in model.coordinates]) / stiffness
    return np.concatenate([deflection, deflection * np.sqrt(stiffness / model.mass)])


class PeriodMap:
    """z -> z(T) on the section, and its derivatives, for one scene (any speed)."""

    def __init__(self, scene, tolerance: float = SHOOTING_TOLERANCE, mesh_periods: int = 1,
                 scales: np.ndarray | None = None, method: str = "auto",
                 jacobian_method: str | None = None):
        """scales: the unknowns' scales (default `unknown_scales` of this scene; a
        continuation in a parameter gives every value's map the first one's, so that z is the
        same state at every value); method: the compiled integrator's (CompiledStepper);
        jacobian_method: how `jacobian` takes A (JACOBIAN_METHODS; None: "variational" over
        one mesh period, "differences" over several, see MULTI_PERIOD_JACOBIAN)."""
        check_scene(scene)
        if jacobian_method is None:
            jacobian_method = "variational" if mesh_periods == 1 else MULTI_PERIOD_JACOBIAN
        if jacobian_method not in JACOBIAN_METHODS:
            raise ValueError(f"jacobian_method {jacobian_method!r}: allowed are "
                             f"{', '.join(JACOBIAN_METHODS)}")
        self.jacobian_method = jacobian_method
        self.torques = check_balanced(scene)
        self.scene = scene
        self.model = model = GearTrainModel(scene)
        self.stepper = CompiledStepper(model, tolerance, method)
        self.fastest_ringing = fastest_ringing(model)  # Hz: the orbit figures' sampling
        self.mesh_periods = int(mesh_periods)
        self.size = n = model.size
        self.pinion = model.pinion
        self.free = np.array([i for i in range(n) if i != model.pinion])
        self.unknown_entries = np.concatenate([self.free, n + self.free])
        self.scales = (unknown_scales(model)[self.unknown_entries] if scales is None
                       else np.asarray(scales, dtype=float))
        weights = model.mass * model.rigid_rotation
        self.rigid_inertia = float(weights @ model.rigid_rotation)  # R
        self.momentum_weights = weights[self.free] / self.rigid_inertia  # M_i·r_i/R, i ≠ p
        self.section_set = model.mesh.contact_set(0, 0)
        self.section_phase = 0.5 * self.section_set.length
        self.pitch = model.geometry.angular_pitch
        self.evaluations = 0  # period integrations done, for benchmarks
        self.variational_evaluations = 0  # of them, variational ones (jacobian)
        self.contact_band = contact_band(model)
        self.run = self.stepper.start(start_position(model, self.torques[0]))

    # --- coordinates --------------------------------------------------------------------

    def period(self, speed: float) -> float:
        """T = k·pitch/ω, s."""
        return self.mesh_periods * self.pitch / speed

    def state(self, unknowns: np.ndarray, speed: float) -> np.ndarray:
        """The full state [y, ẏ] on the section for scaled unknowns at pinion speed ω."""
        n = self.size
        state = np.empty(2 * n)
        state[self.unknown_entries] = unknowns * self.scales
        state[self.pinion] = self.section_phase
        state[n + self.pinion] = speed - self.momentum_weights @ state[n + self.free]
        return state

    def unknowns(self, state: np.ndarray) -> np.ndarray:
        """The scaled unknowns of a state."""
        return state[self.unknown_entries] / self.scales

    def rigid_angle(self, state: np.ndarray, contact_set) -> float:
        """θ (rad) of a state whose pinion entry is counted from `contact_set`'s start."""
        y = state[:self.size]
        pinion_angle = contact_set.pinion_angle + y[self.pinion]
        return pinion_angle + self.momentum_weights @ y[self.free]

    def static_unknowns(self) -> np.ndarray:
        """The static deflection under M_motor on the section: Newton's first guess."""
        y = np.zeros(self.size)
        y[self.pinion] = self.section_phase
        y = self.model.static_deflection(y, self.section_set, self.torques[0])
        return self.unknowns(np.concatenate([y, np.zeros(self.size)]))

    # --- the map ------------------------------------------------------------------------

    def loaded(self, state: np.ndarray) -> np.ndarray:
        """Which points of the section's set carry load at a state on it: segments.begin's
        rule, its approaches by the compiled equations; a point within the contact band is
        left to begin itself (its approach rate decides)."""
        model = self.model
        if not model.contact_loss:
            return np.ones(len(self.section_set))
        approach = point_approaches(model, self.section_set, state)
        if np.any(np.abs(approach) <= self.contact_band):
            return begin(model, self.section_set, state.copy(), self.torques).loaded
        return (approach > 0.0).astype(float)

    def start(self, state: np.ndarray) -> Position:
        """A position at time 0 on the section (points loaded by their approach)."""
        return Position(0.0, state, Segment(self.section_set, self.loaded(state)))

    def reset_run(self, state: np.ndarray) -> None:
        """The map's Run set, in place, to time 0 at `state` on the section (no step-size
        memory carried over: the map depends on the state alone, as differences of it need)."""
        run = self.run
        run.clock[0], run.clock[1] = 0.0, self.stepper.first_step
        run.place[0], run.place[1] = self.section_set.index, self.section_set.cycle
        run.state[:] = state
        run.loaded[:] = 0.0
        run.loaded[:len(self.section_set)] = self.loaded(state)
        run.first_steps[:] = 0.0

    @functools.cached_property
    def static_force(self) -> float:
        """The figures' yardstick, M_motor/Rp (N), worked out once per map (it raises for a
        scene without motor torque, so only where figures are asked for)."""
        return static_mesh_force(self.scene)

    def step_budget(self, period: float) -> int:
        """The most steps one integration over `period` (s) may take before it gives up."""
        return int(STEP_BUDGET_PER_FASTEST * period * self.stepper.fastest_rate) \
            + LEAST_STEP_BUDGET

    def flow(self, state: np.ndarray, speed: float) -> tuple[np.ndarray, float]:
        """The state after T, re-expressed on the section's interval k periods on, and the
        offset of its φp from the section (rad; 0 on a periodic orbit). The period runs on
        one Run of the compiled integrator, reset in place to the same start each time (no
        step-size memory carried from one period integration to the next: the map depends on
        the state alone, as differences of it need)."""
        self.evaluations += 1
        run, stepper = self.run, self.stepper
        self.reset_run(state)
        period = self.period(speed)
        stepper.run_to(run, period, self.torques, self.step_budget(period))
        end_set = self.model.mesh.contact_set(int(run.place[1]), int(run.place[0]))
        target = self.model.mesh.interval_start(self.mesh_periods, 0) + self.section_phase
        offset = end_set.pinion_angle + run.state[self.pinion] - target
        return run.state.copy(), float(offset)

    def section_unknowns(self, position: Position, speed: float) -> np.ndarray | None:
        """The unknowns where a run of this scene from `position` (anywhere in a period, e.g.
        a time run's end) next reaches the section: integrated for the time the rigid rotation
        at ω takes to bring φp there (the vibration moves the crossing's φp by its small share,
        which Newton takes up); None where the run ends outside the section's interval."""
        mesh = self.model.mesh
        here = position.segment.contact_set
        angle = here.pinion_angle + position.state[self.pinion]
        target = mesh.interval_start(here.cycle + 1, 0) + self.section_phase
        duration = (target - angle) / speed
        run = self.stepper.start(Position(0.0, position.state, position.segment))
        self.stepper.run_to(run, duration, self.torques, self.step_budget(duration))
        if int(run.place[0]) != self.section_set.index:
            return None
        return self.unknowns(run.state)

    def residual(self, unknowns: np.ndarray, speed: float):
        """G = z(T) − z (scaled), the end state and its φp offset."""
        end, offset = self.flow(self.state(unknowns, speed), speed)
        return self.unknowns(end) - unknowns, end, offset

    def jacobian(self, unknowns: np.ndarray, speed: float, base=None):
        """∂z(T)/∂z (A, scaled) and ∂φp(T)/∂z (row, rad a unit), by the map's
        `jacobian_method`: the variational equations (`variational_jacobian`) or forward
        differences from `base` (`difference_jacobian`)."""
        if self.jacobian_method == "variational":
            return self.variational_jacobian(unknowns, speed)
        return self.difference_jacobian(unknowns, speed, base)

    @functools.cached_property
    def directions(self) -> np.ndarray:
        """∂(state on the section)/∂z: each unknown moves its own entry by its scale, and a
        rate also the pinion's rate, which the momentum fixes (`state`)."""
        n, count = self.size, len(self.unknown_entries)
        directions = np.zeros((2 * n, count))
        directions[self.unknown_entries, np.arange(count)] = self.scales
        rates = np.arange(len(self.free), count)
        directions[n + self.pinion, rates] = -self.momentum_weights * self.scales[rates]
        return directions

    @functools.cached_property
    def modes(self) -> np.ndarray:
        """The eigenvalues (1/s) of the train at its mean stiffness and damping."""
        return self.model.eigenvalues()

    @functools.cached_property
    def variational_flow(self) -> VariationalFlow:
        """The variational run's integrator, its steps within DOP853's stability bound (also
        where the map runs Radau IIA)."""
        return VariationalFlow(self.model, EXPLICIT_STEP_BOUND / np.abs(self.modes).max())

    def variational_jacobian(self, unknowns: np.ndarray, speed: float):
        """∂z(T)/∂z (A, scaled) and ∂φp(T)/∂z (row), by the variational equations through
        the segments of one period, with the saltation of the sensitivities at each event
        (integrate/variational.py): one integration of the state and its 2(n−1)
        sensitivities."""
        self.evaluations += 1
        self.variational_evaluations += 1
        state, period = self.state(unknowns, speed), self.period(speed)
        step = STEP_MARGIN * multiplier_step(self.modes, period, MULTIPLIER_ERROR)
        _, sensitivity, _ = self.variational_flow.run(self.start(state), period, self.torques,
                                                      self.directions, step)
        return (sensitivity[self.unknown_entries] / self.scales[:, None],
                sensitivity[self.pinion].copy())

    def difference_jacobian(self, unknowns: np.ndarray, speed: float, base=None):
        """∂z(T)/∂z (A, scaled) and ∂φp(T)/∂z (row), by forward differences from `base`
        (residual's result at the point, computed if not given)."""
        if base is None:
            base = self.residual(unknowns, speed)
        residual, end, offset = base
        count = len(unknowns)
        images = np.empty((count, count))
        phase_row = np.empty(count)
        for j in range(count):
            shifted = unknowns.copy()
            shifted[j] += DIFFERENCE_STEP
            moved, moved_offset = self.flow(self.state(shifted, speed), speed)
            images[:, j] = (self.unknowns(moved) - self.unknowns(end)) / DIFFERENCE_STEP
            phase_row[j] = (moved_offset - offset) / DIFFERENCE_STEP
        return images, phase_row

    def poincare(self, images: np.ndarray, phase_row: np.ndarray,
                 state: np.ndarray) -> np.ndarray:
        """The Poincaré map's Jacobian (scaled unknowns) from the fixed-time one (module
        docstring)."""
        rate = self.model.derivative(state, self.section_set,
                                     self.start(state).segment.loaded, *self.torques)
        along = rate[self.unknown_entries] / self.scales
        return images - np.outer(along, phase_row) / rate[self.pinion]

    def multipliers(self, images: np.ndarray, phase_row: np.ndarray,
                    state: np.ndarray) -> np.ndarray:
        """The nontrivial Floquet multipliers from the fixed-time Jacobian (module docstring),
        largest modulus first."""
        values = np.linalg.eigvals(self.poincare(images, phase_row, state))
        return values[np.argsort(-np.abs(values), kind="stable")]

    # --- what the user reads --------------------------------------------------------------

    def figures(self, state: np.ndarray, speed: float,
                samples_per_period: int = SAMPLES_PER_PERIOD) -> dict[str, float]:
        """window_figures over one orbit period, sampled at the time protocol's phases of its
        figures (sweep_point: `samples_per_period` a mesh period, refined so that the fastest
        mode has FASTEST_MODE_SAMPLES a period, and each contact switch sampled finer), on the
        map's own Run from `state` as `flow` starts, in compiled calls of many samples."""
        model = self.model
        start = start_position(model, self.torques[0])
        theta_start = self.rigid_angle(start.state, start.segment.contact_set)
        theta_section = self.rigid_angle(state, self.section_set)
        period = self.period(speed)
        per_period = samples_per_period * figure_refinement(self.fastest_ringing,
                                                            self.pitch / speed,
                                                            samples_per_period)
        count = self.mesh_periods * per_period
        offsets = theta_start + np.arange(count) * self.pitch / per_period - theta_section
        times = np.sort(np.mod(offsets / speed, period))
        self.evaluations += 1
        self.reset_run(state)
        run = self.run
        run.outputs[:] = model.output_vector(state, self.section_set,
                                             run.loaded[:len(self.section_set)])
        statistics = WindowStatistics(model.output_layout)
        for _, rows, switches in sample_chunks(self.stepper, run, self.torques, count,
                                               times.__getitem__, self.step_budget(period)):
            statistics.add(rows)
            statistics.add_extremes(switches)
        return statistics.figures(self.static_force)


def newton(period_map: PeriodMap, unknowns: np.ndarray, speed: float,
           tolerance: float = NEWTON_TOLERANCE, iterations: int = NEWTON_ITERATIONS):
    """Newton on G(z) = z(T) − z at a fixed speed, the Jacobian by differences at every
    iteration. Returns (z, residual norm, iterations, converged, (A, phase row, base))."""
    z = np.asarray(unknowns, dtype=float).copy()
    base = period_map.residual(z, speed)
    norm = float(np.abs(base[0]).max())
    taken = 0
    images = phase_row = None
    while taken < iterations:
        images, phase_row = period_map.jacobian(z, speed, base)
        if norm <= tolerance:
            break
        z = z - np.linalg.solve(images - np.eye(len(z)), base[0])
        taken += 1
        base = period_map.residual(z, speed)
        norm = float(np.abs(base[0]).max())
        if not np.isfinite(norm):
            break
    else:
        images, phase_row = period_map.jacobian(z, speed, base)
    converged = bool(norm <= tolerance)
    return z, norm, taken, converged, (images, phase_row, base)


def orbit_record(period_map: PeriodMap, unknowns, speed, norm, taken, converged, images,
                 phase_row, figures=True) -> PeriodicOrbit:
    """A PeriodicOrbit from a solved (or abandoned) Newton iteration."""
    state = period_map.state(unknowns, speed)
    multipliers = (period_map.multipliers(images, phase_row, state) if images is not None
                   else np.full(len(unknowns), np.nan))
    return PeriodicOrbit(
        pinion_speed=float(speed), mesh_periods=period_map.mesh_periods,
        period=period_map.period(speed), state=state, multipliers=multipliers,
        residual=norm, iterations=taken, converged=converged,
        figures=period_map.figures(state, speed) if figures and converged else {})


def periodic_orbit(scene, pinion_speed: float, initial_state=None, mesh_periods: int = 1,
                   tolerance: float = SHOOTING_TOLERANCE,
                   newton_tolerance: float = NEWTON_TOLERANCE,
                   iterations: int = NEWTON_ITERATIONS) -> PeriodicOrbit:
    """The periodic steady state of a scene at a pinion speed (rad/s) by Newton shooting.

    initial_state: a state [y, ẏ] on the section to start from (e.g. an orbit's `state`);
    None starts from the static deflection, whose first Newton step is the linear mesh's
    periodic solution. mesh_periods: k, for an orbit that repeats every k mesh periods.
    tolerance: the integrator's; newton_tolerance: on z(T) − z, a fraction of the static
    mesh force. The result says whether Newton converged (`converged`); its figures are those
    of a sweep point's window (sweep_point.window_figures) over one orbit period."""
    speed = float(pinion_speed)
    if not (math.isfinite(speed) and speed > 0.0):
        raise ValueError(f"pinion_speed is {pinion_speed!r}; allowed: finite and > 0 rad/s")
    period_map = PeriodMap(scene, tolerance, mesh_periods)
    start = (period_map.static_unknowns() if initial_state is None
             else period_map.unknowns(np.asarray(initial_state, dtype=float)))
    try:
        z, norm, taken, converged, (images, phase_row, _) = newton(
            period_map, start, speed, newton_tolerance, iterations)
    except IntegrationError:
        return PeriodicOrbit(speed, period_map.mesh_periods, period_map.period(speed),
                             period_map.state(start, speed),
                             np.full(len(start), np.nan), math.inf, 0, False)
    return orbit_record(period_map, z, speed, norm, taken, converged, images, phase_row)
