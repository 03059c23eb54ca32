"""Branch switching at a period doubling (issue 23): the period-2 orbit switched to where a
multiplier of the period-1 orbit passes −1, followed in speed, against a settled time run, on
tests/analysis/period_doubling.toml (the jump scene's gear pair, the mesh damped at
zeta_mesh = 0.02: parametric resonance where the mesh frequency is twice the mode's)."""
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq

import herringbone
from herringbone import cli
from herringbone.analysis import stability
from herringbone.analysis.continuation import (
    SWITCH_STEP,
    continue_in_parameter,
    continue_in_speed,
    doubling_excess,
)
from herringbone.analysis.steady_state import NEWTON_TOLERANCE, PeriodMap, periodic_orbit
from herringbone.analysis.sweep import sweep
from herringbone.analysis.sweep_point import Protocol, run_window, static_mesh_force, window_figures
from herringbone.integrate.contract import Position
from herringbone.integrate.stepping import ScipyStepper

SCENE = Path(__file__).with_name("period_doubling.toml")
SPEEDS = np.linspace(4800.0, 5200.0, 9)
INSIDE = 5000.0  # rad/s: between the doublings (4891, 5122), the period-1 orbit unstable


@pytest.fixture(scope="module")
def scene():
    return herringbone.load_scene(SCENE)


@pytest.fixture(scope="module")
def branch(scene):
    return continue_in_speed(scene, SPEEDS)


def test_each_doubling_is_located_and_its_period_2_branch_starts_there(scene, branch):
    """Two doublings, each between the two points of the period-1 branch that flag it,
    where the period-1 orbit has a multiplier within 1e-5 of −1 (measured 7e-7, 5e-8); the
    period-2 branch from each starts within 1e-2 rad/s of it (measured 1.3e-3, 8e-5) and
    within 1.5·SWITCH_STEP of the period-1 orbit there (in state scales; measured 0.0098 and
    0.0100: the switch's own step), its multipliers the period-1 ones squared within 1e-5
    (the −1 one's square is +1; measured within 2e-7). The linear mesh's Floquet analysis
    (herringbone.analysis.stability: contact geometry prescribed, an independent monodromy)
    has its multiplier at −1 within 0.05 rad/s of each (measured 0.017, 0.013)."""
    flagged = [(before.value, after.value) for before, after
               in zip(branch.points, branch.points[1:]) if "period doubling" in after.events]
    assert len(flagged) == 2 and len(branch.doublings) == 2 and len(branch.doubled) == 2
    period_map = PeriodMap(scene)
    for (low, high), value, doubled in zip(flagged, branch.doublings, branch.doubled):
        assert low < value < high and doubled.mesh_periods == 2
        start = doubled.points[0]
        one = periodic_orbit(scene, value, initial_state=start.orbit.state)
        assert one.converged and np.abs(one.multipliers + 1.0).min() <= 1e-5
        assert abs(start.value - value) <= 1e-2
        distance = np.abs(period_map.unknowns(start.orbit.state)
                          - period_map.unknowns(one.state)).max()
        assert 0.5 * SWITCH_STEP <= distance <= 1.5 * SWITCH_STEP
        assert np.allclose(np.sort_complex(start.orbit.multipliers),
                           np.sort_complex(one.multipliers ** 2), atol=1e-5)
        linear = brentq(lambda w: doubling_excess(stability.multipliers(scene, w)), low, high,
                        xtol=1e-6)
        assert abs(linear - value) <= 0.05


def test_the_period_2_orbit_repeats_over_two_mesh_periods_and_not_over_one(scene, branch):
    """On the branch from the upper doubling at 5000 rad/s: periodic over 2T to the Newton
    tolerance (solved afresh by periodic_orbit(mesh_periods=2) from its state: no iteration
    needed), its state after one mesh period 2.49 state scales (static mesh forces) away
    (bound: > 1), stable (|λ| 0.907 over 2T) where the period-1 orbit is not (−1.034)."""
    upper = branch.doubled[1]
    (point,) = [p for p in upper.points if p.on_grid and p.value == INSIDE]
    assert point.orbit.residual <= NEWTON_TOLERANCE and point.orbit.stable
    assert point.change_over_mesh_period > 1.0
    again = periodic_orbit(scene, INSIDE, initial_state=point.orbit.state, mesh_periods=2)
    assert again.converged and again.iterations == 0
    (one,) = [p for p in branch.points if p.value == INSIDE]
    assert not one.orbit.stable and one.orbit.multipliers.real.min() < -1.0
    assert all(p.orbit.stable for p in upper.points[3:])  # past the contact loss's onset
    lower = branch.doubled[0]
    assert not any(p.orbit.stable for p in lower.points[4:])  # subcritical: unstable
    assert not upper.folds and not lower.folds  # leaving a doubling straight is no fold


