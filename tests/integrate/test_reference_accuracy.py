"""The reference holds its tolerance over a whole run where the train rings long (issue 25):
lightly damped and undamped trains, whose step errors add up over the radians the modes ring;
and trains that rattle, whose runs check their own error (integrate/global_error.py) and warn
where scipy's finest step tolerance cannot hold it."""
import math
import warnings

import numpy as np
import pytest
from helpers import MODELS, REGRESSION, force_error
from helpers.scene_distribution import random_scene

import herringbone
from herringbone import ReferenceAccuracyWarning
from herringbone.integrate import stepping
from herringbone.integrate.contract import simulate_with
from herringbone.integrate.reference import checked_reference_run
from herringbone.model.assembly import GearTrainModel, natural_modes

SCENES = REGRESSION / "reference_accuracy"


@pytest.mark.parametrize("name, stop_time, pinion_angle", [
    ("undamped_reference_drift", 0.005, 0.0),  # measured 2.1e-9; before the fix 2.5e-6 (10 ms)
    ("light_load_reference_drift", 0.01, 0.0),  # measured 1.6e-9; before the fix 7.8e-8
    # the start moved by 2e-9 rad: 1.6e-9; 1.1e-8 before steps were held to STEP_RADIANS
    ("light_load_reference_drift", 0.01, 2e-9),
])
def test_default_tolerance_agrees_with_a_hundred_times_tighter(name, stop_time, pinion_angle):
    """The reference at its default tolerance (1e-10) against itself at 1e-12: within 1e-8 of
    the force scale, the bound issue 25 asks for, on the two scenes where it was off by 1e-6
    (an undamped train; a light load at 3 rad/s, whose slow modes ring with ζ < 1e-3); and on
    the second with its start moved by a hair, which changes every step of the run: before an
    explicit step was held to STEP_RADIANS of the fastest mode, such hairs gave 3e-9 to 1.1e-8,
    as one long step or another let a bearing mode's error through."""
    scene = herringbone.load_scene(SCENES / f"{name}.toml")
    default = herringbone.reference_simulate(scene, stop_time=stop_time,
                                             initial_pinion_angle=pinion_angle)
    tighter = herringbone.reference_simulate(scene, stop_time=stop_time, tolerance=1e-12,
                                             initial_pinion_angle=pinion_angle)
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


def unchecked(scene, tolerance, stop_time=None):
    """The reference's run with every step held to the step tolerance `tolerance` gives over
    the scene's experiment (stepping.step_tolerance), without the check of global_error.py
    (what reference_simulate delivered before it checked runs that land); to `stop_time` (s)
    if given, with those steps."""
    model = GearTrainModel(scene)
    step = stepping.step_tolerance(model, tolerance, scene.experiment.stop_time)
    return simulate_with(stepping.ScipyStepper(model, step), scene, stop_time)


def test_a_run_that_never_lands_is_run_once():
    """The contact-loss scene loses and regains single points but its mesh never lifts off
    whole over 5 ms: no check, one run, the unchecked run to the bit."""
    scene = herringbone.load_scene(MODELS / "contact_loss.toml")
    result, check = checked_reference_run(scene, stop_time=0.005)
    assert check.runs == 1 and check.landings == 0 and check.estimate is None
    model = GearTrainModel(scene)
    stepper = stepping.ScipyStepper(model, stepping.step_tolerance(model, 1e-10, 0.005))
    plain = simulate_with(stepper, scene, stop_time=0.005)
    assert all(np.array_equal(result[name], plain[name]) for name in plain)


def test_a_rattling_train_agrees_with_a_hundred_times_tighter():
    """Random scene 1029 (tests/helpers/scene_distribution.py): a light load with contact loss
    that rattles through 28 landings of its lifted-off mesh in 9 ms, each amplifying the
    errors before it (a relative 1e-13 on the initial pinion speed moves the forces by 2.5e-9
    of the force scale). Unchecked, the run at 1e-10 was 3.2e-7 off the one at 1e-12. Checked
    (global_error.py), the runs at 1e-10 and at 1e-12 both end at scipy's finest step
    tolerance, their error estimated at 1.1e-10 and 1.4e-10 (each warns). The bar, and the
    same against the unchecked run at 1e-12 (measured 2.4e-9), which differs from the checked
    ones in every step."""
    scene = random_scene(1029)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ReferenceAccuracyWarning)  # 1.1e-10 against 1e-10
        default, check = checked_reference_run(scene)
    assert check.landings > 20 and check.estimate < 1e-9
    with pytest.warns(ReferenceAccuracyWarning, match="random_1029"):
        tighter = herringbone.reference_simulate(scene, tolerance=1e-12)
    assert force_error(default, tighter, scene) < 1e-8
    assert force_error(default, unchecked(scene, 1e-12), scene) < 1e-8


# Rattling random scenes that the check cannot bring within the tolerance: each ends at scipy's
# finest step tolerance and warns. Measured: the estimate at 1e-10; the run delivered against the
# unchecked run at 1e-12; and what a relative 1e-13 on the initial pinion speed moves the forces
# by (the train's sensitivity; 1e-13 is some 500 units of double precision).
BEYOND_DOUBLE_PRECISION = {
    1202: "estimated 3.6e-7; 8.6e-7 off the unchecked run at 1e-12; sensitivity 6.0e-6",
    1028: "estimated 1.5e-8; 1.3e-7 off the unchecked run at 1e-12; sensitivity 5.2e-7",
    1072: "estimated 1.7e-9; 4.2e-8 off the unchecked run at 1e-12; sensitivity 3.5e-6",
    1200: "estimated 2.4e-9; 1.5e-8 off the unchecked run at 1e-12; sensitivity 7.8e-7",
}
# seconds for the test on one core: 1200 12, 1028 10, 1072 75, 1202 5
SLOW_SEEDS = {1200, 1028, 1072}


