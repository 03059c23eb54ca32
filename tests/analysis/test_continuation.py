"""Continuation of periodic steady states in a scene parameter or a torque at a fixed pinion
speed (issue 23): agreement with settled time runs, the torque that follows, the jump scene's
folds in the mesh damping with the stability between them, and sweep's and the command's
choice of the method."""
import numpy as np
import pandas as pd
import pytest
from helpers import MODELS

import herringbone
from herringbone import cli
from herringbone.analysis.continuation import continue_in_parameter
from herringbone.analysis.steady_state import NEWTON_TOLERANCE, balanced_torques, periodic_orbit
from herringbone.analysis.sweep import sweep
from herringbone.analysis.sweep_point import Protocol, run_window, static_mesh_force, window_figures
from herringbone.model.assembly import GearTrainModel

# the time runs the orbits are held to: transients decayed to 1e-8, the integrator at 1e-10
SETTLED = Protocol(settle_residual=1e-8, tolerance=1e-10, window_periods=2, floquet=False)
SPEED = 500.0  # rad/s, on the reference scene
JUMP_SPEED = 2420.0  # rad/s: between the jump scene's folds in speed (2350, 2428 at zeta 0.05)
DAMPINGS = np.linspace(0.03, 0.07, 9)


@pytest.fixture(scope="module")
def jump_scene():
    return herringbone.load_scene(MODELS / "jump_resonance.toml")


@pytest.fixture(scope="module")
def damping_branch(jump_scene):
    return continue_in_parameter(jump_scene, "zeta_mesh", DAMPINGS, pinion_speed=JUMP_SPEED)


def settled_figures(scene, protocol=SETTLED):
    return window_figures(run_window(scene, protocol), static_mesh_force(scene))


def points_at(branch, value):
    return [p for p in branch.points if p.on_grid and np.isclose(p.value, value, rtol=1e-12)]


@pytest.mark.parametrize("name, values, checked", [
    ("dbeta_right", np.linspace(-1e-4, 1e-4, 5), 1e-4),
    ("zeta_mesh", np.linspace(0.03, 0.08, 5), 0.08),
    ("M_motor", np.linspace(300.0, 700.0, 5), 300.0),
])
def test_parameter_branch_agrees_with_settled_time_runs(reference_scene, name, values,
                                                        checked):
    """On the reference scene at 500 rad/s, a branch in a lead error, the mesh damping or the
    motor torque (the load following, M_load = u·M_motor): a stable orbit at every requested
    value, whose K_v and dte peak-to-peak lie within 1e-5 relative of a time run of the scene
    at that value settled to 1e-8 (measured: 6e-8, 6e-9, 4e-9), and whose multipliers and K_v
    are those of periodic_orbit solved afresh there (the branch's maps share the first value's
    unknown scales)."""
    branch = continue_in_parameter(reference_scene, name, values, pinion_speed=SPEED)
    table = branch.table()
    assert branch.name == name and not branch.folds
    assert list(table[name]) == list(values) and set(table["stability"]) == {"stable"}
    assert np.allclose(table["speed_rpm"], SPEED * 30 / np.pi, rtol=1e-15)
    assert np.all(np.isfinite(table["floquet_max"])) and (table["floquet_max"] < 1).all()
    (point,) = points_at(branch, checked)
    at = reference_scene.with_parameters(w0_pinion=SPEED)
    at = (at.with_inputs(**balanced_torques(at, name, checked)) if name == "M_motor"
          else at.with_parameters(**{name: checked}))
    timed = settled_figures(at)
    for figure in ("K_v", "dte_p2p_um"):
        assert point.figures[figure] == pytest.approx(timed[figure], rel=1e-5), figure
    fresh = periodic_orbit(at, SPEED, initial_state=point.orbit.state)
    assert np.abs(np.abs(fresh.multipliers) - np.abs(point.orbit.multipliers)).max() <= 1e-5
    assert fresh.figures["K_v"] == pytest.approx(point.figures["K_v"], rel=1e-7)


def test_torque_branch_keeps_the_train_balanced(reference_scene):
    """A branch in M_load: the motor torque follows (M_motor = M_load/u, its column), the
    static force with it; a branch in M_motor the same the other way."""
    ratio = GearTrainModel(reference_scene).geometry.ratio
    loads = [1200.0, 1800.0, 2400.0]
    table = continue_in_parameter(reference_scene, "M_load", loads, pinion_speed=SPEED).table()
    assert list(table["M_load"]) == loads
    assert np.allclose(table["M_motor_Nm"], np.array(loads) / ratio, rtol=1e-15)
    assert balanced_torques(reference_scene, "M_motor", 500.0) == pytest.approx(
        {"M_motor": 500.0, "M_load": 500.0 * ratio})


