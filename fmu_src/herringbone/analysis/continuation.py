"""The branch of periodic steady states over a range of pinion speeds: pseudo-arclength
continuation of the shooting problem of steady_state.py.

The unknowns are v = (z/Z, ω/W): the section's scaled state z (steady_state) in units of
Z = `AMPLITUDE_UNIT` of the static mesh force, and the speed in units of W, the spacing of the
requested speeds, so that a step of length 1 moves the speed by one requested spacing or the
state by Z. From a solved point with tangent t (the null vector of [∂G/∂z·Z, ∂G/∂ω·W]):

- predictor v + s·t; where the branch runs along the speed (|t_ω| >= `ALONG_SPEED`) and the next
  requested speed in its direction is within the step, the step lands on it and the corrector
  holds the speed there (natural continuation: a row at every requested speed); elsewhere —
  near a fold — the corrector holds tᵀ·(v − v_pred) = 0 (pseudo-arclength), which passes folds;
- corrector: chord Newton with the last point's Jacobian, updated by Broyden's rank-one rule, at
  most `CORRECTOR_ITERATIONS` iterations; then the Jacobian afresh at the solution (the Floquet
  multipliers and the next tangent need it);
- step control: the step grows by 1.5 after a corrector of at most 2 iterations, shrinks by 0.6
  after one of 5 or more, halves on failure; below `SMALLEST_STEP` the continuation gives up
  on this stretch: the next requested speed is run by time integration (steady_state's section
  is not needed for that: sweep_point's protocol) and marked so, and shooting starts again at
  the following one from the last orbit.

What is flagged on the point past it: a fold where t_ω changes sign (a multiplier through +1),
a period doubling where a real multiplier passes −1, a torus (Neimark–Sacker) where a complex
pair leaves or enters the unit circle. The period-1 branch is followed through all three; past
a period doubling or torus it is unstable, and the motion a time run shows there is not on it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..integrate.contract import IntegrationError
from ..model.parameters import RPM_PER_RAD_S
from .steady_state import (
    NEWTON_TOLERANCE,
    SHOOTING_TOLERANCE,
    UNIT_CIRCLE_BAND,
    PeriodicOrbit,
    PeriodMap,
    newton,
    orbit_record,
)

AMPLITUDE_UNIT = 1.0  # Z: fraction of the static mesh force that one unit of step moves z
ALONG_SPEED = 0.3  # |t_ω| above which a step may land on a requested speed
CORRECTOR_ITERATIONS = 6
REUSE_DISTANCE = 3e-2  # see SpeedContinuation.accept
FOLD_PROXIMITY = 0.05  # see SpeedContinuation.near_fold
CORRECTION_FRACTION = 0.5  # most correction, as a fraction of the predictor's step
NATURAL_HALVINGS = 5  # see SpeedContinuation.advance
REFRESHES = 1  # fresh Jacobians a corrector may take where the chord contracts slowly
SMALLEST_STEP = 1e-3
LARGEST_STEP = 3.0  # three spacings of the requested speeds
MOST_POINTS = 2000  # the continuation gives up past this many points, and past
MOST_POINTS_PER_SPEED = 8  # this many per requested speed where that is more


@dataclass
class BranchPoint:
    """One point of a branch: its orbit (None for a time-integration point), how it was
    found, and what happened between it and the point before."""

    speed: float  # rad/s
    orbit: PeriodicOrbit | None
    method: str  # "shooting" or "time"
    on_grid: bool  # at one of the requested speeds
    events: tuple[str, ...] = ()  # "fold", "period doubling", "torus"
    figures: dict = field(default_factory=dict)
    tangent_speed: float = math.nan  # t_ω at the point (its sign: the branch's direction)


@dataclass
class Branch:
    """The points in the order of the branch (arclength), and the speeds of its folds."""

    points: list[BranchPoint]
    folds: list[float]
    evaluations: int = 0  # period integrations it took (Jacobians, residuals, figures)

    def table(self):
        """A pandas DataFrame, a row a point in branch order: w0_pinion, the sweep figures,
        floquet_max (|λ|max of the orbit), floquet_exponent_per_s, stability ('stable',
        'unstable' or 'time' where no orbit converged), method, on_grid, event."""
        import pandas as pd

        rows = []
        for number, point in enumerate(self.points):
            orbit = point.orbit
            largest = float(np.abs(orbit.multipliers).max()) if orbit else math.nan
            rows.append({
                "w0_pinion": point.speed, "speed_rpm": point.speed * RPM_PER_RAD_S,
                **point.figures,
                "floquet_max": largest,
                "floquet_exponent_per_s": orbit.largest_exponent if orbit else math.nan,
                "stability": ("time" if orbit is None else
                              "stable" if orbit.stable else "unstable"),
                "method": point.method, "on_grid": point.on_grid,
                "event": ", ".join(point.events), "branch_point": number})
        return pd.DataFrame(rows)


def crossings(before: np.ndarray, after: np.ndarray) -> tuple[str, ...]:
    """How the multipliers left or entered the unit circle between two points."""
    def counts(values):
        outside = np.abs(values) > 1.0 + UNIT_CIRCLE_BAND
        real = np.abs(values.imag) <= 1e-9 * np.abs(values)
        return ((outside & real & (values.real < 0)).sum(),
                (outside & ~real).sum(), (outside & real & (values.real > 0)).sum())

    flip, torus, _ = (a != b for a, b in zip(counts(before), counts(after)))
    return (("period doubling",) if flip else ()) + (("torus",) if torus else ())


class SpeedContinuation:
    """The continuation's state: the last point (scaled unknowns v, Jacobian, tangent), the
    step, and the branch so far (module docstring)."""

    def __init__(self, scene, speeds, tolerance=SHOOTING_TOLERANCE,
                 newton_tolerance=NEWTON_TOLERANCE, protocol=None):
        from .sweep_point import Protocol

        self.scene = scene
        self.grid = np.sort(np.asarray(speeds, dtype=float))
        self.period_map = PeriodMap(scene, tolerance)
        self.size = len(self.period_map.unknown_entries)
        spacing = np.diff(self.grid)
        self.speed_unit = float(np.median(spacing)) if len(spacing) else 0.01 * self.grid[0]
        self.newton_tolerance = newton_tolerance
        self.protocol = protocol or Protocol()
        self.points: list[BranchPoint] = []
        self.distances: list[float] = []
        self.folds: list[float] = []
        self.v = self.jacobian = self.tangent = None
        self.previous_v = None  # the point before the last, where that was a shooting point
        self.step = 1.0

    # --- v <-> (z, ω) ---------------------------------------------------------------------

    def split(self, v):
        """(z, ω) of the scaled unknowns v."""
        return v[:self.size] * AMPLITUDE_UNIT, float(v[self.size] * self.speed_unit)

    def residual(self, v):
        """G(v) (fraction of the static mesh force) and steady_state's base tuple."""
        base = self.period_map.residual(*self.split(v))
        return base[0], base

    def full_jacobian(self, v, base):
        """[∂G/∂z·Z, ∂G/∂ω·W] afresh, and the fixed-time images and phase row."""
        z, speed = self.split(v)
        images, phase_row, speed_column = self.period_map.jacobian(z, speed, base, True)
        jacobian = np.hstack([(images - np.eye(self.size)) * AMPLITUDE_UNIT,
                              speed_column[:, None] * self.speed_unit])
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
        except (IntegrationError, np.linalg.LinAlgError):
            return None
        return None

    def accept(self, v, base, iterations, fresh, on_grid, previous_tangent):
        """Take a solved point: its tangent, multipliers, events, figures. The Jacobian the
        corrector took serves where it was taken within REUSE_DISTANCE of the solution and no
        point of the orbit lost contact (the map is then affine in z to rounding, bar the
        pinion angle's weak say in the stiffness); else it is taken afresh here."""
        z, speed = self.split(v)
        figures = self.period_map.figures(self.period_map.state(z, speed), speed)
        where, jacobian, images, phase_row = fresh
        self.distances.append(float(np.abs(v - where).max() * AMPLITUDE_UNIT))
        if (np.abs(v - where).max() * AMPLITUDE_UNIT > REUSE_DISTANCE
                or figures["contact_lost_share"] > 0.0):
            jacobian, images, phase_row = self.full_jacobian(v, base)
        self.jacobian = jacobian
        self.tangent = self.new_tangent(jacobian, previous_tangent)
        orbit = orbit_record(self.period_map, z, speed, float(np.abs(base[0]).max()),
                             iterations, True, images, phase_row, figures=False)
        events: tuple[str, ...] = ()
        last = self.points[-1] if self.points else None
        if last is not None and last.orbit is not None:
            if np.sign(last.tangent_speed) != np.sign(self.tangent[-1]):
                events += ("fold",)
                t0, t1 = last.tangent_speed, self.tangent[-1]
                self.folds.append(last.speed + (speed - last.speed) * t0 / (t0 - t1))
            events += crossings(last.orbit.multipliers, orbit.multipliers)
        self.previous_v, self.v = self.v, v
        self.points.append(BranchPoint(speed, orbit, "shooting", on_grid, events,
                                       figures, float(self.tangent[-1])))

    def start_at(self, speed, unknowns) -> bool:
        """Newton at a fixed speed from `unknowns` (z); on success the branch goes on from
        there, heading up in speed."""
        try:
            z, norm, taken, converged, (_, _, base) = newton(
                self.period_map, unknowns, speed, self.newton_tolerance)
            if converged:
                v = np.append(z / AMPLITUDE_UNIT, speed / self.speed_unit)
                fresh = (v, *self.full_jacobian(v, base))
        except (IntegrationError, np.linalg.LinAlgError):
            return False
        if not converged:
            return False
        upward = np.zeros(self.size + 1)
        upward[-1] = 1.0
        self.accept(v, base, taken, fresh, True, upward)
        if self.points[-1].events and len(self.points) > 1:
            self.points[-1].events = ()  # no continuity with the point before a gap
        return True

    def by_time(self, speed):
        """A requested speed that shooting could not reach: sweep_point's time protocol."""
        from .sweep_point import run_window, static_mesh_force, window_figures

        at = self.scene.with_parameters(w0_pinion=speed)
        figures = window_figures(run_window(at, self.protocol), static_mesh_force(at))
        self.points.append(BranchPoint(speed, None, "time", True, (), figures))

    def target(self):
        """The next requested speed in the branch's direction, or None."""
        speed = self.v[-1] * self.speed_unit
        slack = 1e-9 * self.speed_unit
        ahead = (self.grid[self.grid > speed + slack] if self.tangent[-1] > 0
                 else self.grid[self.grid < speed - slack][::-1])
        return float(ahead[0]) if len(ahead) else None

    def near_fold(self) -> bool:
        """A real multiplier of the last orbit within FOLD_PROXIMITY of +1: ∂G/∂z is nearly
        singular, and a step at fixed speed may find no solution (or jump across a fold)."""
        orbit = self.points[-1].orbit
        if orbit is None:
            return True
        values = orbit.multipliers
        real = np.abs(values.imag) <= 1e-9 * np.abs(values)
        return bool(np.any(real & (np.abs(values - 1.0) < FOLD_PROXIMITY)))

    def along_speed(self, speed):
        """The predictor at a (scaled) speed: z quadratic in the speed through the last two
        points with the last one's slope t_z/t_ω, where the last step was at fixed speed
        (the branch a graph over the speed there); else the tangent's line."""
        slope = self.tangent[:-1] / self.tangent[-1]
        change = speed - self.v[-1]
        z = self.v[:-1] + slope * change
        if self.previous_v is not None and self.points[-1].on_grid:
            back = self.previous_v[-1] - self.v[-1]
            if back != 0.0:
                curvature = (self.previous_v[:-1] - self.v[:-1] - slope * back) / back ** 2
                z = z + curvature * change ** 2
        return np.append(z, speed)

    def advance(self) -> bool:
        """One step along the branch. Away from folds, at fixed speed: to the next requested
        speed, or where that fails to halfway there (an intermediate point), down to
        1/2^NATURAL_HALVINGS of the way; near a fold or past that, a pseudo-arclength step
        (halved until the corrector converges). False where it cannot go on with steps down
        to SMALLEST_STEP."""
        target = self.target()
        natural = target is not None and not self.near_fold()
        goal = None if target is None else target / self.speed_unit
        halvings = 0
        while self.step >= SMALLEST_STEP:
            if natural:
                constraint = np.zeros(self.size + 1)
                constraint[-1] = 1.0
                predicted = self.along_speed(goal)
            else:
                step, constraint = self.step, self.tangent
                if goal is not None:  # stop short of the next requested speed, not past it
                    landing = (goal - self.v[-1]) / self.tangent[-1]
                    if 0.0 < landing:
                        step = min(step, 0.9 * landing)
                predicted = self.v + step * self.tangent
            solved = self.correct(predicted, constraint)
            if solved is not None and (np.linalg.norm(solved[0] - predicted)
                                       > CORRECTION_FRACTION * np.linalg.norm(predicted - self.v)):
                solved = None  # the corrector went far: it may have landed on another branch
            if solved is None:
                if natural and halvings < NATURAL_HALVINGS:
                    halvings += 1
                    goal = 0.5 * (goal + self.v[-1])
                elif natural:
                    natural = False
                    self.step = min(self.step, abs(goal - self.v[-1]))
                else:
                    self.step *= 0.5
                continue
            # a step at fixed speed keeps the direction in speed (no fold near): its two ends'
            # tangents may be far from parallel in z over a long step
            heading = self.tangent
            if natural:
                heading = np.zeros(self.size + 1)
                heading[-1] = np.sign(self.tangent[-1])
            v, base, iterations, fresh = solved
            self.accept(v, base, iterations, fresh, natural and halvings == 0, heading)
            self.step = min(self.step * (1.5 if iterations <= 2 else
                                         0.6 if iterations >= 5 else 1.0), LARGEST_STEP)
            return True
        return False


