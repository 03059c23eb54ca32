"""walk.advance's records as flat buffers (integrate/compiled/buffers.py): what is packed
comes back, field by field, in compiled code and in Python alike, and the run's views are
views, so that what the loop writes is the run's position."""
import numpy as np
import pytest
from helpers import MODELS
from numba import njit

import herringbone
from herringbone.integrate.compiled import buffers, walk
from herringbone.integrate.compiled_stepper import CompiledStepper
from herringbone.integrate.contract import start_position
from herringbone.model.assembly import GearTrainModel
from herringbone.model.equations import System


@njit
def constants_back(constants):
    system, mesh, settings = buffers.unpack_constants(constants)
    return (system.element_rows_relative.copy(), system.coupling_column.copy(),
            system.axial_travel_per_radian, mesh.lengths.copy(), mesh.counts.copy(),
            mesh.tables.copy(), settings.copy())


@njit
def run_back(run):
    clock, place, state, loaded, first_steps, outputs, vectors, values, counters, memory = \
        buffers.unpack_run(run)
    state[0] = 12.5  # written through the view
    return (clock.copy(), place.copy(), state.copy(), loaded.copy(), first_steps.copy(),
            outputs.copy(), vectors.copy(), values.copy(), counters.copy(), memory.copy())


def stepper_and_run(name):
    scene = herringbone.load_scene(MODELS / f"{name}.toml")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7, "exponential")
    return model, stepper, stepper.start(start_position(model, scene.inputs.at(0.0)[0]))


@pytest.mark.parametrize("name", ["reference", "staggered"])  # (4 points a set; 8, wider)
def test_the_constants_unpack_to_the_same_system_mesh_and_settings(name):
    model, stepper, _ = stepper_and_run(name)
    (rows, columns, travel, lengths, counts, tables, settings) = constants_back(
        stepper.constants)
    system: System = model.system
    assert np.array_equal(rows, system.element_rows_relative)
    assert np.array_equal(columns, system.coupling_column)
    assert travel == system.axial_travel_per_radian
    assert np.array_equal(lengths, stepper.lengths)
    assert np.array_equal(counts, stepper.counts)
    assert np.array_equal(tables, stepper.tables)
    assert np.array_equal(settings, stepper.settings)


@pytest.mark.parametrize("name", ["reference", "staggered"])
def test_a_run_unpacks_to_views_of_its_position_and_workspace(name):
    _, stepper, run = stepper_and_run(name)
    run.workspace.vectors[:] = np.arange(run.workspace.vectors.size).reshape(
        run.workspace.vectors.shape)
    run.workspace.values[:] = -np.arange(run.workspace.values.size).reshape(
        run.workspace.values.shape)
    run.workspace.counters[:] = np.arange(len(walk.Counter))
    run.workspace.memory[:] = np.arange(len(walk.Memory)) + 0.5
    before = [array.copy() for array in (run.clock, run.place, run.state, run.loaded,
                                         run.first_steps, run.outputs)]
    compiled = run_back(run.buffers)
    python = (*before, run.workspace.vectors, run.workspace.values, run.workspace.counters,
              run.workspace.memory)
    for name_, in_compiled, in_python in zip(
            ("clock", "place", "state", "loaded", "first_steps", "outputs", "vectors",
             "values", "counters", "memory"), compiled, python):
        expected = in_python.copy()
        if name_ == "state":
            expected[0] = 12.5
        assert in_compiled.shape == expected.shape, name_
        assert np.array_equal(in_compiled, expected), name_
    assert run.state[0] == 12.5  # the compiled write reached the run's position
    assert run.state.base is run.buffers[0] and run.place.base is run.buffers[1]