def test_a_time_sweep_of_one_torque_keeps_a_balanced_train_balanced(reference_scene):
    """The time protocol's point of one swept torque: the other follows where the scene's
    torques balance (as the continuation's), and stays where they do not."""
    from herringbone.analysis.sweep import Point, scene_at

    ratio = GearTrainModel(reference_scene).geometry.ratio
    point = Point(0, (("M_motor", 300.0),))
    assert scene_at(reference_scene, point).inputs.at(0.0) == pytest.approx((300.0, 300 * ratio))
    unbalanced = reference_scene.with_inputs(M_motor=500.0, M_load=1000.0)
    assert scene_at(unbalanced, point).inputs.at(0.0) == (300.0, 1000.0)


def test_damping_branch_of_the_jump_scene_passes_two_folds(jump_scene, damping_branch):
    """At 2420 rad/s the jump scene's response is S-shaped in the mesh damping: from the upper
    branch (teeth apart a third of each period) at 0.03 the continuation passes a fold near
    0.053, comes back along the unstable middle branch (a real multiplier > 1) to a fold near
    0.047 and goes on along the lower branch (no contact loss) to 0.07. Three orbits at 0.05,
    every point's multipliers reported; stability changes only at the folds."""
    low, high = sorted(damping_branch.folds)
    assert len(damping_branch.folds) == 2 and 0.045 < low < 0.05 < high < 0.056
    table = damping_branch.table()
    assert set(table["method"]) == {"shooting"}
    assert table["event"].str.contains("fold").sum() == 2
    stability = table["stability"].to_numpy()
    stretches = [kind for i, kind in enumerate(stability) if i == 0 or kind != stability[i - 1]]
    assert stretches == ["stable", "unstable", "stable"]
    assert (table["contact_lost_share"].iloc[0] > 0.3) and table["contact_lost_share"].iloc[-1] == 0
    for point in damping_branch.points:
        assert len(point.orbit.multipliers) == 2 and np.all(np.isfinite(point.orbit.multipliers))
        assert point.orbit.residual <= NEWTON_TOLERANCE
        if not point.orbit.stable:
            largest = point.orbit.multipliers[0]
            assert abs(largest.imag) < 1e-9 and largest.real > 1.0
    assert len(points_at(damping_branch, 0.05)) == 3
    assert [len(points_at(damping_branch, value)) for value in (0.04, 0.06)] == [1, 1]


def test_damping_branch_agrees_with_time_runs_of_the_jump_scene(jump_scene, damping_branch):
    """Where one orbit exists (0.04: the upper branch, contact lost; 0.06: the lower) a time
    run from the static start lands on it: K_v and dte peak-to-peak within 1e-5 relative (a
    settle of 0.1 s, 400 mesh periods; measured 1.7e-9, 1.3e-8); at 0.05, between the folds,
    on one of the two stable orbits there (the lower, 1.4e-8)."""
    long_settle = Protocol(settle_time=0.1, tolerance=1e-10, window_periods=2, floquet=False)
    for value in (0.04, 0.06, 0.05):
        timed = settled_figures(jump_scene.with_parameters(w0_pinion=JUMP_SPEED,
                                                           zeta_mesh=value), long_settle)
        stable = [p for p in points_at(damping_branch, value) if p.orbit.stable]
        distances = [max(abs(p.figures[k] / timed[k] - 1) for k in ("K_v", "dte_p2p_um"))
                     for p in stable]
        assert min(distances) <= 1e-5, value


