"""Periodic steady states by shooting and their continuation in speed (issue 23): agreement
with long time runs on stable branches, periodicity of unstable orbits checked by the
independent scipy reference, Floquet multipliers against the linear mesh's, the jump scene's
folds against up- and down-sweeps by time integration, bad input."""
import numpy as np
import pytest
from helpers import MODELS

import herringbone
from herringbone.analysis.continuation import continue_in_speed
from herringbone.analysis.stability import multipliers as linear_mesh_multipliers
from herringbone.analysis.steady_state import (
    NEWTON_TOLERANCE,
    PeriodMap,
    ShootingError,
    periodic_orbit,
)
from herringbone.analysis.sweep import chained_time_sweep
from herringbone.analysis.sweep_point import Protocol, run_window, static_mesh_force, window_figures
from herringbone.integrate.contract import Position
from herringbone.integrate.stepping import ScipyStepper

# the time runs the orbits are held to: transients decayed to 1e-8, the integrator at 1e-10
SETTLED = Protocol(settle_residual=1e-8, tolerance=1e-10, window_periods=2, floquet=False)


@pytest.fixture(scope="module")
def jump_scene():
    return herringbone.load_scene(MODELS / "jump_resonance.toml")


@pytest.fixture(scope="module")
def jump_branch(jump_scene):
    return continue_in_speed(jump_scene, np.arange(2300.0, 2500.1, 10.0))


@pytest.mark.parametrize("speed", [300.0, 1500.0])
def test_orbit_figures_agree_with_a_settled_time_run(reference_scene, speed):
    """On the reference scene's stable branch, K_v and dte peak-to-peak of the orbit (sampled
    at the time protocol's phases) within 1e-5 relative of a time run settled to 1e-8; every
    other figure within 1e-5 of its scale. Measured: 3e-7 at 157 rad/s, 1e-8 at 1000."""
    orbit = periodic_orbit(reference_scene, speed)
    assert orbit.converged and orbit.stable and orbit.residual <= NEWTON_TOLERANCE
    scene = reference_scene.with_parameters(w0_pinion=speed)
    timed = window_figures(run_window(scene, SETTLED), static_mesh_force(scene))
    for name in ("K_v", "dte_p2p_um"):
        assert orbit.figures[name] == pytest.approx(timed[name], rel=1e-5), name
    force = static_mesh_force(scene)
    for name, value in timed.items():
        scale = 1.0 if name in ("K_v", "K_v_half", "contact_lost_share", "load_share_left") else \
            timed["dte_p2p_um"] if "dte" in name else force
        assert abs(orbit.figures[name] - value) <= 1e-5 * scale, name


def test_unstable_orbit_is_periodic_by_the_reference_integrator(jump_scene, jump_branch):
    """The middle branch of the jump scene is unstable (a real multiplier > 1) and its orbits
    repeat after one mesh period to the Newton tolerance; run through the independent scipy
    reference (its own event rule) one period from the orbit's state comes back to it within
    2e-7 of each unknown's scale (its tolerance is 1e-10 a step, over a period with contact
    losses and regains; measured: 1.2e-8)."""
    unstable = [p.orbit for p in jump_branch.points
                if p.orbit is not None and not p.orbit.stable]
    assert len(unstable) >= 5
    period_map = PeriodMap(jump_scene)
    reference = ScipyStepper(period_map.model, 1e-10)
    for orbit in unstable[::3]:
        assert orbit.residual <= NEWTON_TOLERANCE
        largest = orbit.multipliers[0]
        assert abs(largest.imag) < 1e-9 and largest.real > 1.0
        segment = period_map.start(orbit.state).segment
        end = reference.advance(Position(0.0, orbit.state.copy(), segment), orbit.period,
                                period_map.torques)
        assert end.segment.contact_set.index == 0 and end.segment.contact_set.cycle == 1
        change = period_map.unknowns(end.state) - period_map.unknowns(orbit.state)
        assert np.abs(change).max() <= 2e-7
        assert end.state[period_map.pinion] == pytest.approx(period_map.section_phase,
                                                             abs=1e-9)


