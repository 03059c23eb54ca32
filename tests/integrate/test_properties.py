"""Property tests over random scenes, and the regression scenes they leave behind.

Every random scene (random_scenes.scenes(): 8-60 teeth, helix 5°-40°, bearings 1e8-1e11 N/m,
damping down to zero, 1-2500 rad/s, some turned backwards, light loads, torque steps, lead
errors, stagger, edge ramps; 5-20 ms runs) and every tests/regression/*.toml scene must pass
property_checks.check_scene: compiled against reference within 1e-4 of the force scale at the
default tolerance (1e-6 at 1e-9, against a reference at 1e-12; 1e-2 at 1e-5, against one at
1e-8; where the reference's run lifts off and lands, against reference_simulate's, which checks
its error over the run), no tension, finite outputs, angular momentum following the torques to
1e-9 of its largest term, the same n_contacts away from switches. The same draw made exact
(scene_distribution.made_exact: symmetric halves, no lead errors, sharp edges) puts the
exponential method's exact segments to the same checks.

Every run checks a few dozen seeded scenes (scene_distribution's NumPy sampler): the same
scenes on every run and machine. (Hypothesis's derandomized draw is not the same: it mixes in
the literals of every local module imported so far, so its scenes changed with the session's
imports and with every edit of the code.) The `slow` tests draw many more with Hypothesis, at
random, and shrink what fails:

    pytest -m slow tests/integrate/test_properties.py                         # 300 examples each
    HERRINGBONE_PROPERTY_EXAMPLES=2000 pytest -m slow tests/integrate/test_properties.py

A scene that fails is written to tests/regression/found_<digest>.toml (its header says what failed
and by how much; property_checks.save_if_final): commit it, and the regression test runs it from
then on. The drawn tests pass over a scene that is already a known disagreement there, and
over one that cannot judge (property_checks.can_be_judged): one that the reference does not
resolve (resolved_by_the_reference): there every run, reference or compiled, lies force
scales from every other, and no integrator can be judged; and one whose
recorded reference, at a tolerance per step a thousand times tighter than the compiled run's,
does not hold the bound itself (property_checks.per_step_holds): a train that amplifies a
step's error from landing to landing beyond what any tolerance per step holds.
"""
import dataclasses
import os

import helpers.property_checks as checks
import numpy as np
import pytest
from helpers import (
    MODELS,
    REGRESSION,
    benchmark_module,
    compiled_run,
    force_error,
    regression_scene,
)
from helpers.random_scenes import random_scene, scenes
from helpers.scene_distribution import LOW_SPEED, made_exact, turned_backwards
from hypothesis import HealthCheck, assume, given, settings

import herringbone
from herringbone.integrate.compiled import exponential
from herringbone.integrate.compiled_stepper import choose_method
from herringbone.model.assembly import GearTrainModel

LONG = settings(max_examples=int(os.environ.get("HERRINGBONE_PROPERTY_EXAMPLES", "300")),
                deadline=None, print_blob=True, suppress_health_check=[HealthCheck.too_slow])
REGRESSION_SCENES = sorted(REGRESSION.glob("*.toml"))


def landing_amplified(train, estimate, method, errors, found):
    """The reason of a train the reference resolves and the compiled run converges on in
    proportion to its tolerance, but past the bound: the tolerance holds each step, and the
    train's landings amplify a step's error. `errors`: the compiled run's, over the force
    scale, at its tolerances."""
    return (f"{train}: the reference resolves it (reference_simulate's error over the run "
            f"estimated at {estimate}); the compiled run ({method}) converges on it in "
            f"proportion to its tolerance (over the force scale: {errors}): its step tolerance "
            f"holds each step, not what the landings amplify (found by {found})")