def test_sweep_of_one_parameter_continues_by_default(jump_scene, tmp_path, capsys):
    """sweep(params={name: values}, speeds=[one]) is a branch (folds in attrs, the continued
    name); at 0.04, where Newton from the static deflection does not converge (contact lost
    on the only orbit), it starts from the time protocol's run there, on the upper branch;
    method="time" runs the time protocol; the command likewise, with --speed."""
    values = [0.04, 0.05, 0.06]
    first = jump_scene.with_parameters(w0_pinion=JUMP_SPEED, zeta_mesh=values[0])
    assert not periodic_orbit(first, JUMP_SPEED).converged
    table = sweep(jump_scene, speeds=[JUMP_SPEED], params={"zeta_mesh": values},
                  progress=False)
    assert table.attrs["continued"] == "zeta_mesh" and len(table.attrs["folds"]) == 2
    assert set(table["stability"]) == {"stable", "unstable"}
    assert set(table["method"]) == {"shooting"} and table["contact_lost_share"].iloc[0] > 0.3
    assert list(table.columns[:4]) == ["zeta_mesh", "speed_rpm", "mesh_frequency_Hz",
                                       "static_mesh_force_N"]
    short = Protocol(settle_time=0.05, window_periods=4, floquet=False)
    timed = sweep(jump_scene, speeds=[JUMP_SPEED], params={"zeta_mesh": values},
                  protocol=short, method="time", workers=0, progress=False)
    assert list(timed["method"]) == ["time"] * 3
    code = cli.main(["sweep", str(MODELS / "jump_resonance.toml"), "--param", "zeta_mesh",
                     "0.04", "0.06", "3", "--speed", str(JUMP_SPEED), "--no-progress", "-o",
                     str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0 and "folds (jumps) in zeta_mesh at 0.05" in out
    written = pd.read_csv(tmp_path / "jump_resonance_sweep_zeta_mesh.csv")
    assert set(written["stability"]) == {"stable", "unstable"}
    assert (tmp_path / "jump_resonance_sweep_zeta_mesh.png").stat().st_size > 10_000


@pytest.mark.parametrize("arguments, culprit", [
    (["--param", "zeta_mesh", "0.03", "0.07", "3", "--speed", "-1"], "--speed -1"),
    (["--speeds", "100", "200", "2", "--speed", "300"], "--speed 300"),
    (["--param", "zeta_mesh", "0.03", "0.07", "3", "--method", "shooting", "--param",
      "dbeta_right", "0", "1e-5", "2"], "two quantities"),
    (["--param", "z_pinion", "9", "11", "3", "--method", "shooting"], "whole numbers"),
    (["--param", "zeta_mesh", "0.03", "0.07", "3", "--time-sweeps"], "--time-sweeps"),
])
def test_bad_parameter_sweeps_get_one_line_and_exit_code_2(arguments, culprit, capsys):
    code = cli.main(["sweep", str(MODELS / "reference.toml"), "--no-progress", *arguments])
    error = capsys.readouterr().err
    assert code == 2
    assert error.startswith("herringbone sweep: ") and error.count("\n") == 1
    assert culprit in error and "allowed" in error


def test_bad_continued_quantities_are_refused_by_name(reference_scene):
    with pytest.raises(ValueError, match="z_wheel takes whole numbers"):
        continue_in_parameter(reference_scene, "z_wheel", [30, 36])
    with pytest.raises(ValueError, match="w0_pinion is the pinion speed.*continue_in_speed"):
        continue_in_parameter(reference_scene, "w0_pinion", [300, 400])
    with pytest.raises(ValueError, match="zeta_mesh"):
        continue_in_parameter(reference_scene, "zeta_mesh", [0.05, -0.01])
    with pytest.raises(ValueError, match="M_load: values 0, 1800 N·m; allowed: all > 0 or all < 0"):
        continue_in_parameter(reference_scene, "M_load", [0.0, 1800.0])
    with pytest.raises(ValueError, match="pinion_speed"):
        continue_in_parameter(reference_scene, "zeta_mesh", [0.05], pinion_speed=0.0)


def test_a_branch_lost_is_begun_again_at_the_next_value_and_flagged_restart(monkeypatch):
    """Where the continuation cannot go on (its first step fails here, forced), the next
    requested speed starts the branch again from the last orbit: that orbit is flagged
    "restart" (no continuity with the one before; the report and the curve say so), and the
    branch goes on from it as usual."""
    from herringbone.analysis import continuation

    advance, calls = continuation.Continuation.advance, []

    def lost_once(self):
        calls.append(self.v[-1])
        return False if len(calls) == 1 else advance(self)

    monkeypatch.setattr(continuation.Continuation, "advance", lost_once)
    scene = herringbone.load_scene(MODELS / "reference.toml")
    branch = continuation.continue_in_speed(scene, [500.0, 600.0, 700.0], doubling=False)
    events = {point.value: point.events for point in branch.points if point.on_grid}
    assert events == {500.0: (), 600.0: ("restart",), 700.0: ()}, events
    assert [point.method for point in branch.points] == ["shooting"] * len(branch.points)


def test_a_branch_that_turns_back_out_of_the_range_leaves_no_speed_behind(jump_scene):
    """From 2420 rad/s the jump scene's lower branch folds at 2427.9 rad/s and its unstable
    middle runs back below 2420, out of the range: the speeds past the fold are begun again,
    the first flagged "restart", on the upper branch that a time run from the static start
    lands on (K_v within 1e-5 at 2500 rad/s), and the summary says where the branch was
    lost. Every requested speed has its orbit; the sweep had stopped at the fold, its K_v
    at most 2.08 where the upper branch reaches 3.19."""
    from herringbone.analysis.sweep_report import describe

    speeds = np.linspace(2420.0, 2520.0, 6)
    table = sweep(jump_scene, speeds=speeds, workers=0, progress=False)
    requested = table[table["on_grid"]]
    assert set(speeds) <= set(requested["w0_pinion"][requested["stability"] == "stable"])
    restart = table[table["event"] == "restart"]
    assert restart["w0_pinion"].tolist() == [2440.0]
    at_2500 = requested[(requested["w0_pinion"] == 2500.0) & (requested["stability"] == "stable")]
    timed = settled_figures(jump_scene.with_parameters(w0_pinion=2500.0),
                            Protocol(settle_time=0.1, tolerance=1e-10, window_periods=2,
                                     floquet=False))
    assert at_2500["K_v"].iloc[0] == pytest.approx(timed["K_v"], rel=1e-5)
    assert table["K_v"][table["stability"] == "stable"].max() > 3.1
    summary = describe(jump_scene, table, 0.0).splitlines()
    assert any(line.startswith("the branch was lost past 2427.9 rad/s: no orbit followed on "
                               "to 2440 rad/s") for line in summary)


def test_a_sharp_fall_of_K_v_gets_points_and_its_jump_is_pinned(reference_scene):
    """`herringbone sweep reference --param beta 0.35 0.6 6 --speed 450`: the branch went
    from 0.3531 (K_v 2.17) to 0.3765 (1.65) in one step, Newton converging easily, over K_v's
    fall to 1.00 at the axial overlap ε_β = 1 (β = asin(π·m_n/b) = 0.36724) and its jump back
    to 1.50; the picture read 1.8 at 0.365 where the orbit has 1.21. Now a step over which K_v
    changes by more than FIGURE_CHANGE (0.05) is taken again shorter: between 0.36 and 0.37
    the points fall below 1.3 (to 1.0008 at 0.36725), the one nearest 0.365 (0.36487, K_v
    1.2142) is where a settled time run lies (within 1e-6 relative; measured 1.3e-9), and
    every step changes K_v by at most 0.05 but the jump, which one step of at most
    FINEST_FIGURE_STEP (1/128 of the 0.05 rad spacing, 3.9e-4 rad) spans, just past ε_β = 1
    (0.36731 → 0.36738)."""
    branch = continue_in_parameter(reference_scene, "beta", [0.35, 0.40], pinion_speed=450.0,
                                   doubling=False)
    values = np.array([p.value for p in branch.points])
    factors = np.array([p.figures["K_v"] for p in branch.points])
    inside = (values > 0.36) & (values < 0.37)
    assert inside.any() and factors[inside].min() < 1.3
    near = int(np.abs(np.where(inside, values, np.inf) - 0.365).argmin())
    assert abs(values[near] - 0.365) < 1e-3 and factors[near] < 1.3
    at = reference_scene.with_parameters(w0_pinion=450.0, beta=values[near])
    assert settled_figures(at)["K_v"] == pytest.approx(factors[near], rel=1e-6)
    from herringbone.analysis.continuation import FIGURE_CHANGE, FINEST_FIGURE_STEP

    steep = np.flatnonzero(np.abs(np.diff(factors)) > FIGURE_CHANGE)
    assert len(steep) == 1 and factors[steep[0]] < 1.01 < 1.5 < factors[steep[0] + 1]
    overlap = np.arcsin(np.pi * reference_scene.parameters["m_n"]
                        / reference_scene.parameters["b_left"])
    assert 0.0 < values[steep[0] + 1] - values[steep[0]] <= FINEST_FIGURE_STEP * 0.05
    assert values[steep[0]] - 1e-4 < overlap < values[steep[0] + 1]
