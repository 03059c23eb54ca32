"""The compiled loop keeps the memory it is given: `walk.advance` runs without numba's reference
counts (compiled/__init__.py says why), so a kernel that allocated, or handed back arrays, under
the wrong setting would leak memory or free arrays that Python still holds. Each method runs in
a fresh process with numba's allocation statistics on; every allocation must be freed and every
array passed in must end with the references it had."""

import pytest
from helpers.memory_probe import assert_kept, run_probe

PROBE = r"""
import json, sys
import numpy as np
from numba.core.runtime import rtsys
import herringbone
from herringbone.integrate.compiled_stepper import CompiledStepper
from herringbone.integrate.contract import start_position
from herringbone.model.assembly import GearTrainModel

scene = herringbone.load_scene(sys.argv[1])
model = GearTrainModel(scene)
stepper = CompiledStepper(model, 1e-7, sys.argv[2])
start = start_position(model, scene.inputs.at(0.0)[0])
run = stepper.start(start)
stepper.run_to(run, 1e-4, scene.inputs.at(0.0))  # loads (or compiles) the kernels first

def arrays(value):
    if isinstance(value, np.ndarray):
        yield value
    elif isinstance(value, tuple):
        for item in value:
            yield from arrays(item)

given = list(arrays((stepper.system_arrays, stepper.mesh, stepper.settings, run.clock, run.place,
                     run.state, run.loaded, run.first_steps, run.outputs, run.workspace)))
def references():  # (one way of counting, before and after: a loop's own tuples hold one)
    return [sys.getrefcount(array) for array in given]

counted = references()
before = rtsys.get_allocation_stats()
for k in range(1, 41):
    stepper.run_to(run, 1e-4 + k * float(sys.argv[3]), scene.inputs.at(0.0))
after = rtsys.get_allocation_stats()
print(json.dumps({
    "allocated": after.alloc - before.alloc, "freed": after.free - before.free,
    "records_made": after.mi_alloc - before.mi_alloc,
    "records_freed": after.mi_free - before.mi_free,
    "references_changed": sum(now != then for now, then in zip(references(), counted)),
    "arrays": len(given)}))
"""


@pytest.mark.parametrize("scene, method, interval", [
    ("reference", "dop853", 2e-4),
    ("reference", "exponential", 2e-4),
    ("contact_loss", "dop853", 2e-4),  # losses and regains: the grazing probe and its steps
    ("stiff_bearings", "radau", 2e-6),  # Radau IIA allocates its Newton arrays at every step
])
def test_a_run_frees_what_it_allocates_and_keeps_what_it_was_given(scene, method, interval):
    figures = run_probe(PROBE, scene, method, interval)
    assert figures["arrays"] >= 10
    print(figures)
    assert_kept(figures)
    if method == "radau":
        assert figures["allocated"] > 0  # the check sees the allocations it counts