# Scenes of the draw that the two integrators do not agree on, each a fault not yet cured; strict,
# so that a cure makes its test fail until the entry is removed
DISAGREEMENTS = {
    "found_59825caa1e": "a rattling train with no mesh damping (contact lost and regained at "
                        "531 rad/s): neither integrator has converged at its tight tolerance "
                        "(compiled 1e-9 against 1e-11: 2.4e-2 of the force scale; reference "
                        "1e-10 against 1e-12: 2.5e-3). reference_simulate, which checks a run "
                        "that lands (86 landings here), warns: even at scipy's finest step "
                        "tolerance its error is estimated at 5.3e-6; the per-step references "
                        "these checks run lie 2.3e-2 (1e-10) and 1.6e-4 (1e-12) from that run, "
                        "the compiled runs 1.35 (1e-7) and 2.5e-2 (1e-9)",
    "found_4c2831d756": "a rattling train (light load, no motor, rigid bearings, contact lost "
                        "and regained): the reference at 1e-10 does not agree with the "
                        "reference of the previous release by more than the force scale, and "
                        "the compiled run lies 2 force scales from it. reference_simulate, "
                        "which checks a run that lands (245 landings here), warns: even at "
                        "scipy's finest step tolerance its error is estimated at 0.37 of the "
                        "force scale, and every run at another step tolerance, per-step "
                        "reference or compiled, lies 1.9 to 2.3 force scales from it: no run "
                        "in double precision resolves this train (docs/reference-accuracy.md)",
    "found_aaeb0efe2e": "a rattling train with no mesh damping, no bearings and no motor, which "
                        "the torque step throws backwards to 3.4e4 rad/s (102 landings in 16 "
                        "ms): the reference at 1e-10 lies 11.8 force scales from itself at "
                        "1e-12, and reference_simulate, which checks a run that lands, warns "
                        "that even at scipy's finest step tolerance its error is 16 force "
                        "scales; the compiled run lies 7.2 (1e-7) and 11.8 (1e-9) from it",
    "found_6d9d0203a0": "the same train without its load (69 landings in 16 ms, 3.3e4 rad/s "
                        "backwards): the reference at 1e-10 lies 9.0 force scales from itself "
                        "at 1e-12, reference_simulate estimates its error at 17 even at "
                        "scipy's finest step tolerance; the compiled run lies 19.2 (1e-7) and "
                        "8.1 (1e-9) from it",
    "found_42d38d1d40": "a sibling of found_6d9d0203a0 that the draw found next (no mesh "
                        "damping, no bearings, no motor or load, a torque step at 7.8 ms; 63 "
                        "to 70 landings in 16 ms): reference_simulate, which checks a run "
                        "that lands, warns that even at scipy's finest step tolerance its "
                        "error over the run is 1.1 (1e-12) to 33 (1e-10) force scales; the "
                        "per-step references these checks run lie 6.9 (1e-10) and 16.1 "
                        "(1e-12) from it, the compiled runs 11 (1e-7) and 9.6 (1e-9): no run "
                        "in double precision resolves this train",
    "found_82231c292f": "a rattling train with no damping anywhere (mesh and bearings), no "
                        "motor or load, a torque step at 3.9 ms; 339 landings in 16 ms: "
                        "reference_simulate warns that even at scipy's finest step tolerance "
                        "its error over the run is 0.18 (1e-12) to 2.4 (1e-10) force scales; "
                        "the per-step references lie 1.9 (1e-10) and 1.8 (1e-12) from it, the "
                        "compiled runs 2.2 (1e-7 and 1e-9): no run in double precision "
                        "resolves this train",
    "found_5f6a0dae18": "a light train at 2500 rad/s with a soft undamped input shaft, a lead "
                        "error and edge ramps, no bearings, that loses and regains contact 40 "
                        "times in 9.5 ms: reference_simulate resolves it (its error over the "
                        "run estimated at 2.5e-7 at 1e-10, 3.3e-7 at 1e-12); the compiled run "
                        "lies 4.2e-3 of the force scale from it at 1e-7 and 8.1e-5 at 1e-9, "
                        "the per-step references 1.2e-3 (1e-10) and 1.2e-5 (1e-12). Not a "
                        "landing missed: a relative 1e-13 on the initial pinion speed moves its "
                        "forces by 8.7e-6 (1e-11 by 8.7e-4, 1e-9 by 0.085), and the compiled run "
                        "converges on the reference as its tolerance tightens (4.2e-3, 1.3e-4, "
                        "8.1e-5, 9.8e-6, 8.6e-7, 2.1e-7 at 1e-7 to 1e-12): the train amplifies "
                        "a step's error some 1e8-fold, beyond what a tolerance per step holds "
                        "(0.60 at 1e-7 before the steps saw the free flight's undamped modes)",
    "found_de62c18e83": "a light train at 2500 rad/s with no damping at all (no mesh damping, "
                        "an undamped input shaft, no bearings), a lead error and sharp face "
                        "edges, that loses and regains contact 17 times in 7.8 ms: "
                        "reference_simulate resolves it (its error over the run estimated at "
                        "7e-8), but a relative 1e-11 on the initial pinion speed moves its "
                        "forces by 7.5e-6: the per-step references lie 4.8e-4 (1e-10) and "
                        "3.1e-6 (1e-12) from it, the compiled runs 2.6e-3 (1e-7) and 1.6e-5 "
                        "(1e-9) (found by the draw on 2026-11-27)",
    "found_7829a34ec8": "a rattling train (mesh damping ζ 0.0067, undamped bearings; contact lost "
                        "and regained 97 times): reference_simulate, which checks a run that "
                        "lands, warns that even at scipy's finest step tolerance its error over "
                        "the run is 1.3e-4 of the force scale (its runs at 1e-10 and 1e-12 are "
                        "that one run); the per-step references these checks run lie 0.28 "
                        "(1e-10) and 5.4e-3 (1e-12) from it, the compiled runs 2.0 (1e-7) and "
                        "0.030 (1e-9)",
    "found_345d6831cc": "a rattling train with no mesh damping and undamped wheel bearings "
                        "(contact lost and regained 66 times): reference_simulate warns that "
                        "even at scipy's finest step tolerance its error over the run is 5e-7 of "
                        "the force scale; the per-step references these checks run lie 1.7e-3 "
                        "(1e-10) and 1.6e-5 (1e-12) from it, the compiled runs 0.014 (1e-7) and "
                        "1.5e-4 (1e-9): the train amplifies a step's error some million-fold, "
                        "beyond what a tolerance per step holds",
    "found_465097d4b4": landing_amplified(
        "a train with no mesh damping, no load and no bearings, a lead error on one half, whose "
        "motor torque drops tenfold at 5.9 ms (35 landings in 16 ms)", "4e-11 at 1e-10",
        "DOP853, `auto`'s", "1.5e-4 at 1e-7, 2.3e-6 at 1e-9, 1.7e-7 at 1e-10, 1.5e-8 at 1e-11",
        "the draw on 2026-11-28"),
    "found_57ba526e1e": landing_amplified(
        "a free gear pair (no motor, load or bearings; mesh damping ζ 0.13) with a lead error "
        "on its right half, at 1097 rad/s under its torques, that loses and regains contact 38 "
        "times in 15.6 ms", "1.3e-9 at 1e-10, 1.5e-9 at 1e-12", "DOP853, `auto`'s",
        "7e-4 at 1e-7, 2e-4 at 1e-8, 1.8e-5 at 1e-9, 1.3e-6 at 1e-10", "the draw on 2026-11-29"),
    "found_279bae3628": landing_amplified(
        "a light train at 1 rad/s (mesh damping ζ 0.005, no bearings, an undamped soft output "
        "shaft) whose motor torque drops fourfold at 4.4 ms, so that the load turns it back "
        "(the pinion to 1700 rad/s) and it lands 25 times in 11 ms",
        "2e-8 at scipy's finest step tolerance", "the exponential method, `auto`'s; DOP853 five "
        "times further off", "1.1e-3 at 1e-7, 9.6e-5 at 1e-8, 8e-6 at 1e-9, 6.6e-7 at 1e-10",
        "the draw on 2026-11-29"),
    "found_9d9f16c6e7": landing_amplified(
        "a light train at 1 rad/s (no motor, no bearings, mesh damping ζ 0.006, edge ramps) "
        "whose motor torque drops tenfold at 3.7 ms, so that the load turns it back and it "
        "lands 99 times in 18.6 ms", "4.4e-9 at 1e-12", "the exponential method, `auto`'s, "
        "half the sets exact; DOP853 as far off", "1.6e-3 at 1e-7, 6.9e-5 at 1e-8, 3.6e-6 at "
        "1e-9, 1.8e-7 at 1e-10, 2.8e-9 at 1e-11", "the made-exact draw on 2026-11-29"),
}
# Scenes the two agree on within the default bound but not within the tight one
TIGHT_DISAGREEMENTS = {
    "found_cf90c2c007": "a train that loses and regains contact 60 times: the reference "
                        "resolves it (reference_simulate's error over the run estimated at "
                        "1.3e-8 at 1e-12), but a relative 1e-13 on the initial pinion speed "
                        "moves its forces by 8.5e-7 of the force scale; the compiled run at "
                        "1e-9 lies 2.4e-6 from it (5.9e-5 at 1e-7, within its bound 1e-4) and "
                        "converges on it as its tolerance tightens (2.7e-7 at 1e-10, 1.6e-8 "
                        "at 1e-11)",
}