@pytest.mark.parametrize("speed", [157.08, 1000.0, 2500.0])
def test_multipliers_agree_with_the_linear_mesh(reference_scene, speed):
    """Where no point loses contact the orbit's multipliers are those of the linear mesh
    (herringbone.analysis.stability), up to the term that analysis leaves out: the load's
    F·∂g/∂φp·δφp, the pinion angle's say in the stiffness. Measured: moduli within 4.3e-4
    (1000 rad/s, a multiplier of 0.25), the largest within 7e-7."""
    orbit = periodic_orbit(reference_scene, speed)
    assert orbit.figures["contact_lost_share"] == 0.0
    linear = linear_mesh_multipliers(reference_scene, speed)
    assert len(linear) == len(orbit.multipliers)
    assert np.abs(np.abs(orbit.multipliers) - np.abs(linear)).max() <= 1e-3
    assert abs(abs(orbit.multipliers[0]) - abs(linear[0])) <= 1e-5
    assert orbit.largest_exponent == pytest.approx(
        np.log(np.abs(linear[0])) / orbit.period, rel=1e-3)


def test_continuation_multipliers_are_those_of_a_fresh_jacobian(reference_scene):
    """The branch reuses the corrector's Jacobian where it was taken near the solution
    (continuation.REUSE_DISTANCE): its multipliers agree with periodic_orbit's at the same
    speed, started from the branch's state, at every point. Measured over 400-1000 rad/s (30
    points, 15 of them on a Jacobian taken 2e-3 to 3e-2 away): the largest within
    3.4e-7, every modulus within 5.1e-5 (the ones that far off are under 1e-3: a Jacobian off
    by the pinion angle's say in the stiffness moves each multiplier by about as much)."""
    branch = continue_in_speed(reference_scene, np.linspace(400.0, 1000.0, 13))
    assert all(p.method == "shooting" for p in branch.points) and not branch.folds
    for point in branch.points:
        fresh = periodic_orbit(reference_scene, point.speed, initial_state=point.orbit.state)
        error = np.abs(np.abs(fresh.multipliers) - np.abs(point.orbit.multipliers))
        assert error.max() <= 1e-4 and error[0] <= 1e-6
        assert fresh.figures["K_v"] == pytest.approx(point.figures["K_v"], rel=1e-7)


def test_jump_scene_sweeps_jump_at_the_folds(jump_scene, jump_branch):
    """Up- and down-sweeps by time integration (each point from the last one's end state)
    land on different branches between the two folds the continuation found, and each leaves
    its branch within one sweep step (10 rad/s) of a fold."""
    assert len(jump_branch.folds) == 2
    low_fold, high_fold = sorted(jump_branch.folds)
    assert 2300.0 < low_fold < high_fold < 2500.0
    speeds = np.arange(2300.0, 2500.1, 10.0)
    settled = Protocol(settle_residual=1e-6, window_periods=10, floquet=False)
    up = chained_time_sweep(jump_scene, speeds, settled)["K_v"].to_numpy()
    down = chained_time_sweep(jump_scene, speeds[::-1], settled)["K_v"].to_numpy()[::-1]
    apart = speeds[np.abs(up - down) > 0.5]  # on different branches
    assert len(apart) >= 5 and np.all(np.diff(apart) == 10.0)
    # the down-sweep holds the upper branch down to apart[0], the up-sweep the lower up to
    # apart[-1]: each then jumps, and the fold that ends its branch is within a step
    assert abs(apart[0] - low_fold) <= 10.0
    assert abs(apart[-1] - high_fold) <= 10.0
    stable_on_branch = [p for p in jump_branch.points if p.on_grid and p.orbit.stable]
    for point in stable_on_branch:  # every settled time point is on a stable orbit there
        i = int(np.flatnonzero(speeds == point.speed)[0])
        assert min(abs(up[i] - point.figures["K_v"]), abs(down[i] - point.figures["K_v"])) \
            < 1e-3


