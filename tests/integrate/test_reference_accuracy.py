"""The reference holds its tolerance over a whole run where the train rings long (issue 25):
lightly damped and undamped trains, whose step errors add up over the radians the modes ring."""
import math

import pytest
from helpers import MODELS, REGRESSION, force_error
from helpers.scene_distribution import random_scene

import herringbone
from herringbone.integrate import stepping
from herringbone.model.assembly import GearTrainModel, natural_modes

SCENES = REGRESSION / "reference_accuracy"


@pytest.mark.parametrize("name, stop_time", [
    ("undamped_reference_drift", 0.005),  # measured 2.1e-9; before the fix 2.5e-6 over 10 ms
    ("light_load_reference_drift", 0.01),  # measured 1.6e-9; before the fix 7.8e-8
])
def test_default_tolerance_agrees_with_a_hundred_times_tighter(name, stop_time):
    """The reference at its default tolerance (1e-10) against itself at 1e-12: within 1e-8 of
    the force scale, the bound issue 25 asks for, on the two scenes where it was off by 1e-6
    (an undamped train; a light load at 3 rad/s, whose slow modes ring with ζ < 1e-3)."""
    scene = herringbone.load_scene(SCENES / f"{name}.toml")
    default = herringbone.reference_simulate(scene, stop_time=stop_time)
    tighter = herringbone.reference_simulate(scene, stop_time=stop_time, tolerance=1e-12)
    assert force_error(default, tighter, scene) < 1e-8


def test_an_undamped_train_rings_its_fastest_mode_for_the_whole_run():
    """No damping: the radians rung are those of the fastest natural frequency over the run."""
    scene = herringbone.load_scene(SCENES / "undamped_reference_drift.toml")
    fastest = 2 * math.pi * natural_modes(scene)[0].max()
    model = GearTrainModel(scene)
    assert stepping.ringing_radians(model, 0.01) == pytest.approx(fastest * 0.01, rel=1e-9)
    assert stepping.ringing_radians(model, 0.02) == pytest.approx(fastest * 0.02, rel=1e-9)
    step = stepping.step_tolerance(model, 1e-10, 0.01)
    assert step == pytest.approx(1e-10 * stepping.RINGING_BUDGET / (fastest * 0.01), rel=1e-9)


def test_a_damped_train_rings_no_longer_however_long_the_run():
    """The reference scene (shafts, bearings and mesh damped): its modes' rings end with their
    damping (1/ζ radians), so a run of 100 s rings no more than one of 10 s; a run shorter than
    RINGING_BUDGET radians of every mode keeps the tolerance per step as it is."""
    model = GearTrainModel(herringbone.load_scene(MODELS / "reference.toml"))
    assert stepping.ringing_radians(model, 100.0) == stepping.ringing_radians(model, 10.0)
    assert stepping.ringing_radians(model, 0.01) < stepping.ringing_radians(model, 10.0)
    assert stepping.step_tolerance(model, 1e-10, 1e-5) == 1e-10


def test_the_step_tolerance_stops_at_scipys_finest():
    scene = herringbone.load_scene(SCENES / "undamped_reference_drift.toml")
    model = GearTrainModel(scene)
    assert stepping.step_tolerance(model, 1e-12, 1.0) == stepping.FINEST_STEP_TOLERANCE


@pytest.mark.xfail(strict=True, reason="issue 25 open on rattling trains: the reference at 1e-10 "
                   "is 3.2e-7 of the force scale off itself at 1e-12 on random scene 1029")
def test_a_rattling_train_agrees_with_a_hundred_times_tighter():
    """Random scene 1029 (tests/helpers/scene_distribution.py): a light load with contact loss that
    rattles through about 400 losses and regains in 9 ms. Measured 3.2e-7 (before the reference
    held its tolerance over the run, 2.3e-5); the worst of seeds 1000-1299 are 1202 (5.8e-5),
    1028 (1.3e-5), 1072 (8.8e-7), 1200 (7.4e-7). Moving each event from the dense output onto
    the stepped solution changed nothing (it moved them by at most 1e-8 of a step). The runs
    differ by 1e-9 for 4 ms; then the difference grows from landing to landing of the lifted-off
    mesh (docs/reference-accuracy.md)."""
    scene = random_scene(1029)
    default = herringbone.reference_simulate(scene)
    tighter = herringbone.reference_simulate(scene, tolerance=1e-12)
    assert force_error(default, tighter, scene) < 1e-8