# Scenes the two agree on within the tight bound but not within the default one
DEFAULT_DISAGREEMENTS = {
    "found_39bc44cd08": landing_amplified(
        "a light train at 1 rad/s (no motor, no bearings, no mesh damping, edge ramps) whose "
        "motor torque drops ninefold at 3.9 ms, so that the load turns it back and it lands 37 "
        "times in 7.8 ms", "1.2e-10", "DOP853, `auto`'s: the ramps of a slow train keep sets "
        "from being exact", "1.5e-4 at 1e-7 (bound 1e-4), 9.9e-6 at 1e-8, 5.8e-7 at 1e-9 "
        "(within the tight bound), 2.8e-8 at 1e-10", "the made-exact draw on 2026-11-29"),
    "found_7257c253f0": landing_amplified(
        "a light train at 1 rad/s (no load rotor, no bearings, a lead error on its right half, "
        "edge ramps) under steady torques, which rattles, swinging between 6.4 and -1.2 rad/s, "
        "and lands 32 times in 15.6 ms", "2.7e-11", "DOP853, `auto`'s",
        "1.2e-4 at 1e-7 (bound 1e-4), 1e-5 at 1e-8, 7.7e-7 at 1e-9 (within the tight bound), "
        "2e-8 at 1e-10", "the draw on 2026-11-29"),
}


# With -m slow: at the tight tolerance the scenes whose reference at 1e-12 runs through long
# ringing (undamped_stiff_bearings over a minute on two cores, the others 15 to 45 s; their
# default checks, some as long, stay in the quick run); at both, found_d74586bece, whose
# reference restarts at 15 000 pitches of a free pinion spun to 1e6 rad/s (a minute a check;
# the check it exposed has a quick test of its own), and the known disagreements, whose
# reference checks its run of a train that lands down to scipy's finest step tolerance where
# no run resolves it (3 to 70 s a scene on this project's slower 2-core machine)
SLOW_WHEN_TIGHT = {"undamped_stiff_bearings", "found_0deb4142a8", "found_a0c02a6892",
                   "found_64696b9bdb"}
