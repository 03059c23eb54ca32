"""Radau IIA's kernel (integrate/compiled/radau.py): the Jacobian its Newton iterations and its
error estimate are built on."""
import numpy as np
import pytest
from helpers import MODELS

import herringbone
from herringbone.integrate.compiled import exponential, radau, walk
from herringbone.model.assembly import GearTrainModel
from herringbone.model.equations import derivative


def radau_jacobian(model, segment, state, tolerance):
    """jacobian_of at `state` with the absolute tolerance a run at `tolerance` gives it."""
    size = state.shape[0]
    rate, jacobian = np.empty(size), np.empty((size, size))
    derivative(model.system, segment.points, segment.point_count, segment.loaded,
               segment.motor_torque, segment.load_torque, state, rate)
    radau.jacobian_of(model.system, segment, state, rate, tolerance * model.state_scales(),
                      tolerance, jacobian, np.empty(size), np.empty(size))
    return jacobian


@pytest.mark.parametrize("tolerance", [1e-5, 1e-9, 1e-12])
def test_the_jacobian_is_the_sets_linear_part_where_the_state_is_zero(tolerance):
    """At a set's start (the pinion's entry, re-expressed from the set's start, is zero there)
    with every other entry zero too, each column but the pinion angle's equals the set's
    linear part A (exponential.linear_system: the equations are linear in those entries) to
    1e-6 of the column's largest entry, at every tolerance. The difference steps follow the
    state's scales: steps of 1e-7 of the absolute tolerance left such columns to rounding
    (off by 0.4 % of their size at 1e-7, 11 % at 1e-9, wholly at 1e-12), so that Newton
    diverged after a switch and the error estimate let steps through at up to 200 times the
    tolerance (test_integrator.py, test_a_static_solution_stays_static)."""
    model = GearTrainModel(herringbone.load_scene(MODELS / "integer_overlap.toml"))
    lengths, counts, tables = model.mesh.period_table()
    loaded = np.ones(counts[0])
    segment = walk.CompiledSegment(tables[0], counts[0], loaded, 500.0, 1800.0, lengths[0],
                                   walk.Event.CONTACT, -1)
    state = np.zeros(2 * model.size)
    jacobian = radau_jacobian(model, segment, state, tolerance)
    linear, _ = exponential.linear_system(model.system, tables[0], counts[0], loaded)
    for column in set(range(state.shape[0])) - {model.pinion}:
        size = np.abs(linear[:, column]).max()
        assert np.abs(jacobian[:, column] - linear[:, column]).max() <= 1e-6 * size, column