def continue_in_speed(scene, speeds, tolerance=SHOOTING_TOLERANCE,
                      newton_tolerance=NEWTON_TOLERANCE, protocol=None,
                      progress: bool = False) -> Branch:
    """The branch of period-1 steady states over the requested pinion speeds (rad/s): a point
    at every requested speed the branch passes (several where it folds back over it), and
    between them the points that passing a fold took. Where shooting fails the requested speed
    is run by time integration (sweep_point's `protocol`) and marked method = "time"; shooting
    starts again at the next requested speed from the last orbit found."""
    from tqdm import tqdm

    from ..arguments import check_scene, check_speeds

    check_scene(scene)
    grid = np.sort(check_speeds(speeds))
    run = SpeedContinuation(scene, grid, tolerance, newton_tolerance, protocol)
    most = max(MOST_POINTS, MOST_POINTS_PER_SPEED * len(grid))
    with tqdm(total=len(grid), unit="speed", desc="continuation", disable=not progress,
              smoothing=0.0) as bar:
        def moved():
            bar.update(int(np.searchsorted(grid, run.points[-1].speed * (1 + 1e-12),
                                           side="right")) - bar.n)

        index = 0
        start = run.period_map.static_unknowns()
        while index < len(grid) and not run.start_at(grid[index], start):
            run.by_time(grid[index])
            index += 1
        while run.v is not None and len(run.points) < most:
            moved()
            if run.tangent[-1] > 0 and run.points[-1].speed >= grid[-1] * (1 - 1e-12):
                break
            if run.tangent[-1] < 0 and run.target() is None:
                break  # the branch left the range below its first speed
            if run.advance():
                continue
            ahead = grid[grid > max(p.speed for p in run.points) * (1 + 1e-12)]
            z = run.split(run.v)[0]
            run.v = run.previous_v = None
            for speed in ahead:
                run.step = 1.0
                if run.start_at(speed, z):
                    break
                run.by_time(speed)
        moved()
    return Branch(run.points, run.folds, run.period_map.evaluations)