SLOW_ALWAYS = set(DISAGREEMENTS) | {"found_d74586bece"}


def regression_cases():
    """Every regression scene at the default and at the tight tolerance, a known disagreement
    (at the tight one only: TIGHT_DISAGREEMENTS; at the default one only:
    DEFAULT_DISAGREEMENTS) as a strict xfail naming it."""
    cases = []
    for path in REGRESSION_SCENES:
        for tight in (False, True):
            reason = DISAGREEMENTS.get(path.stem) or (
                TIGHT_DISAGREEMENTS if tight else DEFAULT_DISAGREEMENTS).get(path.stem)
            marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
            if path.stem in SLOW_ALWAYS or (tight and path.stem in SLOW_WHEN_TIGHT):
                marks.append(pytest.mark.slow)
            cases.append(pytest.param(path, tight, marks=marks,
                                      id=f"{path.stem}-{'tight' if tight else 'default'}"))
    return cases


def check_tight(scene, bound=checks.TIGHT_BOUND):
    """Compiled at 1e-9 against the reference at 1e-12: within `bound` (1e-6) of the force
    scale."""
    checks.check_scene(scene, checks.TIGHT_TOLERANCE, bound, reference_tolerance=1e-12)


# Regression scenes whose forces at the tight tolerance rounding decides: a relative 1e-13 on
# the initial pinion speed moves the checked reference by about the tight bound, so the
# compiled run falls on either side of it from one machine to another.
# Each is judged at twice that spread as measured on the machine the test runs on
# (checks.rounding_spread), never looser than the tight bound: where rounding moves it less,
# the plain bound holds.
ROUNDING_DECIDED = {
    "found_ac909a1c90": "an undamped gear pair alone (no bearings, motor or load rotor) at "
                        "2 322 rad/s for 15.6 ms, found with the compiled run 6.4e-6 off: the "
                        "1e-13 moves the reference 1.07e-6; DOP853, Radau IIA and the "
                        "exponential method at 1e-12 lie 5e-7 to 2.1e-6 apart; the compiled "
                        "run at 1e-9 lies 1.2e-6 off on a Zen 4 EPYC (2026-11-29), within 1e-6 "
                        "on the machine before it; on an EPYC with numpy 2.4 (2026-12-01) "
                        "rounding moved the reference 2.6e-7 only",
}


def tight_bound(name, scene):
    """The tight check's bound for the regression scene `name`: TIGHT_BOUND, or for one that
    ROUNDING_DECIDED names, twice its checks.rounding_spread on this machine where that is
    larger."""
    if name not in ROUNDING_DECIDED:
        return checks.TIGHT_BOUND
    return max(checks.TIGHT_BOUND, 2.0 * checks.rounding_spread(scene, 1e-12))


def check_loose(scene):
    """Compiled at 1e-5 against the reference at 1e-8: within 1e-2 of the force scale."""
    checks.check_scene(scene, checks.LOOSE_TOLERANCE, checks.LOOSE_BOUND,
                       reference_tolerance=1e-8)


# Seeded scenes the integrators disagree on, each a fault not yet cured (strict xfails)
SEED_DISAGREEMENTS = {
    34: "the compiled integrator at its default tolerance is 8e-4 of the force scale off (a "
        "light train at 1.2 rad/s with edge ramps that loses and regains contact 18 times, "
        "where the reference estimates its own error over the run at 6.2e-9); at 1e-9 1.7e-5: "
        "its step tolerance holds each step, not what the landings amplify",
}


def seeded_cases(seeds):
    """random_scene(seed) for each seed, a known disagreement as a strict xfail naming it."""
    return [pytest.param(seed, id=f"seed_{seed}", marks=[pytest.mark.xfail(
        strict=True, reason=SEED_DISAGREEMENTS[seed])] if seed in SEED_DISAGREEMENTS else [])
        for seed in seeds]


# about 0.5 s a scene on one core (at most ~2 s): the two tests take about two minutes
@pytest.mark.parametrize("seed", seeded_cases(range(40)))
def test_random_scene_at_the_default_tolerance(seed):
    checks.check_scene(random_scene(seed))


@pytest.mark.parametrize("seed", seeded_cases(range(40, 52)))
def test_random_scene_at_a_tight_tolerance(seed):
    check_tight(random_scene(seed))


# 0.3 to 4 s a scene
@pytest.mark.parametrize("path", sorted(MODELS.glob("*.toml")), ids=lambda path: path.stem)
def test_a_shipped_scene_turned_backwards(path):
    """Every shipped scene with its initial pinion speed reversed, over its first 10 ms: on a
    switch at φp = 0 it starts in the set it turns into (docs/model.md section 6), and the
    two integrators agree from t = 0 on."""
    scene = turned_backwards(herringbone.load_scene(path), torques_too=False)
    experiment = dataclasses.replace(scene.experiment, output_interval=2e-5,
                                     stop_time=min(0.01, scene.experiment.stop_time))
    checks.check_scene(dataclasses.replace(scene, experiment=experiment))


