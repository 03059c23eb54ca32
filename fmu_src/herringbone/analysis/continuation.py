"""The branch of periodic steady states over a range of one quantity: pseudo-arclength
continuation of the shooting problem of steady_state.py in the pinion speed, or at a fixed
pinion speed in a scene parameter or an input torque.

The continued quantity p is the speed ω (`SpeedAxis`: one PeriodMap serves every speed) or a
parameter (`ParameterAxis`: a PeriodMap per value, each with the first one's unknown scales, so
that z is the same state at every value). A torque keeps the train balanced: the other torque
follows it, M_load = u·M_motor (steady_state.balanced_torques): the transmitted torque is what
is continued, set by either end.

The unknowns are v = (z/Z, p/W): the section's scaled state z (steady_state) in units of
Z = `AMPLITUDE_UNIT` of the static mesh force, and p in units of W, the spacing of the
requested values, so that a step of length 1 moves p by one requested spacing or the state by
Z. From a solved point with tangent t (the null vector of [∂G/∂z·Z, ∂G/∂p·W], ∂G/∂p by a
forward difference of the map at p and p + h):

- where no real multiplier of the last orbit lies within `FOLD_PROXIMITY` of +1, the step goes
  to the next requested value in the branch's direction and the corrector holds p there
  (natural continuation: a row at every requested value); elsewhere — near a fold — the
  predictor is v + s·t and the corrector holds tᵀ·(v − v_pred) = 0 (pseudo-arclength), which
  passes folds;
- corrector: chord Newton with the last point's Jacobian, updated by Broyden's rank-one rule, at
  most `CORRECTOR_ITERATIONS` iterations; then the Jacobian afresh at the solution (the Floquet
  multipliers and the next tangent need it);
- step control: the step grows by 1.5 after a corrector of at most 2 iterations, shrinks by 0.6
  after one of 5 or more, halves on failure; a solved step over which K_v changes by more than
  `FIGURE_CHANGE` (or dte peak-to-peak over |dte_mean| by as much) is refused and taken again
  shorter in proportion, until it moves p by at most `FINEST_FIGURE_STEP`, and the next step
  (natural ones too: `Continuation.reach`) is kept to what that change allows, so that a
  sharp feature of the figures gets points where Newton alone would step over it; below
  `SMALLEST_STEP` the continuation gives up on this stretch: the next requested value is run
  by time integration (steady_state's section is not needed for that: sweep_point's
  protocol) and marked so, and shooting starts again at the following one from the last
  orbit.

What is flagged on the point past it: a fold where t_p changes sign (a multiplier through +1),
a period doubling where a real multiplier passes −1, a torus (Neimark–Sacker) where a complex
pair leaves or enters the unit circle. The period-1 branch is followed through all three; past
a period doubling or torus it is unstable, and the motion a time run shows there is not on it.
At each period doubling the period-2 branch is switched to and followed as well
(follow_doublings: located, started along the −1 multiplier's eigenvector, continued over 2T
by the same driver); its own doublings (to period 4) are flagged, not followed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..integrate.contract import IntegrationError
from ..model.parameters import INPUTS, PARAMETERS, RPM_PER_RAD_S, unit_of, with_unit
from ..model.scene import SceneError
from .progress_bar import Status, progress_bar
from .steady_state import (
    DIFFERENCE_STEP,
    NEWTON_TOLERANCE,
    SHOOTING_TOLERANCE,
    UNIT_CIRCLE_BAND,
    PeriodicOrbit,
    PeriodMap,
    balanced_torques,
    newton,
    orbit_record,
)

SPEED = "w0_pinion"
AMPLITUDE_UNIT = 1.0  # Z: fraction of the static mesh force that one unit of step moves z
CORRECTOR_ITERATIONS = 6
REUSE_DISTANCE = 3e-2  # see Continuation.accept
FOLD_PROXIMITY = 0.05  # see Continuation.near_fold
CORRECTION_FRACTION = 0.5  # most correction, as a fraction of the predictor's step
NATURAL_HALVINGS = 5  # see Continuation.advance
REFRESHES = 1  # fresh Jacobians a corrector may take where the chord contracts slowly
SMALLEST_STEP = 1e-3
# a step over which K_v changes by more than FIGURE_CHANGE (a share of the static mesh force),
# or dte peak-to-peak over |dte_mean| (a share of the static deflection) by as much, is
# taken again shorter, down to FINEST_FIGURE_STEP: the line the pictures draw between two
# points then misreads a curve that is monotone between them by at most that much. Newton
# alone steps over sharp features: at 450 rad/s the reference's K_v falls from 2.17 at beta
# 0.3531 to 1.00 at ε_β = 1 (β 0.36724) and jumps back to 1.50 by 0.36738, where a step of
# Newton's goes from 0.3531 to 0.3765. 0.05 is a twentieth of that fall, and of the axis of a
# resonance curve (K_v 1.45-1.79 on the reference over 100-1000 rad/s, 12 speeds: 58 points,
# 7 % more period integrations than Newton's steps alone)
FIGURE_CHANGE = 0.05
# 1/128 of a requested spacing: K_v's jump at ε_β = 1 (dte peak-to-peak goes on smoothly)
# is pinned to within 4e-4 rad of beta
FINEST_FIGURE_STEP = 1.0 / 128
# a fold is where t_p changes sign; a tangent with |t_p| below this goes straight across p
# and says nothing of the branch's way in p (the period-2 branch leaves its doubling so while
# no contact is lost, the map affine there: t_p is the differences' noise, 1e-3, and would
# flag folds that are none), so the sign is compared with the last point's that had one
STRAIGHT_ACROSS = 1e-2
LARGEST_STEP = 3.0  # three spacings of the requested values
MOST_POINTS = 2000  # the continuation gives up past this many points, and past
MOST_POINTS_PER_SPEED = 8  # this many per requested value where that is more
MAPS_KEPT = 8  # a parameter's PeriodMaps kept (see ParameterAxis)
# branch switching at a period doubling (follow_doublings): the bifurcation is located until a
# multiplier is within DOUBLING_TOLERANCE of −1 (at most LOCATE_ITERATIONS orbits), the
# period-2 branch started SWITCH_STEP (in Z) along the eigenvector from it, and taken to have
# come back to the period-1 branch where its change over one mesh period falls below
# REJOIN_FRACTION of its first point's
DOUBLING_TOLERANCE = 1e-6
LOCATE_ITERATIONS = 20
SWITCH_STEP = 1e-2
REJOIN_FRACTION = 0.5
# a failed period integration, a singular Jacobian, or a corrector's value out of the
# parameter's range: the step fails and is retried shorter
STEP_FAILURES = (IntegrationError, np.linalg.LinAlgError, SceneError)


@dataclass
class BranchPoint:
    """One point of a branch: the continued quantity's value and the pinion speed, its orbit
    (None for a time-integration point), how it was found, and what happened between it and
    the point before."""

    value: float  # the continued quantity (Branch.name), in its unit
    speed: float  # rad/s
    orbit: PeriodicOrbit | None
    method: str  # "shooting" or "time"
    on_grid: bool  # at one of the requested values
    # "fold", "period doubling", "torus"; "restart": the first orbit after the branch was lost
    events: tuple[str, ...] = ()
    figures: dict = field(default_factory=dict)
    tangent_value: float = math.nan  # t_p at the point (its sign: the branch's direction)
    follows: dict = field(default_factory=dict)  # columns that follow p (the other torque)
    # max |z(T) − z| of the orbit over one mesh period T, in state scales: 0 on a period-1
    # orbit, the distance of a period-2 orbit from being one (measured on 2T branches only)
    change_over_mesh_period: float = math.nan


@dataclass
class Branch:
    """The points in the order of the branch (arclength), the values of its folds, and the
    name of the continued quantity (w0_pinion, a parameter, M_motor or M_load); for the
    period-1 branch, the period-2 branches switched to at its period doublings (`doubled`,
    each a Branch of mesh_periods 2) and the values where those doublings were located."""

    points: list[BranchPoint]
    folds: list[float]
    evaluations: int = 0  # period integrations it took (Jacobians, residuals, figures)
    name: str = SPEED
    mesh_periods: int = 1
    doubled: list[Branch] = field(default_factory=list)
    doublings: list[float] = field(default_factory=list)

    def table(self):
        """A pandas DataFrame, a row a point in branch order, this branch's rows then each
        doubled branch's: the continued quantity (its name), speed_rpm, the torque that
        follows a continued torque (M_load_Nm or M_motor_Nm), the sweep figures (over the
        orbit's period), floquet_max (|λ|max of the orbit over its period),
        floquet_exponent_per_s, stability ('stable', 'unstable' or 'time' where no orbit
        converged), method, on_grid, event, mesh_periods (the orbit's period: 1 or 2 mesh
        periods), branch (0 this one, 1… the doubled ones), change_over_mesh_period; and
        window_drift where a point ran by time (sweep_point.window_drift; NaN for orbits)."""
        import pandas as pd

        tables = [self.rows(0)] + [b.rows(n + 1) for n, b in enumerate(self.doubled)]
        return pd.DataFrame([row for rows in tables for row in rows])

    def rows(self, branch_number: int) -> list[dict]:
        """table()'s rows of this branch alone."""
        rows = []
        for number, point in enumerate(self.points):
            orbit = point.orbit
            largest = float(np.abs(orbit.multipliers).max()) if orbit else math.nan
            rows.append({
                self.name: point.value, "speed_rpm": point.speed * RPM_PER_RAD_S,
                **point.follows, **point.figures,
                "floquet_max": largest,
                "floquet_exponent_per_s": orbit.largest_exponent if orbit else math.nan,
                "stability": ("time" if orbit is None else
                              "stable" if orbit.stable else "unstable"),
                "method": point.method, "on_grid": point.on_grid,
                "event": ", ".join(point.events), "branch_point": number,
                "mesh_periods": self.mesh_periods, "branch": branch_number,
                "change_over_mesh_period": point.change_over_mesh_period})
        return rows


def crossings(before: np.ndarray, after: np.ndarray) -> tuple[str, ...]:
    """How the multipliers left or entered the unit circle between two points."""
    def counts(values):
        outside = np.abs(values) > 1.0 + UNIT_CIRCLE_BAND
        real = np.abs(values.imag) <= 1e-9 * np.abs(values)
        return ((outside & real & (values.real < 0)).sum(),
                (outside & ~real).sum(), (outside & real & (values.real > 0)).sum())

    flip, torus, _ = (a != b for a, b in zip(counts(before), counts(after)))
    return (("period doubling",) if flip else ()) + (("torus",) if torus else ())


def value_unit(grid: np.ndarray) -> float:
    """W: the median spacing of the requested values (sorted); for one value a hundredth of
    it (1e-2 where it is 0)."""
    if len(grid) > 1:
        return float(np.median(np.diff(grid)))
    return 0.01 * abs(float(grid[0])) or 0.01


def continued_problem(scene, name: str) -> str | None:
    """Why `name` cannot be continued on this scene, or None: a parameter of the scene that
    varies continuously (not a tooth count), or M_motor or M_load."""
    if name in INPUTS:
        return None
    if name not in scene.parameters:
        return (f"{name} is not a parameter of scene {scene.name}; allowed: "
                f"{', '.join(sorted(scene.parameters))}, M_motor, M_load")
    kind = PARAMETERS[name].kind
    if kind is not float:
        return (f"{name} takes {'whole numbers' if kind is int else 'true or false'}; "
                "continuation follows a quantity that varies continuously (a parameter in a "
                "unit, M_motor, M_load)")
    return None


class SpeedAxis:
    """The pinion speed continued (rad/s): one map serves every speed."""

    name = SPEED

    def __init__(self, scene, tolerance: float, mesh_periods: int = 1):
        self.scene, self.tolerance, self.mesh_periods = scene, tolerance, mesh_periods
        self.period_map = PeriodMap(scene, tolerance, mesh_periods)

    def doubled(self) -> SpeedAxis:
        """The same axis for orbits of twice the period (the same unknown scales: one
        scene)."""
        return SpeedAxis(self.scene, self.tolerance, 2 * self.mesh_periods)

    def map_at(self, value: float) -> PeriodMap:
        """The period map at a speed: the one map."""
        return self.period_map

    def speed_at(self, value: float) -> float:
        """The pinion speed at a value: the value."""
        return value

    def difference_step(self, value: float) -> float:
        """h of the forward difference ∂G/∂ω (rad/s)."""
        return DIFFERENCE_STEP * value

    def scene_at(self, value: float):
        """The scene at a speed (for a time-integration point)."""
        return self.scene.with_parameters(w0_pinion=value)

    def follows(self, value: float) -> dict:
        """No column follows the speed."""
        return {}

    @property
    def evaluations(self) -> int:
        """Period integrations so far."""
        return self.period_map.evaluations


class ParameterAxis:
    """A scene parameter or input torque continued at a fixed pinion speed (rad/s). Each value
    has its own PeriodMap, built on first use (20-50 ms on the reference scene: the compiled
    integrator's tables) and kept for the last MAPS_KEPT values; every one takes the first
    requested value's unknown scales (z is the same state at every value) and integration
    method (a switch of method along the branch would move the map by its tolerance). A
    torque moves the other with it (steady_state.balanced_torques)."""

    def __init__(self, scene, name: str, speed: float, tolerance: float, unit: float,
                 first_value: float, mesh_periods: int = 1, like: ParameterAxis | None = None):
        """mesh_periods: the orbits' period in mesh periods; like: an axis whose unknown
        scales and integration method this one takes (None: its first value's map's)."""
        self.scene = scene.with_parameters(w0_pinion=speed)
        self.name, self.speed, self.tolerance, self.unit = name, speed, tolerance, unit
        self.first_value, self.mesh_periods = first_value, mesh_periods
        scales: np.ndarray | None = None if like is None else like.scales
        method: str = "auto" if like is None else like.method
        first = PeriodMap(self.scene_at(first_value), tolerance, mesh_periods, scales, method)
        self.scales: np.ndarray = first.scales
        self.method: str = first.stepper.method
        # value -> map, least recently used first
        self.maps: dict[float, PeriodMap] = {first_value: first}
        self.retired = 0  # period integrations of maps no longer kept

    def doubled(self) -> ParameterAxis:
        """The same axis for orbits of twice the period, with this one's scales and method
        (z the same state on both)."""
        return ParameterAxis(self.scene, self.name, self.speed, self.tolerance, self.unit,
                             self.first_value, 2 * self.mesh_periods, like=self)

    def scene_at(self, value: float):
        """The scene at the value (SceneError where it is out of the parameter's range)."""
        if self.name in INPUTS:
            return self.scene.with_inputs(**balanced_torques(self.scene, self.name, value))
        return self.scene.with_parameters(**{self.name: value})

    def map_at(self, value: float) -> PeriodMap:
        """The period map at a value: kept, or built (and the least recently used dropped)."""
        period_map = self.maps.pop(value, None)
        if period_map is None:
            period_map = PeriodMap(self.scene_at(value), self.tolerance, self.mesh_periods,
                                   self.scales, self.method)
            if len(self.maps) == MAPS_KEPT:
                self.retired += self.maps.pop(next(iter(self.maps))).evaluations
        self.maps[value] = period_map
        return period_map

    def speed_at(self, value: float) -> float:
        """The pinion speed at a value: the branch's fixed speed."""
        return self.speed

    def difference_step(self, value: float) -> float:
        """h of the forward difference ∂G/∂p, in p's unit: DIFFERENCE_STEP of |p| or of the
        requested spacing, the larger (a parameter may be 0: a lead error); backwards where p
        + h is beyond the parameter's range (a value at its bound)."""
        step = DIFFERENCE_STEP * max(abs(value), self.unit)
        allowed = PARAMETERS[self.name].allowed if self.name in PARAMETERS else None
        return -step if allowed is not None and not allowed.contains(value + step) else step

    def follows(self, value: float) -> dict:
        """The other torque's column where a torque is continued."""
        if self.name not in INPUTS:
            return {}
        other = "M_load" if self.name == "M_motor" else "M_motor"
        return {f"{other}_Nm": balanced_torques(self.scene, self.name, value)[other]}

    @property
    def evaluations(self) -> int:
        """Period integrations so far, over every map built."""
        return self.retired + sum(m.evaluations for m in self.maps.values())


class Continuation:
    """The continuation's state: the last point (scaled unknowns v, Jacobian, tangent), the
    step, and the branch so far (module docstring), along a SpeedAxis or ParameterAxis."""

    def __init__(self, axis, grid, newton_tolerance=NEWTON_TOLERANCE, protocol=None):
        from .sweep_point import Protocol

        self.axis = axis
        self.grid = np.sort(np.asarray(grid, dtype=float))
        self.size = len(axis.map_at(self.grid[0]).unknown_entries)
        self.unit = value_unit(self.grid)
        self.newton_tolerance = newton_tolerance
        self.protocol = protocol or Protocol()
        self.points: list[BranchPoint] = []
        self.distances: list[float] = []
        self.folds: list[float] = []
        # the last point whose t_p says which way the branch goes in p (see STRAIGHT_ACROSS)
        self.heading: BranchPoint | None = None
        self.v = self.jacobian = self.tangent = None
        self.previous_v = None  # the point before the last, where that was a shooting point
        self.step = 1.0
        # the longest next natural step, |Δp| in W, the last step's change of the figures
        # allows (advance, take)
        self.reach = math.inf

    # --- v <-> (z, p) ---------------------------------------------------------------------

    def split(self, v):
        """(z, p) of the scaled unknowns v; p within rounding (1e-12 W) of a requested value
        is that value, exactly as requested (the table's rows, the maps kept by value)."""
        value = float(v[self.size] * self.unit)
        nearest = float(self.grid[np.abs(self.grid - value).argmin()])
        if abs(nearest - value) <= 1e-12 * abs(self.unit):
            value = nearest
        return v[:self.size] * AMPLITUDE_UNIT, value

    def map_residual(self, z, value):
        """steady_state's residual tuple (G, end state, φp offset) at (z, p)."""
        return self.axis.map_at(value).residual(z, self.axis.speed_at(value))

    def residual(self, v):
        """G(v) (fraction of the static mesh force) and steady_state's base tuple."""
        base = self.map_residual(*self.split(v))
        return base[0], base

    def full_jacobian(self, v, base):
        """[∂G/∂z·Z, ∂G/∂p·W] afresh, and the fixed-time images and phase row."""
        z, value = self.split(v)
        images, phase_row = self.axis.map_at(value).jacobian(
            z, self.axis.speed_at(value), base)
        step = self.axis.difference_step(value)
        value_column = (self.map_residual(z, value + step)[0] - base[0]) / step
        jacobian = np.hstack([(images - np.eye(self.size)) * AMPLITUDE_UNIT,
                              value_column[:, None] * self.unit])
        return jacobian, images, phase_row

    def new_tangent(self, jacobian, previous):
        """The null vector of the Jacobian, unit length, oriented along `previous`."""
        bordered = np.vstack([jacobian, previous / np.linalg.norm(previous)])
        right = np.zeros(self.size + 1)
        right[-1] = 1.0
        tangent = np.linalg.solve(bordered, right)
        return tangent / np.linalg.norm(tangent)

    def correct(self, predicted, constraint):
        """Newton on G(v) = 0, constraint·(v − predicted) = 0: the Jacobian afresh at the
        predictor, then chord iterations with Broyden updates; where one reduces |G| by less
        than half, the Jacobian afresh there (at most REFRESHES times). Returns (v, base,
        iterations, (v, Jacobian, images, phase row) where the Jacobian was last taken) or
        None."""
        v = predicted.copy()
        try:
            r, base = self.residual(v)
            fresh = (v.copy(), *self.full_jacobian(v, base))
            matrix, refreshes = fresh[1].copy(), 0
            for iteration in range(1, CORRECTOR_ITERATIONS + 1):
                bordered = np.vstack([matrix, constraint])
                change = np.linalg.solve(bordered, np.append(-r, constraint @ (predicted - v)))
                v = v + change
                new_r, base = self.residual(v)
                if not np.all(np.isfinite(new_r)):
                    return None
                if np.abs(new_r).max() <= self.newton_tolerance:
                    return v, base, iteration, fresh
                if np.abs(new_r).max() > np.abs(r).max() and refreshes == REFRESHES:
                    return None  # diverging with a fresh Jacobian
                if np.abs(new_r).max() > 0.5 * np.abs(r).max() and refreshes < REFRESHES:
                    refreshes += 1
                    fresh = (v.copy(), *self.full_jacobian(v, base))
                    matrix = fresh[1].copy()
                else:
                    matrix += np.outer(new_r - r - matrix @ change, change) / (change @ change)
                r = new_r
        except STEP_FAILURES:
            return None
        return None

    def figures_at(self, v) -> dict:
        """The sweep figures of the orbit at the scaled unknowns v (PeriodMap.figures)."""
        z, value = self.split(v)
        period_map, speed = self.axis.map_at(value), self.axis.speed_at(value)
        return period_map.figures(period_map.state(z, speed), speed)

    def figure_change(self, figures: dict) -> float:
        """How far `figures` moved from the last point's, in units of FIGURE_CHANGE: the
        larger of |ΔK_v| (K_v a share of each point's static mesh force) and the change of
        dte_p2p/|dte_mean| (a share of each point's static deflection: a torque scales both
        alike); over 1, the step is too long for the pictures."""
        last = self.points[-1].figures
        change = abs(figures["K_v"] - last["K_v"])
        if figures["dte_mean_um"] != 0.0 and last["dte_mean_um"] != 0.0:
            change = max(change, abs(figures["dte_p2p_um"] / abs(figures["dte_mean_um"])
                                     - last["dte_p2p_um"] / abs(last["dte_mean_um"])))
        return change / FIGURE_CHANGE

    def accept(self, v, base, iterations, fresh, on_grid, previous_tangent, figures=None):
        """Take a solved point: its tangent, multipliers, events, figures (`figures`, where
        already taken at v). The Jacobian the corrector took serves where it was taken within
        REUSE_DISTANCE of the solution and no point of the orbit lost contact (the map is then
        affine in z to rounding, bar the pinion angle's weak say in the stiffness); else it is
        taken afresh here."""
        z, value = self.split(v)
        period_map, speed = self.axis.map_at(value), self.axis.speed_at(value)
        figures = self.figures_at(v) if figures is None else figures
        where, jacobian, images, phase_row = fresh
        self.distances.append(float(np.abs(v - where).max() * AMPLITUDE_UNIT))
        if (np.abs(v - where).max() * AMPLITUDE_UNIT > REUSE_DISTANCE
                or figures["contact_lost_share"] > 0.0):
            jacobian, images, phase_row = self.full_jacobian(v, base)
        self.jacobian = jacobian
        self.tangent = self.new_tangent(jacobian, previous_tangent)
        orbit = orbit_record(period_map, z, speed, float(np.abs(base[0]).max()),
                             iterations, True, images, phase_row, figures=False)
        events: tuple[str, ...] = ()
        last = self.points[-1] if self.points else None
        t1, heading = float(self.tangent[-1]), self.heading
        if last is not None and last.orbit is not None:
            if (heading is not None and abs(t1) >= STRAIGHT_ACROSS
                    and np.sign(heading.tangent_value) != np.sign(t1)):
                t0 = heading.tangent_value
                self.folds.append(heading.value + (value - heading.value) * t0 / (t0 - t1))
                events += ("fold",)
            events += crossings(last.orbit.multipliers, orbit.multipliers)
        self.previous_v, self.v = self.v, v
        self.points.append(BranchPoint(value, speed, orbit, "shooting", on_grid, events,
                                       figures, float(self.tangent[-1]),
                                       self.axis.follows(value)))
        if abs(t1) >= STRAIGHT_ACROSS:
            self.heading = self.points[-1]

    def start_at(self, value, unknowns=None) -> bool:
        """Newton at a fixed value from `unknowns` (z; None: the static deflection there); on
        success the branch goes on from there, heading up in the continued quantity."""
        try:
            period_map = self.axis.map_at(value)
            if unknowns is None:
                unknowns = period_map.static_unknowns()
            z, norm, taken, converged, (_, _, base) = newton(
                period_map, unknowns, self.axis.speed_at(value), self.newton_tolerance)
            if converged:
                v = np.append(z / AMPLITUDE_UNIT, value / self.unit)
                fresh = (v, *self.full_jacobian(v, base))
        except STEP_FAILURES:
            return False
        if not converged:
            return False
        upward = np.zeros(self.size + 1)
        upward[-1] = 1.0
        self.reach = math.inf  # no step before it to say how fast the figures change
        self.accept(v, base, taken, fresh, True, upward)
        if len(self.points) > 1:
            # no continuity with the points before: where an orbit came before, the branch
            # was lost between the two, and says so ("restart": no line drawn across)
            lost = any(point.method == "shooting" for point in self.points[:-1])
            self.points[-1].events = ("restart",) if lost else ()
        return True

    def by_time(self, value):
        """A requested value that shooting could not reach: sweep_point's time protocol.
        Returns the time run's end position."""
        from .sweep_point import run_window_from, static_mesh_force, window_drift, window_figures

        at = self.axis.scene_at(value)
        window, end = run_window_from(at, self.protocol)
        force = static_mesh_force(at)
        # how far from a steady state its figures are (the summary names a point over 1 %)
        figures = {**window_figures(window, force),
                   "window_drift": window_drift(window, self.protocol, force)}
        self.points.append(BranchPoint(value, self.axis.speed_at(value), None, "time", True,
                                       (), figures, follows=self.axis.follows(value)))
        return end

    def begin_at(self, value, unknowns=None) -> bool:
        """start_at `value` from `unknowns` (None: the static deflection); where Newton fails
        there, the time protocol's point, and Newton again from where that run next reaches
        the section (its transient settled, it is near an orbit: contact lost far from the
        static state, say); where that converges, the orbit replaces the time point."""
        if self.start_at(value, unknowns):
            return True
        end = self.by_time(value)
        try:
            settled = self.axis.map_at(value).section_unknowns(end, self.axis.speed_at(value))
        except STEP_FAILURES:
            return False
        if settled is None or not self.start_at(value, settled):
            return False
        del self.points[-2]  # the time point, now an orbit
        return True

    def target(self):
        """The next requested value in the branch's direction, or None."""
        value = self.v[-1] * self.unit
        slack = 1e-9 * self.unit
        ahead = (self.grid[self.grid > value + slack] if self.tangent[-1] > 0
                 else self.grid[self.grid < value - slack][::-1])
        return float(ahead[0]) if len(ahead) else None

    def near_fold(self) -> bool:
        """A real multiplier of the last orbit within FOLD_PROXIMITY of +1: ∂G/∂z is nearly
        singular, and a step at a fixed value may find no solution (or jump across a fold)."""
        orbit = self.points[-1].orbit
        if orbit is None:
            return True
        values = orbit.multipliers
        real = np.abs(values.imag) <= 1e-9 * np.abs(values)
        return bool(np.any(real & (np.abs(values - 1.0) < FOLD_PROXIMITY)))

    def along_axis(self, value):
        """The predictor at a (scaled) value: z quadratic in p through the last two points
        with the last one's slope t_z/t_p, where the last step was at a fixed value (the
        branch a graph over p there); else the tangent's line."""
        slope = self.tangent[:-1] / self.tangent[-1]
        change = value - self.v[-1]
        z = self.v[:-1] + slope * change
        if self.previous_v is not None and self.points[-1].on_grid:
            back = self.previous_v[-1] - self.v[-1]
            if back != 0.0:
                curvature = (self.previous_v[:-1] - self.v[:-1] - slope * back) / back ** 2
                z = z + curvature * change ** 2
        return np.append(z, value)

    def predictor(self, natural: bool, goal):
        """(predicted v, constraint row) of a step: at the fixed scaled value `goal` where
        natural, else along the tangent by self.step, stopping short of `goal` (the next
        requested value), not past it."""
        if natural:
            constraint = np.zeros(self.size + 1)
            constraint[-1] = 1.0
            return self.along_axis(goal), constraint
        step = self.step
        if goal is not None:
            landing = (goal - self.v[-1]) / self.tangent[-1]
            if 0.0 < landing:
                step = min(step, 0.9 * landing)
        return self.v + step * self.tangent, self.tangent

    def solve_step(self, natural: bool, goal):
        """A step's corrector from its predictor: (solved tuple or None, figures or None,
        `moved`: their change in units of FIGURE_CHANGE, the step's |Δp| in W and its
        length ‖Δv‖). None where it failed or went far (more than CORRECTION_FRACTION of
        the step: it may have landed on another branch)."""
        predicted, constraint = self.predictor(natural, goal)
        distance = float(np.linalg.norm(predicted - self.v))
        solved = self.correct(predicted, constraint)
        if solved is None or (np.linalg.norm(solved[0] - predicted)
                              > CORRECTION_FRACTION * distance):
            return None, None, (0.0, 0.0, distance)
        figures = self.figures_at(solved[0])
        return solved, figures, (self.figure_change(figures),
                                 abs(float(solved[0][-1] - self.v[-1])), distance)

    def advance(self) -> bool:
        """One step along the branch. Away from folds, at a fixed value: to the next requested
        value (no further than `reach`), or where that fails to halfway there (an
        intermediate point), down to 1/2^NATURAL_HALVINGS of the way; near a fold or past
        that, a pseudo-arclength step (halved until the corrector converges). A step over
        which the figures change by more than FIGURE_CHANGE is taken again shorter, in
        proportion, until it moves p by at most FINEST_FIGURE_STEP: a step that hardly moves
        p is drawn as the nearly upright line it is (the period-2 branch leaving its
        doubling at one speed, where the map is affine). False where it cannot go on with
        steps down to SMALLEST_STEP."""
        target = self.target()
        natural = target is not None and not self.near_fold()
        goal = None if target is None else target / self.unit
        on_target = goal is not None and abs(goal - self.v[-1]) <= self.reach
        if natural and not on_target:
            goal = self.v[-1] + math.copysign(self.reach, goal - self.v[-1])
        halvings = 0
        while self.step >= SMALLEST_STEP:
            solved, figures, moved = self.solve_step(natural, goal)
            change, across, distance = moved
            if solved is not None and change > 1.0 and across > FINEST_FIGURE_STEP:
                shorter = max(0.1, 0.8 / change)  # to within the bound, were it linear
                if natural:
                    goal, on_target = self.v[-1] + shorter * (goal - self.v[-1]), False
                else:
                    self.step = shorter * min(self.step, distance)
                continue
            if solved is None:
                if natural and halvings < NATURAL_HALVINGS:
                    halvings += 1
                    goal, on_target = 0.5 * (goal + self.v[-1]), False
                elif natural:
                    natural = False
                    self.step = min(self.step, abs(goal - self.v[-1]))
                else:
                    self.step *= 0.5
                continue
            self.take(solved, figures, natural and on_target, natural, moved)
            return True
        return False

    def take(self, solved, figures, on_grid: bool, natural: bool, moved) -> None:
        """Accept an advance's step and set the next one (`moved`: solve_step's). The step
        grows by 1.5 after a corrector of at most 2 iterations, shrinks by 0.6 after one of
        5 or more, within [SMALLEST_STEP, LARGEST_STEP]; where the figures changed, the next
        step is kept to what that change allows at the rate of this one (0.9/change of it):
        `reach` in p, for a natural step, and, where this step moved p by more than
        FINEST_FIGURE_STEP, the step in v."""
        v, base, iterations, fresh = solved
        change, across, distance = moved
        # a step at a fixed value keeps the direction in p (no fold near): its two ends'
        # tangents may be far from parallel in z over a long step
        heading = self.tangent
        if natural:
            heading = np.zeros(self.size + 1)
            heading[-1] = np.sign(self.tangent[-1])
        self.accept(v, base, iterations, fresh, on_grid, heading, figures)
        # never below SMALLEST_STEP after a success: the next advance would not try
        self.step = min(max(self.step * (1.5 if iterations <= 2 else
                                         0.6 if iterations >= 5 else 1.0), SMALLEST_STEP),
                        LARGEST_STEP)
        self.reach = math.inf
        if change > 0.0:
            self.reach = max(across * 0.9 / change, FINEST_FIGURE_STEP)
            if across > FINEST_FIGURE_STEP:
                self.step = max(min(self.step, distance * 0.9 / change), SMALLEST_STEP)


def branch_status(run: Continuation) -> str:
    """How far the branch has got, for the progress bar: the continued quantity at its last
    point and the points so far ("w0_pinion 17.3 rad/s, 120 points"). Between two requested
    values it may take hundreds of points (467 between 10 and 30 rad/s on the reference
    scene), which the bar's count of requested values does not show."""
    name, points = run.axis.name, len(run.points)
    return (f"{name} {with_unit(f'{run.points[-1].value:.4g}', unit_of(name))}, "
            f"{points} point{'' if points == 1 else 's'}")


def follow(run: Continuation, progress: bool = False, doubling: bool = True) -> Branch:
    """The branch from the first requested value at which an orbit converges (Continuation.
    begin_at; the ones before it run by time integration) up past the last, through folds;
    where the continuation cannot go on, or turns back at a fold and leaves the range below,
    the requested values past its furthest point are run by time integration until shooting
    starts again at one of them (from the last orbit, or the time run's state). doubling:
    switch to the period-2 branch at each period doubling it flags and follow that too
    (follow_doublings)."""
    grid, slack = run.grid, 1e-9 * run.unit
    most = max(MOST_POINTS, MOST_POINTS_PER_SPEED * len(grid))
    with progress_bar(len(grid), f"continuation in {run.axis.name}", progress,
                      unit="value") as bar:
        status = Status(bar)

        def moved():
            bar.update(int(np.searchsorted(grid, run.points[-1].value + slack,
                                           side="right")) - bar.n)
            status.show(branch_status(run))

        index = 0
        while index < len(grid) and not run.begin_at(grid[index]):
            index += 1
        while run.v is not None and len(run.points) < most:
            moved()
            if run.tangent[-1] > 0 and run.points[-1].value >= grid[-1] - slack:
                break
            # turned back at a fold and out of the range below its first value, the branch
            # leaves the values past its furthest point to a new start, as a lost one does
            left_below = run.tangent[-1] < 0 and run.target() is None
            if not left_below and run.advance():
                continue
            ahead = grid[grid > max(p.value for p in run.points) + slack]
            z = run.split(run.v)[0]
            run.v = run.previous_v = None
            for value in ahead:
                run.step = 1.0
                if run.begin_at(value, z):
                    break
        moved()
    branch = Branch(run.points, run.folds, run.axis.evaluations, run.axis.name)
    if doubling:
        follow_doublings(run, branch)
        branch.evaluations = run.axis.evaluations + sum(b.evaluations for b in branch.doubled)
    return branch


def doubling_excess(multipliers: np.ndarray) -> float:
    """max |λ| − 1 over the multipliers in the left half-plane: crosses 0 where a real
    multiplier passes −1 (continuous through a complex pair meeting on the negative axis)."""
    negative = multipliers[multipliers.real < 0.0]
    return float(np.abs(negative).max()) - 1.0 if len(negative) else -1.0


def period_one_orbit(run: Continuation, value: float, unknowns: np.ndarray):
    """Newton at a fixed value from `unknowns`: (z, Poincaré Jacobian) or None."""
    period_map, speed = run.axis.map_at(value), run.axis.speed_at(value)
    try:
        z, _, _, converged, (images, phase_row, _) = newton(period_map, unknowns, speed,
                                                             run.newton_tolerance)
    except STEP_FAILURES:
        return None
    if not converged:
        return None
    return z, period_map.poincare(images, phase_row, period_map.state(z, speed))


def locate_doubling(run: Continuation, before: BranchPoint, after: BranchPoint):
    """Where a real multiplier passes −1 between two shooting points of the branch: the
    Illinois variant of regula falsi on doubling_excess in the continued value (each
    estimate an orbit by Newton from the state interpolated between the two), until
    |excess| <= DOUBLING_TOLERANCE. Returns (value, z, the eigenvector of the multiplier
    nearest −1 in scaled unknowns, unit length) or None where an orbit fails."""
    orbits = [p.orbit for p in (before, after) if p.orbit is not None]
    if len(orbits) != 2:
        return None
    ends = [(p.value, doubling_excess(orbit.multipliers))
            for p, orbit in zip((before, after), orbits)]
    if np.sign(ends[0][1]) == np.sign(ends[1][1]):
        return None  # no real multiplier passed −1 (a real one outside turned complex, say)
    states = [run.axis.map_at(p.value).unknowns(orbit.state)
              for p, orbit in zip((before, after), orbits)]
    found = None
    for _ in range(LOCATE_ITERATIONS):
        (a, fa), (b, fb) = ends
        value = b - fb * (b - a) / (fb - fa)
        share = (value - before.value) / (after.value - before.value)
        found = period_one_orbit(run, value, (1 - share) * states[0] + share * states[1])
        if found is None:
            return None
        excess = doubling_excess(np.linalg.eigvals(found[1]))
        if abs(excess) <= DOUBLING_TOLERANCE:
            break
        if np.sign(excess) == np.sign(fb):  # the far end stays: halve its weight (Illinois)
            ends = [(a, 0.5 * fa), (value, excess)]
        else:
            ends = [(b, fb), (value, excess)]
    if found is None:
        return None
    values, vectors = np.linalg.eig(found[1])
    direction = vectors[:, np.abs(values + 1.0).argmin()].real
    return value, found[0], direction / np.linalg.norm(direction)


def switch_to_doubled(run: Continuation, value: float, z: np.ndarray,
                      direction: np.ndarray) -> Continuation | None:
    """A continuation of period-2 orbits started at a period doubling (value, z on the
    period-1 branch): the predictor z + SWITCH_STEP·direction (the −1 multiplier's
    eigenvector; −direction gives the same orbit shifted by one mesh period), corrected by
    Newton on the map over 2T with the step along `direction` held (pseudo-arclength: the
    value is free, the new branch may leave the bifurcation at a fixed value). None where the
    corrector fails or lands on the period-1 orbit."""
    doubled = Continuation(run.axis.doubled(), run.grid, run.newton_tolerance, run.protocol)
    tangent = np.append(direction, 0.0)
    origin = np.append(z / AMPLITUDE_UNIT, value / doubled.unit)
    solved = doubled.correct(origin + SWITCH_STEP * tangent, tangent)
    if solved is None:
        return None
    v, base, iterations, fresh = solved
    doubled.accept(v, base, iterations, fresh, False, tangent)
    doubled.points[-1].tangent_value = math.nan
    measure_change(run, doubled.points[-1])
    if not doubled.points[-1].change_over_mesh_period > 1e-3 * SWITCH_STEP:
        return None  # back on the period-1 orbit
    return doubled


def measure_change(run: Continuation, point: BranchPoint) -> float:
    """max |z(T) − z| of a doubled branch's orbit over one mesh period, by the period-1
    map of `run` (the same unknown scales), stored on the point; inf where it fails."""
    period_map = run.axis.map_at(point.value)
    if point.orbit is None:
        return math.nan
    try:
        change = period_map.residual(period_map.unknowns(point.orbit.state), point.speed)[0]
        point.change_over_mesh_period = float(np.abs(change).max())
    except STEP_FAILURES:
        point.change_over_mesh_period = math.inf
    return point.change_over_mesh_period


def trace_doubled(run: Continuation, doubled: Continuation) -> float | None:
    """Follow a period-2 branch from its first point until it leaves the requested range,
    cannot go on, or comes back to the period-1 branch (its change over one mesh period below
    REJOIN_FRACTION of its first point's): the value where it came back, or None."""
    grid, slack = doubled.grid, 1e-9 * doubled.unit
    first = doubled.points[0].change_over_mesh_period
    most = max(MOST_POINTS, MOST_POINTS_PER_SPEED * len(grid))
    while len(doubled.points) < most:
        value = doubled.points[-1].value
        if doubled.tangent[-1] > 0 and value >= grid[-1] - slack:
            break
        if doubled.tangent[-1] < 0 and value <= grid[0] + slack:
            break
        if not doubled.advance():
            break
        if measure_change(run, doubled.points[-1]) < REJOIN_FRACTION * first:
            return doubled.points[-1].value
    return None


def follow_doublings(run: Continuation, branch: Branch) -> None:
    """At each period doubling the period-1 branch flags (between two shooting points), the
    bifurcation located (locate_doubling), the period-2 branch switched to and followed
    (switch_to_doubled, trace_doubled) with its own folds, period doublings (to period 4:
    flagged, not followed) and tori; a doubling that an earlier period-2 branch came back to
    is not switched at again. Adds them to `branch` (doubled, doublings)."""
    rejoined: list[float] = []
    for before, after in zip(run.points, run.points[1:]):
        if "period doubling" not in after.events or before.orbit is None:
            continue
        located = locate_doubling(run, before, after)
        if located is None:
            continue
        value, z, direction = located
        branch.doublings.append(value)
        if any(abs(value - r) <= run.unit for r in rejoined):
            continue
        doubled = switch_to_doubled(run, value, z, direction)
        if doubled is None:
            continue
        back = trace_doubled(run, doubled)
        if back is not None:
            rejoined.append(back)
        branch.doubled.append(Branch(doubled.points, doubled.folds,
                                     doubled.axis.evaluations, doubled.axis.name,
                                     doubled.axis.mesh_periods))


def continue_in_speed(scene, speeds, tolerance=SHOOTING_TOLERANCE,
                      newton_tolerance=NEWTON_TOLERANCE, protocol=None,
                      progress: bool = False, doubling: bool = True) -> Branch:
    """The branch of period-1 steady states over the requested pinion speeds (rad/s): a point
    at every requested speed the branch passes (several where it folds back over it), and
    between them the points that passing a fold took. Where shooting fails the requested speed
    is run by time integration (sweep_point's `protocol`) and marked method = "time"; shooting
    starts again at the next requested speed from the last orbit found. doubling: at each
    period doubling, the period-2 branch switched to and followed (Branch.doubled)."""
    from ..arguments import check_scene, check_speeds

    check_scene(scene)
    grid = np.sort(check_speeds(speeds))
    axis = SpeedAxis(scene, tolerance)
    return follow(Continuation(axis, grid, newton_tolerance, protocol), progress, doubling)


def continue_in_parameter(scene, name: str, values, pinion_speed: float | None = None,
                          tolerance=SHOOTING_TOLERANCE, newton_tolerance=NEWTON_TOLERANCE,
                          protocol=None, progress: bool = False,
                          doubling: bool = True) -> Branch:
    """The branch of period-1 steady states over the requested values of a scene parameter
    (in its unit) or input torque (N·m) at a fixed pinion speed (rad/s; None: the scene's
    w0_pinion), as continue_in_speed's over speeds: a point at every requested value the
    branch passes, the points that passing a fold took, time integration where shooting
    fails. A torque is the transmitted torque: the other one follows it so that the train
    stays balanced (M_load = u·M_motor), and the table shows it (M_load_Nm or M_motor_Nm).
    Branch.folds are values of the parameter; doubling as continue_in_speed's."""
    from ..arguments import check_scene, check_speeds, check_values

    check_scene(scene)
    problem = continued_problem(scene, name) if name != SPEED else (
        "w0_pinion is the pinion speed; allowed: continue_in_speed")
    if problem:
        raise ValueError(problem)
    grid = np.sort(check_values(values, name))
    if name in INPUTS and not (np.all(grid > 0) or np.all(grid < 0)):
        raise ValueError(f"{name}: values {', '.join(f'{v:g}' for v in grid)} N·m; allowed: "
                         "all > 0 or all < 0 (at 0 there is no static mesh force to measure "
                         "the dynamic factor by)")
    speed = float(check_speeds([scene.parameters[SPEED] if pinion_speed is None
                                else pinion_speed], "pinion_speed")[0])
    for value in grid:  # out of the parameter's range: SceneError here, before any work
        scene.with_parameters(**({} if name in INPUTS else {name: float(value)}))
    axis = ParameterAxis(scene, name, speed, tolerance, value_unit(grid), float(grid[0]))
    return follow(Continuation(axis, grid, newton_tolerance, protocol), progress, doubling)
