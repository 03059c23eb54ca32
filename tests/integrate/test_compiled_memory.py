"""The compiled loop keeps the memory it is given: `walk.advance` runs without numba's reference
counts (compiled/__init__.py says why), so a kernel that allocated, or handed back arrays, under
the wrong setting would leak memory or free arrays that Python still holds. Each method runs in
a fresh process with numba's allocation statistics on; every allocation must be freed and every
array passed in must end with the references it had."""

import pytest
from helpers.memory_probe import assert_kept, probe, run_probe

PROBE = probe(
    setup="stepper.run_to(run, 1e-4, torques)\n",
    body="""
before = rtsys.get_allocation_stats()
for k in range(1, 41):
    stepper.run_to(run, 1e-4 + k * interval, torques)
after = rtsys.get_allocation_stats()
extra = {}
""", given="()")


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