# The seeded draw's speeds are positive (a sign drawn in it would change every seeded scene;
# the Hypothesis draw turns some of its scenes backwards); the same seeds turned backwards,
# both ways: 0.2 to 3 s a scene, but seed 6 braked (10 s: a train that loses contact, judged
# against the checked reference)
@pytest.mark.parametrize("torques_too", [True, False], ids=["torques_reversed", "braked"])
@pytest.mark.parametrize("seed", range(8))
def test_a_random_scene_turned_backwards(seed, torques_too):
    checks.check_scene(turned_backwards(random_scene(seed), torques_too))


# The draw rarely gives a train whose contact sets are all exact (symmetric halves, no lead
# error, no stagger, sharp edges), so the exponential method's exact segments see few random
# scenes: the same seeds made exact (scene_distribution.made_exact). 0.2 to 2.5 s a scene
# (4 s at the tight tolerance)
@pytest.mark.parametrize("seed", range(52, 68))
def test_a_random_train_made_exact_at_the_default_tolerance(seed):
    checks.check_scene(made_exact(random_scene(seed)))


@pytest.mark.parametrize("seed", range(68, 76))
def test_a_random_train_made_exact_at_a_tight_tolerance(seed):
    check_tight(made_exact(random_scene(seed)))


# A loose tolerance is what a sweep or a first look asks for: longer DOP853 steps for the
# grazing checks to see through, and event location tolerances a hundred times wider. The
# same rule as at 1e-7 and 1e-9 (a thousand times the tolerance); measured 4.5e-8 to 1.3e-4
# of the force scale on these 20. Seeds 0-299 as drawn and 0-149 made exact passed but for
# landing-amplified trains (seed 34 and 191, 1.1e-2) and four that cannot be judged. 0.1 to
# 4 s a scene
@pytest.mark.parametrize("seed", seeded_cases(range(12)))
def test_random_scene_at_a_loose_tolerance(seed):
    check_loose(random_scene(seed))


@pytest.mark.parametrize("seed", range(76, 84))
def test_a_random_train_made_exact_at_a_loose_tolerance(seed):
    check_loose(made_exact(random_scene(seed)))


def test_a_train_made_exact_runs_the_exponential_method_unless_slow():
    """made_exact takes away everything that keeps a contact set from being time-invariant but
    the edge ramps of a slow train: every set of a faster one is exact, so `auto` takes the
    exponential method there; a slow one keeps ramps, and sets that meet them are not exact."""
    for seed in range(52, 76):
        model = GearTrainModel(made_exact(random_scene(seed)))
        exact = exponential.exact_sets(model.system, model.mesh.period_table())[
            :, exponential.ALL_LOADED]
        slow = abs(model.scene.parameters["w0_pinion"]) < LOW_SPEED
        assert exact.all() != slow, (seed, exact)
        if not slow:
            assert choose_method(model) == "exponential"


def known_disagreement(scene, tight: bool) -> bool:
    """Whether a drawn scene is a regression scene whose disagreement is known: its strict
    xfail in test_regression_scene holds it, and Hypothesis's database, which replays every
    failing example first, would otherwise report it again on every run instead of drawing."""
    name = checks.regression_name(scene)
    return name in DISAGREEMENTS or name in (TIGHT_DISAGREEMENTS if tight
                                             else DEFAULT_DISAGREEMENTS)


# the draw as it comes, and made exact (scene_distribution.made_exact)
AS_DRAWN_OR_EXACT = pytest.mark.parametrize("exact", [False, True], ids=["as_drawn", "made_exact"])


@pytest.mark.slow
@AS_DRAWN_OR_EXACT
@settings(LONG)
@given(drawn=scenes())
def test_many_random_scenes_at_the_default_tolerance(drawn, exact):
    scene = made_exact(drawn) if exact else drawn
    assume(not known_disagreement(scene, tight=False))
    assume(checks.can_be_judged(scene, checks.REFERENCE_TOLERANCE, checks.DEFAULT_BOUND))
    checks.check_scene(scene)


@pytest.mark.slow
@AS_DRAWN_OR_EXACT
@settings(LONG)
@given(drawn=scenes())
def test_many_random_scenes_at_a_tight_tolerance(drawn, exact):
    scene = made_exact(drawn) if exact else drawn
    assume(not known_disagreement(scene, tight=True))
    assume(checks.can_be_judged(scene, 1e-12, checks.TIGHT_BOUND))
    check_tight(scene)


@pytest.mark.parametrize("path, tight", regression_cases())
def test_regression_scene(path, tight):
    scene = herringbone.load_scene(path)
    if tight:
        check_tight(scene, tight_bound(path.stem, scene))
    else:
        checks.check_scene(scene)


# --- the tools themselves ----------------------------------------------------------------------

@pytest.mark.parametrize("seed", range(20))
def test_a_saved_scene_loads_back_to_the_same_scene(seed, tmp_path):
    scene = random_scene(seed)
    path = checks.save_regression_scene(scene, "a test: nothing failed", tmp_path)
    loaded = herringbone.load_scene(path)
    assert path.read_text().startswith("# Found by tests/integrate/test_properties.py: a test")
    assert loaded.parameters == scene.parameters
    assert loaded.components == scene.components
    assert loaded.experiment == scene.experiment and loaded.inputs == scene.inputs
    assert checks.save_regression_scene(scene, "again", tmp_path) == path  # one file a scene
    assert checks.save_regression_scene(scene, "again", tmp_path) == path
    header = [line for line in path.read_text().splitlines() if line.startswith("#")]
    assert header == ["# Found by tests/integrate/test_properties.py: a test: nothing failed",
                      "# Also: again"]
    assert herringbone.load_scene(path).parameters == scene.parameters