def test_unbalanced_torques_are_refused(reference_scene):
    """A train whose torques do not balance accelerates: no periodic orbit, one message."""
    scene = reference_scene.with_inputs(M_motor=500.0, M_load=1000.0)
    with pytest.raises(ShootingError, match="M_load = 1000 N·m does not balance"):
        periodic_orbit(scene, 500.0)
    with pytest.raises(ValueError, match="pinion_speed"):
        periodic_orbit(reference_scene, -1.0)


def test_a_speed_without_a_converged_orbit_falls_back_to_time_integration(reference_scene,
                                                                          monkeypatch):
    """Where no orbit converges (here: every period integration between 650 and 750 rad/s
    fails) the requested speed is run by the time protocol and marked so; shooting starts
    again at the next one from the last orbit."""
    from herringbone.analysis import steady_state
    from herringbone.integrate.contract import IntegrationError

    flow = steady_state.PeriodMap.flow

    def failing(self, state, speed):
        if 650.0 < speed < 750.0:
            raise IntegrationError("no orbit here")
        return flow(self, state, speed)

    monkeypatch.setattr(steady_state.PeriodMap, "flow", failing)
    short = Protocol(settle_time=0.02, window_periods=4, floquet=False)
    table = continue_in_speed(reference_scene, [600.0, 700.0, 800.0], protocol=short).table()
    on_grid = table[table["on_grid"]]
    assert list(on_grid["w0_pinion"]) == [600.0, 700.0, 800.0]
    assert list(on_grid["method"]) == ["shooting", "time", "shooting"]
    assert list(on_grid["stability"]) == ["stable", "time", "stable"]
    # the time point says how far from a steady state it is, as a sweep by time's do
    assert np.isnan(on_grid["window_drift"].iloc[[0, 2]]).all()
    assert 0.0 <= on_grid["window_drift"].iloc[1] < 1e-2
    timed = window_figures(run_window(reference_scene.with_parameters(w0_pinion=700.0), short),
                           static_mesh_force(reference_scene))
    assert on_grid["K_v"].iloc[1] == timed["K_v"]


def test_orbit_peaks_are_those_of_a_finely_sampled_run(reference_scene):
    """The orbit's K_v and bearing peak at 100 rad/s are those of herringbone.simulate from
    the orbit's state on its section, sampled every 0.1 µs over one period (within 2e-3 of
    the static force): the fastest mode resolved and each contact switch sampled finer
    (sweep_point.figure_refinement, switch_samples). 64 samples a mesh period read K_v
    1.424 where it is 1.520."""
    speed = 100.0
    orbit = periodic_orbit(reference_scene, speed)
    period_map = PeriodMap(reference_scene)
    scene = reference_scene.with_parameters(w0_pinion=speed)
    force = static_mesh_force(scene)
    stepper = period_map.stepper
    times = np.arange(0.0, orbit.period, 1e-7)
    rows = np.empty((len(times), len(period_map.run.outputs)))
    stepper.advance_sampled(period_map.start(orbit.state), orbit.period, period_map.torques,
                            times, rows)
    column = dict(period_map.model.output_layout)
    assert orbit.figures["K_v"] == pytest.approx(rows[:, column["F_mesh"]].max() / force,
                                                 abs=2e-3)
    bearing = np.abs(rows[:, column["F_brg_pinion_left"]]).max()
    assert orbit.figures["F_brg_pinion_left_peak_N"] == pytest.approx(bearing, abs=2e-3 * force)