def test_the_stable_period_2_orbit_is_where_a_time_run_settles(scene, branch):
    """A time run at 5000 rad/s from the static start, settled 0.1 s (800 mesh periods) at
    integrator tolerance 1e-10 and recorded over two mesh periods: K_v and dte peak-to-peak
    within 1e-5 relative of the period-2 orbit's (measured 6.4e-10 and 1.7e-9); the period-1
    orbit's K_v is half as large (1.44 against 3.14)."""
    (point,) = [p for p in branch.doubled[1].points if p.on_grid and p.value == INSIDE]
    settled = Protocol(settle_time=0.1, tolerance=1e-10, window_periods=2, floquet=False)
    timed = window_figures(run_window(scene, settled), static_mesh_force(scene))
    for figure in ("K_v", "dte_p2p_um"):
        assert timed[figure] == pytest.approx(point.figures[figure], rel=1e-5), figure
    (one,) = [p for p in branch.points if p.value == INSIDE]
    assert one.figures["K_v"] < 0.5 * timed["K_v"]


def test_sweep_table_and_command_carry_the_period_2_branch(scene, tmp_path, capsys):
    """sweep's table: the period-1 rows (mesh_periods 1, branch 0) then each period-2 branch's
    (mesh_periods 2, branch 1 and 2), the doublings in attrs; doubling=False leaves the
    doublings flagged on the period-1 branch only. The command writes the same table and its
    picture, and --no-period-doubling the period-1 rows alone."""
    table = sweep(scene, speeds=SPEEDS, progress=False)
    assert set(table["mesh_periods"]) == {1, 2} and set(table["branch"]) == {0, 1, 2}
    assert (table[table["mesh_periods"] == 1]["branch"] == 0).all()
    assert len(table.attrs["period_doublings"]) == 2
    single = sweep(scene, speeds=SPEEDS, progress=False, doubling=False)
    assert set(single["mesh_periods"]) == {1}
    assert single["event"].str.contains("period doubling").sum() == 2
    assert single["K_v"].tolist() == table[table["branch"] == 0]["K_v"].tolist()
    for extra, periods in (([], {1, 2}), (["--no-period-doubling"], {1})):
        folder = tmp_path / str(len(extra))
        code = cli.main(["sweep", str(SCENE), "--speeds", "4800", "5200", "9", "--no-progress",
                         "-o", str(folder), *extra])
        capsys.readouterr()
        assert code == 0
        written = pd.read_csv(folder / "period_doubling_sweep_w0_pinion.csv")
        assert set(written["mesh_periods"]) == periods
        assert (folder / "period_doubling_sweep_w0_pinion_resonance.png").stat().st_size > 10_000


def test_a_branch_in_a_parameter_switches_to_the_same_period_2_orbit(scene, branch):
    """In the mesh damping at 5000 rad/s (0.02 to 0.04): the period-1 orbit doubles between
    0.03 and 0.035 (located at 0.03053); the period-2 branch leaves it unstable (subcritical),
    folds once (at 0.03103: between the two the period-1 and the period-2 orbit are both
    stable) and comes back stable to zeta_mesh = 0.02, where its orbit is the one the branch
    in speed found at 5000 rad/s: K_v and dte peak-to-peak within 1e-7 relative."""
    dampings = np.linspace(0.02, 0.04, 5)
    in_damping = continue_in_parameter(scene, "zeta_mesh", dampings, pinion_speed=INSIDE)
    (located,) = in_damping.doublings
    assert 0.03 < located < 0.035 and len(in_damping.doubled) == 1
    doubled = in_damping.doubled[0]
    assert len(doubled.folds) == 1 and located < doubled.folds[0] < 0.035
    end = doubled.points[-1]
    assert end.value == 0.02 and end.on_grid and end.orbit.stable
    (in_speed,) = [p for p in branch.doubled[1].points if p.on_grid and p.value == INSIDE]
    for figure in ("K_v", "dte_p2p_um"):
        assert end.figures[figure] == pytest.approx(in_speed.figures[figure], rel=1e-7), figure


def test_unstable_period_2_orbits_repeat_by_the_reference_integrator(scene, branch):
    """The branch from the lower doubling is unstable (a real multiplier above 1 over 2T) where
    the teeth part; run through the independent scipy reference (its own event rule) over 2T
    from the orbit's state, it comes back within 2e-7 of each unknown's scale, two mesh
    periods on (measured 9.1e-9, 2.6e-9), and is far from it after one (> 1; measured 5.6,
    6.1)."""
    unstable = [p.orbit for p in branch.doubled[0].points
                if p.figures["contact_lost_share"] > 0.0]
    assert len(unstable) >= 3
    period_map = PeriodMap(scene, mesh_periods=2)
    reference = ScipyStepper(period_map.model, 1e-10)
    for orbit in unstable[::2]:
        assert orbit.residual <= NEWTON_TOLERANCE and orbit.mesh_periods == 2
        largest = orbit.multipliers[0]
        assert abs(largest.imag) < 1e-9 and largest.real > 1.0
        segment = period_map.start(orbit.state).segment
        halfway = reference.advance(Position(0.0, orbit.state.copy(), segment),
                                    0.5 * orbit.period, period_map.torques)
        end = reference.advance(halfway, orbit.period, period_map.torques)
        assert end.segment.contact_set.index == 0 and end.segment.contact_set.cycle == 2
        start = period_map.unknowns(orbit.state)
        assert np.abs(period_map.unknowns(end.state) - start).max() <= 2e-7
        assert np.abs(period_map.unknowns(halfway.state) - start).max() > 1.0