def test_a_known_disagreement_is_known_when_drawn_again():
    """Every regression scene found by the draw loads back to the name it was saved under, so
    that the many-scene tests recognize a known disagreement when Hypothesis replays it."""
    found = [path for path in REGRESSION_SCENES if path.stem.startswith("found_")]
    known = set(DISAGREEMENTS) | set(TIGHT_DISAGREEMENTS) | set(DEFAULT_DISAGREEMENTS)
    assert found and known <= {p.stem for p in found}
    for path in found:
        scene = herringbone.load_scene(path)
        assert checks.regression_name(scene) == path.stem
        assert known_disagreement(scene, tight=True) == (
            path.stem in DISAGREEMENTS or path.stem in TIGHT_DISAGREEMENTS)
        assert known_disagreement(scene, tight=False) == (
            path.stem in DISAGREEMENTS or path.stem in DEFAULT_DISAGREEMENTS)


@pytest.mark.slow  # the reference's check of two landing trains: 25 s
def test_the_draw_judges_only_what_the_reference_resolves():
    """found_42d38d1d40 (no damping anywhere, 63 landings) is beyond what the reference
    resolves: its estimate over the run is 33 force scales. found_345d6831cc (66 landings,
    the reference good to 5e-7) is resolved, and the compiled integrator is judged there (a
    strict xfail of its own); so is a quiet seeded scene."""
    bound = (checks.REFERENCE_TOLERANCE, checks.DEFAULT_BOUND)
    assert not checks.resolved_by_the_reference(regression_scene("found_42d38d1d40"), *bound)
    assert checks.resolved_by_the_reference(regression_scene("found_345d6831cc"), *bound)
    assert checks.resolved_by_the_reference(random_scene(0), *bound)


def test_a_train_that_lands_is_judged_against_the_checked_reference():
    """found_1b70095ae3 (no damping at all, 14 landings in 7.8 ms): the per-step reference
    at 1e-12 lies 1.7e-6 of the force scale from reference_simulate's run, which checks its
    error over the run (estimated at 3.8e-8), beyond the tight bound; the compiled run at
    1e-9 lies 3.9e-8 from the checked one, and is judged against it."""
    scene = regression_scene("found_1b70095ae3")
    reference = checks.run_recorded(scene, "reference", 1e-12)
    assert reference.landings > 0
    judge = checks.force_judge(scene, 1e-12)
    assert force_error(reference.outputs, judge.outputs, scene) > checks.TIGHT_BOUND
    compiled = checks.run_recorded(scene, "compiled", checks.TIGHT_TOLERANCE)
    assert force_error(compiled.outputs, judge.outputs, scene) < 0.1 * checks.TIGHT_BOUND


def test_the_judge_keeps_the_samples_of_the_run_its_check_delivers():
    """found_1b70095ae3 lands, so the check of reference_simulate's run makes two runs or more
    at different step tolerances; the judge's samples are those of the run it delivers: the
    outputs computed afresh from every state kept are that run's outputs to the bit."""
    scene = regression_scene("found_1b70095ae3")
    _, check = checks.checked_reference(scene, 1e-12)
    judge = checks.force_judge(scene, 1e-12)
    assert check.runs >= 2 and judge.landings > 0
    fresh = GearTrainModel(scene)
    for k, sample in enumerate(judge.samples):
        outputs = fresh.outputs(*sample)
        assert all(outputs[name] == judge.outputs[name][k] for name in outputs), k


def test_a_train_that_rings_long_is_judged_against_reference_simulates_run():
    """found_b94916f10b never loses contact, and a mode at 2.6e5 rad/s that only the mesh
    damps (ζ 1.6e-4) rings some 2 600 radians: the per-step reference at 1e-10 lies 1.6e-5 of
    the force scale from reference_simulate's run, whose steps the ringing cuts to 3.8e-13,
    and DOP853 at 1e-11 lies 5e-8 from that run, which is the judge."""
    scene = regression_scene("found_b94916f10b")
    reference = checks.run_recorded(scene, "reference", checks.REFERENCE_TOLERANCE)
    assert reference.landings == 0
    judge = checks.force_judge(scene, checks.REFERENCE_TOLERANCE)
    assert force_error(reference.outputs, judge.outputs, scene) > 1e-5
    compiled = compiled_run(scene, 1e-11, "dop853")
    assert force_error(compiled, judge.outputs, scene) < 1e-7