def test_orbit_figures_sampled_past_the_periods_step_budget_still_come(reference_scene):
    """Where DOP853 integrates, every sample ends a step: the orbit's figures at 800 rad/s
    sampled 16384 times a mesh period take about 16700 steps, twice the period's budget
    (8295), which the samples add to. Finer, they read K_v and a bearing's peak no lower and
    within 1e-4 of the default sampling (measured: 7e-6 and 6e-5)."""
    speed = 800.0
    orbit = periodic_orbit(reference_scene, speed)
    period_map = PeriodMap(reference_scene, method="dop853")
    steps = period_map.stepper.accepted_steps
    figures = period_map.figures(orbit.state, speed, samples_per_period=16384)
    assert period_map.stepper.accepted_steps - steps > 1.5 * period_map.step_budget(orbit.period)
    for name in ("K_v", "F_brg_pinion_left_peak_N"):
        assert 0.0 <= figures[name] / orbit.figures[name] - 1.0 <= 1e-4, name


def test_a_time_point_that_has_not_settled_is_recorded_again(jump_scene, jump_branch):
    """Down the jump scene's upper branch, the first point from the static start and the point
    just past the fold (2340 rad/s, falling to the lower branch) have not settled after the
    least-damped linear mode's settle (5.6 ms: window_drift 0.6 and 0.8 of the static force;
    K_v 2.19 at 2340 rad/s where its only orbit has 1.62). Their windows are recorded again
    from their ends until they repeat, and every point then lies within 1e-3 of K_v of a
    stable orbit at its speed; the settled points keep the mode's settle."""
    from herringbone.analysis.sweep_point import SETTLED_DRIFT, timing

    speeds = [2440.0, 2400.0, 2340.0, 2330.0]
    down = chained_time_sweep(jump_scene, speeds)
    assert (down["window_drift"] < SETTLED_DRIFT).all()
    derived = [timing(jump_scene.with_parameters(w0_pinion=speed), Protocol()).settle
               for speed in speeds]
    assert (down["settle_time_s"] > derived).tolist() == [True, False, True, False]
    for speed, k_v in zip(speeds, down["K_v"]):
        orbits = [p.figures["K_v"] for p in jump_branch.points
                  if p.speed == speed and p.orbit is not None and p.orbit.stable]
        assert min(abs(k_v - orbit) for orbit in orbits) < 1e-3


def test_a_time_point_that_has_not_settled_is_flagged(jump_scene, tmp_path):
    """With its settle given (5.6 ms, the least-damped linear mode's), the first point from
    the static start and the point just past the fold (2340 rad/s, falling to the lower
    branch: K_v 2.19 where its only orbit has 1.62) are transients: their mesh force does not
    repeat over the window (window_drift 0.6 and 0.8 of the static force, a settled point's
    1e-5). They are flagged in the table, named by the summary and drawn open, where they
    were plotted as steady points."""
    from herringbone.analysis.sweep_plots import draw_time_sweeps
    from herringbone.analysis.sweep_point import SETTLED_DRIFT, timing
    from herringbone.analysis.sweep_report import describe

    given = Protocol(settle_time=timing(jump_scene, Protocol()).settle)
    down = chained_time_sweep(jump_scene, [2440.0, 2400.0, 2340.0, 2330.0], given)
    unsettled = down["window_drift"] > SETTLED_DRIFT
    assert unsettled.tolist() == [True, False, True, False]
    assert down["window_drift"].iloc[3] < 1e-4
    said = describe(jump_scene, down, 1.0, time_sweeps={"down": down})
    assert ("not settled at 2 points of the time sweep down (w0_pinion = 2440 rad/s; "
            "w0_pinion = 2340 rad/s)") in said
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots()
    draw_time_sweeps([axes], {"down": down}, [("K_v", None)])
    open_points = [line for line in axes.get_lines() if line.get_markerfacecolor() == "none"]
    assert len(open_points) == 1 and list(open_points[0].get_xdata()) == \
        down["speed_rpm"][unsettled].tolist()
    plt.close(figure)