def rattling_cases():
    """The BEYOND_DOUBLE_PRECISION seeds (strict xfails naming their figures), the slow ones
    marked."""
    return [pytest.param(seed, id=f"seed_{seed}", marks=(
        [pytest.mark.slow] if seed in SLOW_SEEDS else []) + ([pytest.mark.xfail(
            strict=True, raises=AssertionError, reason="a train that amplifies errors beyond "
            f"what scipy's finest step tolerance resolves: {BEYOND_DOUBLE_PRECISION[seed]}")]
            if seed in BEYOND_DOUBLE_PRECISION else []))
        for seed in BEYOND_DOUBLE_PRECISION]


@pytest.mark.parametrize("seed", rattling_cases())
def test_a_rattling_train_warns_and_stays_near_the_unchecked_reference(seed):
    """The other four worst rattling trains of seeds 1000-1299 (slow where the test takes
    over 5 s). The reference at its default tolerance warns that even scipy's finest step
    tolerance leaves its estimated error beyond 1e-10, names the scene, and delivers that
    finest run; which lies beyond 1e-8 of the unchecked run at 1e-12 on every one (strict
    xfails): a relative 1e-13 on the initial pinion speed moves their forces by 5e-7 to 6e-6
    of the force scale. (Seed 1200, 3.9e-9 off when first measured, is 1.5e-8 off here:
    at that sensitivity the last bits of a library move it across the bound.)"""
    scene = random_scene(seed)
    with pytest.warns(ReferenceAccuracyWarning, match=f"random_{seed}"):
        default, check = checked_reference_run(scene)
    assert check.step_tolerance == stepping.FINEST_STEP_TOLERANCE
    assert force_error(default, unchecked(scene, 1e-12), scene) < 1e-8


def test_a_crossing_after_a_bulge_that_stays_below_zero_is_found():
    """Random scene 1177 (a train whose points lose and regain contact some 900 times in 7 ms,
    the mesh never lifting off whole): at 1.937 ms one step of the run at 1e-10 held a bulge
    of one point's event function that stayed below zero and, later in the step, another
    point's approach rising through zero. The search stopped at the bulge, the regain went
    unseen, the point penetrated unloaded, and the run ended 3.0e-4 of the force scale off the
    run at 1e-12. Every interval with a candidate is now searched: 2.7e-9 over the whole run."""
    scene = random_scene(1177)
    runs = [unchecked(scene, tolerance, stop_time=0.0025) for tolerance in (1e-10, 1e-12)]
    assert force_error(*runs, scene) < 1e-8


def test_points_the_static_deflection_leaves_unloaded_add_no_damping():
    """Random scene 1278: a lead error (dbeta_right) leaves some 6 of the 10 points of each
    contact set unloaded at the static deflection, and its pinion's bearings are undamped, so
    the fastest mode (3.2e5 rad/s, the pinion on its bearings) is damped by the mesh alone,
    through the loaded points: every point loaded it would ring 464 radians within the run,
    the points loaded as the static deflection under its torques loads them 1491 (at 36.8 N·m;
    759 at 74.9 N·m). The shipped scenes whose static deflection loads every point ring as
    with every point loaded, to the bit (and so keep their steps)."""
    model = GearTrainModel(random_scene(1278))
    horizon = model.scene.experiment.stop_time
    every_point = stepping.mode_radians(model.eigenvalues(), horizon)
    assert every_point == pytest.approx(464, rel=0.01)
    assert stepping.driving_torques(model, horizon) == pytest.approx([36.806, 74.917],
                                                                     rel=1e-4)
    assert stepping.ringing_radians(model, horizon) == pytest.approx(1491, rel=0.01)
    for name in ("separation", "jump_resonance", "reference"):
        model = GearTrainModel(herringbone.load_scene(MODELS / f"{name}.toml"))
        torque = stepping.driving_torques(model, 0.02)[0]
        assert stepping.statically_loaded_matrices(model, torque) is None
        assert stepping.ringing_radians(model, 0.02) == stepping.mode_radians(
            model.eigenvalues(), 0.02)


@pytest.mark.slow  # 20 s
def test_a_lightly_damped_train_that_never_lands_agrees_with_a_hundred_times_tighter():
    """Random scene 1278, whose points lose and regain contact (16 times) without the mesh
    lifting off: lightly damped where loaded (above), its run at 1e-10 was 1.16e-8 of the force
    scale off the run at 1e-12 when the step tolerance counted the 464 radians of every point
    loaded (its error, 5.4e3 times the step tolerance, carried by the fastest mode and growing
    steadily over the whole run). Counting the 1491 radians of the points statically loaded:
    3.5e-9."""
    scene = random_scene(1278)
    default = herringbone.reference_simulate(scene)
    tighter = herringbone.reference_simulate(scene, tolerance=1e-12)
    assert force_error(default, tighter, scene) < 1e-8