@pytest.mark.slow  # the rule of the slow drawn tests, on four scenes: 19 s
def test_the_draw_judges_only_where_the_reference_holds_its_own_steps():
    """found_de62c18e83 (no damping at all, 17 landings): the recorded reference at 1e-10
    lies 4.8e-4 of the force scale from reference_simulate's checked run, beyond the bound
    1e-4, and no compiled run at 1e-7 is judged there. found_6be024234d (undamped wheel
    bearings, 24 landings; a fault of the compiled steps that the draw found) is judged: its
    recorded reference lies 3.5e-6 from the checked run; so is a seeded scene that never
    lands, and one that the reference refuses (sharp face edges at 1 rpm: it chatters) is
    left to check_scene, which passes a scene both integrators refuse."""
    bound = (checks.REFERENCE_TOLERANCE, checks.DEFAULT_BOUND)
    assert not checks.per_step_holds(regression_scene("found_de62c18e83"), *bound)
    assert checks.per_step_holds(regression_scene("found_6be024234d"), *bound)
    assert checks.per_step_holds(random_scene(0), *bound)
    chattering = herringbone.load_scene(MODELS / "low_speed.toml").with_parameters(
        edge_ramp=0.0, phase0=0.99)
    assert checks.per_step_holds(chattering, *bound)


def test_seeded_scenes_are_reproducible_and_cover_the_spans():
    """The same seed, the same scene; over 300 seeds the draws reach across the spans the
    issue names (and give low speeds an edge ramp, see scene_distribution.LOW_SPEED)."""
    assert random_scene(7).parameters == random_scene(7).parameters
    drawn = [random_scene(seed) for seed in range(300)]
    p = [s.parameters for s in drawn]
    teeth = [q["z_pinion"] for q in p]
    assert min(teeth) <= 10 and max(teeth) >= 58
    helix = np.degrees([q["beta"] for q in p])
    assert helix.min() < 7 and helix.max() > 38
    speeds = np.array([q["w0_pinion"] for q in p])
    assert speeds.min() < 2 and speeds.max() > 1500
    bearings = [q["c_brg_pinion_left"] for q in p if "c_brg_pinion_left" in q]
    assert min(bearings) < 3e8 and max(bearings) > 3e10
    assert any(q["zeta_mesh"] == 0.0 for q in p)
    assert any(q.get("h_brg_wheel_left") == 0.0 for q in p)
    assert any(not q["contact_loss"] for q in p) and np.mean([q["contact_loss"] for q in p]) > 0.7
    assert any(len(s.inputs.times) == 2 for s in drawn)
    assert any(abs(q["dbeta_left"]) > 2e-4 for q in p)
    assert any(q["stagger"] > 0 for q in p) and any(q["phase0"] > 0 for q in p)
    assert any(q["edge_ramp"] == 0.0 for q in p) and any(q["edge_ramp"] > 0.0 for q in p)
    assert all(q["edge_ramp"] > 0.0 for q in p if q["w0_pinion"] < LOW_SPEED)
    assert any(not s.has("bearings") for s in drawn) and any(not s.has("motor") for s in drawn)
    samples = [s.experiment.stop_time / s.experiment.output_interval for s in drawn]
    assert 99.9 < min(samples) and max(samples) < 300.1


@pytest.fixture(scope="module")
def clean_runs():
    """Seed 18: contact loss with free points, a torque step, 94 count changes; passes every
    check on today's integrators. (reference, compiled) runs of it."""
    scene = random_scene(18)
    assert scene.parameters["contact_loss"] and len(scene.inputs.times) == 2
    reference = checks.run_recorded(scene, "reference", checks.REFERENCE_TOLERANCE)
    compiled = checks.run_recorded(scene, "compiled", 1e-7)
    return reference, compiled


def corrupted(run, change):
    """A copy of the run (outputs and samples) with `change(outputs, samples)` applied."""
    copy = dataclasses.replace(run, outputs={k: v.copy() for k, v in run.outputs.items()},
                               samples=list(run.samples))
    change(copy.outputs, copy.samples)
    return copy


def first_sample(run, condition):
    return next(k for k, sample in enumerate(run.samples) if condition(run.model, *sample))


def test_the_checks_pass_the_clean_runs(clean_runs):
    reference, compiled = clean_runs
    for run in clean_runs:
        checks.outputs_finite(run, "run")
        checks.no_tension(run, "run")
        checks.momentum_follows_torques(run, "run")
    checks.forces_agree(compiled, reference, checks.DEFAULT_BOUND)
    checks.contact_counts_agree(compiled, reference, checks.DEFAULT_BOUND)


