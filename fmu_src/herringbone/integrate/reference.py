"""The reference integration: scipy's DOP853, restarted at every switch.

Speed is a lesser concern here; this is the anchor every faster integrator is measured against.
Each segment of the run (segments.py) is integrated on its own with the contact set and loaded
points held fixed, and ends exactly at the next contact switch, contact loss or regain, or input
change, so the method keeps its full order everywhere (stepping.py). It shares the equations of
motion and the mesh geometry with the compiled integrator, but finds its events and decides what
follows them by its own rule (segments.py, stepping.py), so that the two check each other.
"""
from __future__ import annotations

from ..arguments import REFERENCE_DEFAULT_TOLERANCE, check_reference_run
from ..model.assembly import GearTrainModel
from .contract import Result, simulate_with
from .global_error import Check, checked_run
from .stepping import ScipyStepper, step_tolerance

DEFAULT_TOLERANCE = REFERENCE_DEFAULT_TOLERANCE  # its home: arguments.py


def reference_simulate(scene, stop_time=None, output_interval=None, tolerance=DEFAULT_TOLERANCE,
                       method="DOP853", initial_pinion_angle=0.0, check_tension=False):
    """Simulate a scene with the scipy reference (independent of the compiled integrator).

    Parameters
    ----------
    scene : Scene
    stop_time, output_interval : float or None
        Simulated seconds, and seconds between samples (at most stop_time); None: the scene's.
    tolerance : float
        The error aimed at in the forces over the run (held within a few times it, up to 21
        times on lightly damped trains: docs/reference-accuracy.md), relative to the force
        scale (the static mesh force, GearTrainModel.force_scale); [1e-12, 1e-5]. Each step is
        held to it through GearTrainModel.state_scales, cut where the train's modes ring longer
        than stepping.RINGING_BUDGET radians within the run (their step errors add up over every
        radian they ring: stepping.step_tolerance). A run in which the mesh lifts off and lands
        again, where small errors can grow from landing to landing, checks its error by a run
        ten times tighter, and runs tighter still where it exceeds the tolerance
        (global_error.py; two to four runs; measured in docs/reference-accuracy.md).
    method : str
        scipy's solve_ivp method ("DOP853", "Radau", …).
    initial_pinion_angle : float
        φp at t = 0, rad (0 in docs/model.md; another gives the run shifted in mesh phase).
    check_tension : bool
        Raise IntegrationError wherever a loaded point pulls or a free one penetrates
        (stepping.ScipyStepper's debug check; it costs a third more time).

    Returns
    -------
    Result
        {"time": …, output name: …} sampled every output_interval, SI units.

    Warns
    -----
    ReferenceAccuracyWarning
        A run that lifts off and lands whose estimated error exceeds `tolerance` even at
        scipy's finest step tolerance (the message names the scene and the estimate): a train
        that amplifies errors beyond what double precision resolves.

    Raises
    ------
    ValueError
        An argument outside arguments.check_reference_run's ranges, before any work
        (SceneError, a ValueError, for something that is not a Scene).
    IntegrationError
        The run cannot go on (it says where and why).

    Examples
    --------
    >>> import herringbone
    >>> scene = herringbone.load_scene("reference")
    >>> anchor = herringbone.reference_simulate(scene, stop_time=0.005, output_interval=1e-4)
    >>> fast = herringbone.simulate(scene, stop_time=0.005, output_interval=1e-4)
    >>> float(abs(fast["F_mesh"] - anchor["F_mesh"]).max()) < 1e-3  # N: they agree
    True
    """
    check_reference_run(scene, stop_time, output_interval, tolerance, method,
                        initial_pinion_angle)
    return checked_reference_run(scene, stop_time, output_interval, tolerance, method,
                                 initial_pinion_angle, check_tension)[0]


def checked_reference_run(scene, stop_time=None, output_interval=None,
                          tolerance=DEFAULT_TOLERANCE, method="DOP853", initial_pinion_angle=0.0,
                          check_tension=False, wrap=None) -> tuple[Result, Check]:
    """reference_simulate's run, its arguments checked by the caller, and what the check of
    its error over the run found (global_error.Check). `wrap(stepper)`, if given, gives what
    each of the check's runs advances through (a progress bar's stepper: the same numbers)."""
    stop_time = scene.experiment.stop_time if stop_time is None else stop_time
    model = GearTrainModel(scene)

    def run(step):
        stepper = ScipyStepper(model, step, method, check_tension=check_tension)
        result = simulate_with(stepper if wrap is None else wrap(stepper), scene, stop_time,
                               output_interval, initial_pinion_angle)
        return result, stepper.landings

    return checked_run(run, model, tolerance, step_tolerance(model, tolerance, stop_time))
