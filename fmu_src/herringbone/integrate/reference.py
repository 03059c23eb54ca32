"""The reference integration: scipy's DOP853, restarted at every switch.

Speed is a lesser concern here; this is the anchor every faster integrator is measured against.
Each segment of the run (segments.py) is integrated on its own with the contact set and loaded
points held fixed, and ends exactly at the next contact switch, contact loss or regain, or input
change, so the method keeps its full order everywhere (stepping.py). It shares the equations of
motion and the mesh geometry with the compiled integrator, but finds its events and decides what
follows them by its own rule (segments.py, stepping.py), so that the two check each other.
"""
from __future__ import annotations

from ..arguments import check_reference_run
from ..model.assembly import GearTrainModel
from .contract import simulate_with
from .stepping import ScipyStepper

# the reference's default error per step, relative to the static mesh force (reference_simulate,
# `herringbone run --reference`)
DEFAULT_TOLERANCE = 1e-10


def reference_simulate(scene, stop_time=None, output_interval=None, tolerance=DEFAULT_TOLERANCE,
                       method="DOP853", initial_pinion_angle=0.0, check_tension=False):
    """Simulate a scene; returns {"time": …, output name: …} sampled every output_interval.

    tolerance: the error allowed per step, relative to the force scale (the static mesh force),
    applied to every state entry through GearTrainModel.state_scales.
    initial_pinion_angle: φp at t = 0 (docs/model.md starts at 0; any other angle must give the same
    run shifted in mesh phase).
    check_tension: raise IntegrationError wherever a loaded point pulls or a free one penetrates
    (stepping.ScipyStepper's debug check; it costs a third more time).
    Arguments outside arguments.check_reference_run's ranges (tolerance in [1e-12, 1e-5], a
    solve_ivp method) raise ValueError before any work.
    """
    check_reference_run(scene, stop_time, output_interval, tolerance, method,
                        initial_pinion_angle)
    stepper = ScipyStepper(GearTrainModel(scene), tolerance, method, check_tension=check_tension)
    return simulate_with(stepper, scene,
                         stop_time, output_interval, initial_pinion_angle)