def test_each_check_fails_where_its_property_does(clean_runs):
    """Each check must see a run broken in its own property, by little more than its bound."""
    reference, compiled = clean_runs
    scale = reference.model.force_scale()
    has_free = first_sample(compiled, lambda m, x, cs, loaded: (loaded == 0).any())
    has_loaded = first_sample(compiled, lambda m, x, cs, loaded: (loaded != 0).any())

    def all_loaded(outputs, samples):
        state, contact_set, loaded = samples[has_free]
        samples[has_free] = (state, contact_set, np.ones_like(loaded))

    def all_free(outputs, samples):
        state, contact_set, loaded = samples[has_loaded]
        samples[has_loaded] = (state, contact_set, np.zeros_like(loaded))

    with pytest.raises(AssertionError, match="loaded point pulls"):
        checks.no_tension(corrupted(compiled, all_loaded), "compiled")
    with pytest.raises(AssertionError, match="free point is pressed"):
        checks.no_tension(corrupted(compiled, all_free), "compiled")
    with pytest.raises(AssertionError, match="F_brg_wheel_left"):
        checks.forces_agree(corrupted(compiled, lambda o, s: o["F_brg_wheel_left"].__setitem__(
            50, o["F_brg_wheel_left"][50] + 1.5 * checks.DEFAULT_BOUND * scale)),
            reference, checks.DEFAULT_BOUND)
    with pytest.raises(AssertionError, match="angular momentum"):
        checks.momentum_follows_torques(corrupted(compiled, lambda o, s: o["w_load"].__setitem__(
            70, o["w_load"][70] * (1 + 1e-7))), "compiled")
    with pytest.raises(AssertionError, match="not finite"):
        checks.outputs_finite(corrupted(compiled, lambda o, s: o["dte"].__setitem__(3, np.nan)),
                              "compiled")


def test_the_momentum_check_takes_rounding_against_the_terms_not_their_sum():
    """found_d74586bece: a free pair driven apart by equal torques (its flanks never touch), L
    near 3e-6 N·m·s while each gear's I·ω grows to 1.8 N·m·s. Its exact motion with a rounding
    of 4e-14 of the terms (what the reference's run carried, 2.1e-8 of L) passes; an error of
    1e-8 of a gear's momentum at one sample still fails."""
    scene = regression_scene("found_d74586bece")
    p = scene.parameters
    ratio = p["z_wheel"] / p["z_pinion"]
    motor, load = scene.inputs.at(0.0)
    assert len(scene.inputs.times) == 1 and motor == load and ratio == 1.0
    time = np.linspace(0.0, scene.experiment.stop_time, 101)
    pinion = p["w0_pinion"] + motor / p["I_pinion"] * time
    wheel = p["w0_pinion"] / ratio - load / p["I_wheel"] * time
    rounding = 4e-14 * np.abs(p["I_pinion"] * pinion).max() * np.sin(7.0 * time / time[-1])
    run = checks.RecordedRun(GearTrainModel(scene), {
        "time": time, "w_pinion": pinion + rounding / p["I_pinion"], "w_wheel": wheel})
    assert np.abs(p["I_pinion"] * pinion + p["I_wheel"] * wheel).max() < 1e-5
    checks.momentum_follows_torques(run, "run")
    with pytest.raises(AssertionError, match="angular momentum"):
        checks.momentum_follows_torques(corrupted(run, lambda o, s: o["w_wheel"].__setitem__(
            60, o["w_wheel"][60] * (1 + 1e-8))), "run")


def test_contact_counts_may_differ_only_at_a_switch(clean_runs):
    """A count off by one where every point carries more than the bound and φp is far from the
    set's ends fails; one at a sample where some point carries almost nothing passes."""
    reference, compiled = clean_runs
    hair = checks.DEFAULT_BOUND * reference.model.force_scale()

    def least_force(model, state, contact_set, loaded):
        return np.abs(checks.point_forces(model, state, contact_set)).min()

    firm = first_sample(reference, lambda *sample: least_force(*sample) > 10 * hair)
    with pytest.raises(AssertionError, match="not at a switch"):
        checks.contact_counts_agree(corrupted(compiled, lambda o, s: o["n_contacts"].__setitem__(
            firm, o["n_contacts"][firm] + 1)), reference, checks.DEFAULT_BOUND)
    near = first_sample(reference, lambda *sample: least_force(*sample) <= hair)
    checks.contact_counts_agree(corrupted(compiled, lambda o, s: o["n_contacts"].__setitem__(
        near, o["n_contacts"][near] + 1)), reference, checks.DEFAULT_BOUND)


def test_the_random_scene_benchmark_judges_only_against_a_truth_good_to_a_tenth_of_the_bound():
    """benchmarks/random_scenes.py counts a compiled run off the truth (the reference at 1e-12)
    only where the truth's own estimate of its error over the run is within a tenth of the
    bound: seed 7097's truth (1.3e-4) judges neither compiled run, 7066's (5.2e-7) the one at
    1e-7 (bound 1e-4) but not the one at 1e-9 (bound 1e-6), a run never checked (no landing:
    no estimate) both."""
    summary = benchmark_module("random_scenes").summary
    rows = [{"seed": seed, "error_reference_1e-10": 0.0, "error_compiled_1e-7": 2e-2,
             "error_compiled_1e-9": 2e-4, **estimate}
            for seed, estimate in ((7097, {"estimate_reference_1e-12": 1.3e-4}),
                                   (7066, {"estimate_reference_1e-12": 5.2e-7}), (1, {}))]
    lines = summary(rows, 1.0, "test").splitlines()
    judged = [line for line in lines if "within 0.1 of the bound" in line]
    assert judged[0].endswith("2 of 2 (seeds [7066, 1])"), judged
    assert judged[1].endswith("1 of 1 (seeds [1])"), judged
    assert any(line.endswith("2 of 3 (seeds [7097, 7066])") for line in lines), lines
