"""The compiled integrator (integrate/compiled_stepper.py): agreement with the reference,
convergence order across the switches, exact re-runs, and the implicit method on a stiff
scene."""
import dataclasses
import functools
import math

import numpy as np
import pytest
from helpers import MODELS, force_error, momentum_terms, regression_scene, shipped_run
from helpers import communication_run as run

import herringbone
from herringbone.integrate.compiled import walk
from herringbone.integrate.compiled_stepper import (
    DEFAULT_TOLERANCE,
    LEAST_RINGING_FACTOR,
    RINGING_CUT_FLOOR,
    CompiledStepper,
    compiled_entry,
    ringing_factor,
    runge_kutta_method,
    step_tolerance_factor,
)
from herringbone.integrate.contract import simulate_with, start_position
from herringbone.integrate.stepping import ScipyStepper
from herringbone.model.assembly import GearTrainModel


@pytest.fixture(scope="module")
def reference_model(reference_scene):
    return GearTrainModel(reference_scene)


@pytest.fixture(scope="module")
def tight_reference(reference_model):
    """scipy's DOP853 at 1e-12 over 0.02 s (five mesh periods, forty switches)."""
    return run(ScipyStepper(reference_model, 1e-12), 0.02, 1e-3)


@pytest.mark.parametrize("method, tolerance, bound", [
    ("dop853", DEFAULT_TOLERANCE, 1e-6),  # the FMU's default: the 1e-6
    ("dop853", 1e-7, 1e-6),
    ("dop853", 1e-10, 1e-8),
    ("radau", 1e-7, 1e-6),
    ("radau", 1e-10, 1e-8),
])
def test_agrees_with_the_reference(reference_model, tight_reference, method, tolerance, bound):
    fast = run(CompiledStepper(reference_model, tolerance, method), 0.02, 1e-3)
    assert force_error(fast, tight_reference, reference_model) <= bound
    assert np.array_equal(fast["n_contacts"], tight_reference["n_contacts"])


@pytest.mark.parametrize("communication_step", [1e-5, 1e-2])
def test_communication_step_does_not_change_the_answer(reference_model, tight_reference,
                                                       communication_step):
    """Stopping every 1e-5 s, or only every 1e-2 s, lands on the same trajectory."""
    fast = run(CompiledStepper(reference_model, 1e-9, "dop853"), 0.02, communication_step)
    every = int(round(1e-3 / communication_step)) if communication_step < 1e-3 else 1
    thinned = {n: v[every - 1::every] for n, v in fast.items()}
    reference = tight_reference if communication_step <= 1e-3 else {
        n: v[9::10] for n, v in tight_reference.items()}
    assert force_error(thinned, reference, reference_model) <= 1e-7


@pytest.mark.parametrize("method, order, steps", [("dop853", 8, [2.4e-5, 1.2e-5, 6e-6]),
                                                   ("radau", 5, [4e-6, 2e-6, 1e-6])])
def test_convergence_order_survives_the_switches(reference_model, method, order, steps):
    """Fixed steps (a loose tolerance, so the step is max_step except where a switch or a
    communication point cuts it short) over 0.01 s, twenty switches: a four times shorter
    step divides the error by about 4^order. The lever arms move with φp inside each step,
    because the pinion angle is part of the state every stage evaluates: nothing is frozen.
    The order is read over a factor of four because how each segment's last step is cut
    shifts the error constant by up to 2× from one step size to the next. The switches are
    located to rounding: the default places them to a hundredth of the tolerance, which at
    this tolerance of 1 would be all the error. Measured: 8.2 (DOP853, errors 4.6e-6 to
    5.2e-11), 5.0 (Radau IIA, 5.6e-7 to 5.5e-10)."""
    truth = run(CompiledStepper(reference_model, 1e-13, "dop853", max_step=5e-7), 0.01, 1e-3)
    errors = [force_error(run(CompiledStepper(reference_model, 1.0, method, max_step=h,
                                              event_time_tolerance=0.0),
                              0.01, 1e-3), truth, reference_model) for h in steps]
    assert errors[0] > errors[1] > errors[2] > 1e-11  # above the truth's own error
    measured = math.log(errors[0] / errors[2]) / math.log(steps[0] / steps[2])
    assert order - 0.5 <= measured <= order + 1.5, (errors, measured)


def test_simulate_samples_like_the_reference(reference_scene):
    """herringbone.simulate: the compiled run on reference_simulate's grid and torque table."""
    scene = reference_scene.with_inputs(table=[[0.0, 500.0, 1800.0], [0.004, 800.0, 1800.0]])
    fast = herringbone.simulate(scene, stop_time=0.01, output_interval=1e-4)
    reference = herringbone.reference_simulate(scene, stop_time=0.01, output_interval=1e-4,
                                               tolerance=1e-12)
    assert np.array_equal(fast["time"], reference["time"])
    assert force_error(fast, reference, GearTrainModel(scene)) <= 1e-6


def test_a_saved_position_reruns_identically(reference_model):
    stepper = CompiledStepper(reference_model, 1e-7)
    position = stepper.advance(start_position(reference_model, 500.0), 3.7e-3, (500.0, 1800.0))
    once = stepper.advance(position, 5e-3, (700.0, 1800.0))
    again = stepper.advance(position, 5e-3, (700.0, 1800.0))
    assert np.array_equal(once.state, again.state) and np.array_equal(once.outputs,
                                                                      again.outputs)


@pytest.mark.parametrize("method", ["dop853", "radau", "exponential"])
def test_run_to_calls_its_loop_past_numbas_dispatch_to_the_same_run(reference_model, method):
    """From its second call run_to calls the loop's compiled entry for its buffers' types
    (compiled_entry), not numba's dispatcher: the run is the dispatcher's to the bit."""
    direct, dispatched = (CompiledStepper(reference_model, 1e-7, method) for _ in range(2))
    runs = [stepper.start(start_position(reference_model, 500.0))
            for stepper in (direct, dispatched)]
    for k in range(1, 41):
        direct.run_to(runs[0], k * 1e-4, (500.0, 1800.0))
        dispatched.loop = walk.advance
        dispatched.run_to(runs[1], k * 1e-4, (500.0, 1800.0))
    assert direct.loop is not walk.advance and runs[0].events > 2
    assert np.array_equal(runs[0].state, runs[1].state)
    assert np.array_equal(runs[0].outputs, runs[1].outputs)


def test_a_stepper_that_has_run_pickles_and_its_copy_runs_alike(reference_model):
    """The compiled entry run_to keeps is code of this process: a stepper pickled or copied
    after it has run (a sweep's period map sent to a worker) leaves it behind, and the copy
    finds its own and runs to the bit as the original."""
    import copy
    import pickle

    stepper = CompiledStepper(reference_model, 1e-7)
    runs = [stepper.start(start_position(reference_model, 500.0))]
    stepper.run_to(runs[0], 1e-3, (500.0, 1800.0))
    for twin in (pickle.loads(pickle.dumps(stepper)), copy.deepcopy(stepper)):
        assert twin.loop is walk.advance
        runs.append(twin.start(stepper.position(runs[0])))
        twin.run_to(runs[-1], 3e-3, (500.0, 1800.0))
        twin.run_to(runs[-1], 4e-3, (500.0, 1800.0))
        assert twin.loop is not walk.advance
    stepper.run_to(runs[0], 3e-3, (500.0, 1800.0))
    stepper.run_to(runs[0], 4e-3, (500.0, 1800.0))
    for run_ in runs[1:]:
        assert np.array_equal(run_.state, runs[0].state)


def test_a_function_numba_has_no_entry_for_is_called_as_it_is():
    def plain(value):
        return value

    assert compiled_entry(plain, (1.0,)) is plain
    assert compiled_entry(walk.advance, (1.0,)) is walk.advance


def test_contact_loss_and_regain_agree_with_the_reference(reference_scene):
    """Light load and a large helix error: points lose and regain contact. The crossings are
    located on steps of the method itself, so agreement holds as for smooth running."""
    scene = reference_scene.with_parameters(dbeta_left=4e-4, dbeta_right=-4e-4).with_inputs(
        M_motor=20.0, M_load=72.0)
    model = GearTrainModel(scene)
    reference = run(ScipyStepper(model, 1e-12), 0.01, 1e-4, torques=(20.0, 72.0))
    fast = run(CompiledStepper(model, 1e-9, "dop853"), 0.01, 1e-4, torques=(20.0, 72.0))
    full = len(model.mesh.contact_set(0, 0))
    assert reference["n_contacts"].min() < full - 1  # the case really loses contact
    assert force_error(fast, reference, model) <= 1e-6
    assert np.array_equal(fast["n_contacts"], reference["n_contacts"])


def stiff_scene(reference_scene, bearing_damping):
    """Bearings of 1e11 N/m under bodies a tenth as heavy: modes up to ~550 kHz."""
    return reference_scene.with_parameters(
        **{f"c_brg_{g}_{s}": 1e11 for g in ("pinion", "wheel") for s in ("left", "right")},
        **{f"h_brg_{g}_{s}": bearing_damping for g in ("pinion", "wheel")
           for s in ("left", "right")},
        m_pinion=0.0929436, m_wheel=1.20455, I_pinion=2.18927e-5, I_wheel=0.00367713)


def test_stiff_lightly_damped_modes_are_followed_explicitly(reference_scene):
    """With the reference bearing damping the stiff modes ring (ζ ≈ 1 %) and carry ~2 % of the
    static force in the bearing reactions: every method must follow them, so "auto" keeps the
    explicit method among the Runge-Kutta ones (the scene is symmetric, so "auto" itself
    takes the exponential method, tests/integrate/test_exponential.py), whose stability
    bound then matches the accuracy it needs anyway."""
    model = GearTrainModel(stiff_scene(reference_scene, 2000.0))
    assert runge_kutta_method(model.eigenvalues()) == "dop853"
    stepper = CompiledStepper(model, 1e-7, "dop853")
    reference = run(ScipyStepper(model, 1e-10), 2e-3, 1e-4)
    assert force_error(run(stepper, 2e-3, 1e-4), reference, model) <= 1e-5


def test_the_steps_are_held_to_the_undamped_modes_of_the_free_flight_too():
    """tests/regression/found_6be024234d.toml: the mesh damps the engaged train (its least
    damped fast mode at ζ ≈ 0.004, a ringing factor of 0.19), but the wheel bearings are
    undamped, and between a lift-off and a landing their 33 to 72 kHz modes ring on: the steps
    take the tolerance times LEAST_RINGING_FACTOR. (Its compiled run lay 1.8e-4 of the force
    scale off the reference at 1e-7 before, beyond the property checks' bound 1e-4, and 2.8e-5
    now: test_properties.py's test_regression_scene.) A train held in contact never flies free,
    and its engaged modes alone set the steps."""
    scene = regression_scene("found_6be024234d")
    model = GearTrainModel(scene)
    modes = model.eigenvalues()
    assert ringing_factor(modes) == pytest.approx(0.193, abs=0.005)
    assert step_tolerance_factor(model, modes) == LEAST_RINGING_FACTOR
    assert CompiledStepper(model, 1e-7).step_tolerance == pytest.approx(
        1e-7 * LEAST_RINGING_FACTOR, rel=1e-12)
    held = GearTrainModel(dataclasses.replace(scene, given={**scene.given,
                                                            "contact_loss": False}))
    assert step_tolerance_factor(held, held.eigenvalues()) == pytest.approx(0.193, abs=0.005)


def test_the_ringing_cut_stops_where_rounding_begins():
    """found_b94916f10b rings nearly undamped (ζ 1.6e-4), so its steps take the tolerance
    times LEAST_RINGING_FACTOR: at 1e-11 that would be 3e-14, where DOP853's error estimate
    meets rounding and the run failed at its first step. The cut stops at RINGING_CUT_FLOOR,
    and the run holds; a tolerance asked for below the floor is kept as asked."""
    scene = regression_scene("found_b94916f10b")
    model = GearTrainModel(scene)
    assert step_tolerance_factor(model, model.eigenvalues()) == LEAST_RINGING_FACTOR
    stepper = CompiledStepper(model, 1e-11, "dop853")
    assert stepper.step_tolerance == RINGING_CUT_FLOOR
    simulate_with(stepper, scene, stop_time=1e-3)
    assert stepper.accepted_steps > 0
    assert CompiledStepper(model, 5e-14, "dop853").step_tolerance == 5e-14


def test_implicit_method_steps_over_overdamped_stiff_modes(reference_scene):
    """Bearing damping of 2e5 N·s/m makes the stiff modes overdamped, with eigenvalues up to
    ~2e7 1/s: the explicit method needs ~3 600 steps in this millisecond for stability alone,
    at any tolerance (measured; ten times the damping makes it 37 000). The Runge-Kutta
    choice is Radau IIA ("auto" takes the exponential method, the scene being symmetric),
    which steps by accuracy (about 500 steps) and agrees with DOP853 run at 1e-11."""
    model = GearTrainModel(stiff_scene(reference_scene, 2e5))
    assert runge_kutta_method(model.eigenvalues()) == "radau"
    stepper = CompiledStepper(model, 1e-7, "radau")
    explicit = CompiledStepper(model, 1e-11, "dop853")
    truth = run(explicit, 1e-3, 1e-4)
    assert force_error(run(stepper, 1e-3, 1e-4), truth, model) <= 1e-6
    assert stepper.accepted_steps < explicit.accepted_steps / 5


def test_compiled_cache_is_keyed_on_every_kernel_file(tmp_path, monkeypatch):
    """numba checks only a function's own file; walk.advance compiles dop853.step and the
    model's equations into itself, and counting.py sets how they are compiled, so a change to
    any of those files must move the whole cache, and a change elsewhere must not."""
    import shutil

    from herringbone.compiling import cache, sources

    copy = tmp_path / "herringbone"
    shutil.copytree(sources.ROOT, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(sources, "ROOT", copy)
    assert {"model/equations.py", "compiling/counting.py", "integrate/compiled/dop853.py"} <= {
        path.relative_to(copy).as_posix() for path in sources.kernel_files()}
    digests = []
    for changed in ("model/scene.py", "model/equations.py", "compiling/counting.py",
                    "integrate/compiled/dop853.py"):
        cache.package_digest.cache_clear()
        digests.append(cache.package_digest())
        (copy / changed).write_text((copy / changed).read_text() + "\n# changed\n")
    cache.package_digest.cache_clear()
    digests.append(cache.package_digest())
    assert digests[0] == digests[1]  # the scene's loader holds no kernel
    assert len(set(digests[1:])) == 4
    cache.package_digest.cache_clear()  # the real package's digest again for later tests
    monkeypatch.undo()


def test_every_kernel_is_cached_by_its_source_text():
    """A kernel module that defined its kernels before the locator was in place (one that did
    not import compiling.counting first) would be cached beside its file, by numba's own
    locator: an FMU, unpacked to a new folder at every start, would compile it every time."""
    import importlib

    from herringbone.compiling import cache, sources

    for name in sources.kernel_modules():
        importlib.import_module(name)
    kernels = cache.kernels()
    assert {kernel.py_func.__module__.rpartition(".")[2] for kernel in kernels} >= {
        "equations", "dop853", "radau", "exponential", "walk", "variational"}
    assert all(isinstance(kernel._cache._impl.locator, cache.SourceTextCacheLocator)
               for kernel in kernels)


@pytest.mark.parametrize("scene_name", ["reference", "torsional", "contact_loss"])
def test_packed_system_unpacks_to_the_same_arrays(scene_name):
    """The compiled loop takes the System packed into two arrays; unpacked it must be the
    System field for field, exactly: values, shapes, entry types, and arrays as views of the
    buffers (a field added to the declaration and not to unpack_system's readers, or read from
    the wrong buffer or with the wrong shape, fails here)."""
    from herringbone.model.equations import System, pack_system, unpack_system

    system = GearTrainModel(herringbone.load_scene(MODELS / f"{scene_name}.toml")).system
    floats, ints = pack_system(system)
    assert floats.dtype == np.float64 and ints.dtype == np.int64
    unpacked = unpack_system(floats, ints)
    assert type(unpacked) is System
    for name, original, copy in zip(System._fields, system, unpacked, strict=True):
        if isinstance(original, np.ndarray):
            assert copy.shape == original.shape, name
            assert copy.dtype.kind == original.dtype.kind, name
            assert np.array_equal(copy, original), name
            assert np.shares_memory(copy, floats) or np.shares_memory(copy, ints), name
        else:
            assert type(copy) is type(original) and copy == original, name


def test_packing_refuses_a_field_of_the_wrong_shape(reference_model):
    """pack_system checks every field against System's declaration: a vector given as a matrix,
    or two fields that disagree on a size, are refused, not packed into a wrong layout."""
    from herringbone.model.equations import pack_system

    system = reference_model.system
    with pytest.raises(ValueError, match="mass"):
        pack_system(system._replace(mass=system.mass[:, None]))
    with pytest.raises(ValueError, match="coordinates"):
        pack_system(system._replace(rigid_rotation=system.rigid_rotation[:-1]))


@pytest.mark.parametrize("speed, acceleration, angle, target", [
    (150.0, 1e3, 0.012, 0.015),  # forward: reaches the interval's end (0.015 rad)
    (150.0, -4e4, 0.012, 0.015),  # forward, slowing hard
    (-150.0, 2e3, 0.002, 0.0)])  # backward: falls to the interval's start
def test_phase_event_prediction_is_the_quadratic_root(reference_model, speed, acceleration,
                                                      angle, target):
    """DOP853 aims a step at the predicted phase event, ending 1e-4 of it past: the prediction
    must be far closer than that where φp moves as a quadratic over one step."""
    from herringbone.integrate.compiled.walk import PREDICTION_MARGIN, phase_event_ahead

    system = reference_model.system
    n = reference_model.size
    state, rate = np.zeros(2 * n), np.zeros(2 * n)
    state[system.pinion], state[n + system.pinion] = angle, speed
    rate[n + system.pinion] = acceleration
    # 0.5·a·t² + v·t − (target − angle) = 0, the root reached first
    roots = np.roots([0.5 * acceleration, speed, angle - target])
    exact = min(r.real for r in roots if abs(r.imag) < 1e-300 and r.real > 0)
    predicted = phase_event_ahead(system, state, rate, 0.015)
    assert abs(predicted - exact) <= 1e-3 * PREDICTION_MARGIN * exact
    state[n + system.pinion] = 0.0
    assert phase_event_ahead(system, state, rate, 0.015) == math.inf


# --- issue 15: separation and re-engagement, undamped stiff modes -------------------------------


def scene_run(scene, tolerance, stop_time=None):
    """The compiled integrator through a scene's torque table, with the debug contact check on
    (a point in tension or penetrating without load inside any step fails the run)."""
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, tolerance, check_contact=True)
    return simulate_with(stepper, scene, stop_time=stop_time)


@functools.cache
def tightest_reference(scene_source):
    """The reference at 1e-12 of a regression scene, once per session (over a minute for the
    undamped one)."""
    return herringbone.reference_simulate(regression_scene(scene_source.split(":")[1]),
                                          tolerance=1e-12)


@pytest.mark.parametrize("scene_source, tolerance, bound", [
    # measured: 2.6e-8 and 4e-10 (0.12 and 4.2e-10 before every point was loaded by its sign)
    ("regression:regain_after_separation", DEFAULT_TOLERANCE, 1e-6),
    ("regression:regain_after_separation", 1e-9, 1e-8),
    # measured: 2.4e-5 and 2.4e-7 (1.8e-4 and 2.0e-6 with steps at h·|λ|max = 3.5)
    ("regression:undamped_stiff_bearings", DEFAULT_TOLERANCE, 1e-4),
    ("regression:undamped_stiff_bearings", 1e-9, 1e-6),
])
def test_regression_scenes_agree_with_the_reference(scene_source, tolerance, bound):
    scene = regression_scene(scene_source.split(":")[1])
    reference = tightest_reference(scene_source)
    fast = scene_run(scene, tolerance)
    assert force_error(fast, reference, GearTrainModel(scene)) <= bound
    assert np.array_equal(fast["n_contacts"], reference["n_contacts"])


def test_every_point_regains_load_after_a_complete_separation():
    """models/separation.toml: the train unloaded at 4 ms lifts off entirely and lands again
    and again. Every point takes load as its approach turns positive (the debug check inside
    every step), the runs agree, and the count of loaded points goes to zero and back to the
    no-loss law's full set."""
    scene = herringbone.load_scene(MODELS / "separation.toml")
    reference = herringbone.reference_simulate(scene, tolerance=1e-12)
    fast = scene_run(scene, DEFAULT_TOLERANCE)
    assert force_error(fast, reference, GearTrainModel(scene)) <= 1e-6
    assert np.array_equal(fast["n_contacts"], reference["n_contacts"])
    separated = np.flatnonzero(fast["n_contacts"] == 0)
    assert separated.size and fast["n_contacts"][separated[-1]:].max() == 6
    assert fast["F_mesh"].min() == 0.0 and fast["F_mesh"][separated[-1]:].max() > 0.0


@pytest.mark.parametrize("method", ["exponential", "dop853", "radau"])
def test_landings_of_every_point_at_once_are_located_in_few_trials(method):
    """models/jump_resonance.toml lifts off and lands 34 times in 10 ms, every point of the
    set at once, so a landing brackets several crossings within the event time tolerance.
    The location ends there with a trial just before the bracket's end; it used to take that
    same trial again and again, up to MAX_LOCATION_TRIALS: 10.7 trial steps an event with
    the exponential method, 4.5 with DOP853, 14.9 with Radau IIA (measured now: 2.8, 1.8,
    1.5)."""
    position = shipped_run("jump_resonance", method, 0.01)
    assert position.events > 200
    assert position.trial_steps <= 4.5 * position.events


def test_a_location_bisects_once_newton_has_not_closed_in():
    """walk.location_estimate: a Newton estimate inside the bracket is taken for the first
    NEWTON_LOCATION_TRIALS trials, one outside it never; then the bracket's middle, which
    halves it at every trial. An event function that rounding holds at zero over a stretch
    keeps Newton at the bracket's low end, and trials aimed just past it crept up by the event
    time tolerance each: sixty of them left 1.5e-6 s of a 7e-6 s step open
    (tests/regression/found_aaeb0efe2e.toml on a modal form it no longer gets)."""
    from herringbone.integrate.compiled import walk

    low, high = 5.4955e-6, 7.0e-6
    assert walk.location_estimate(0, 6e-6, low, high) == 6e-6
    assert walk.location_estimate(walk.NEWTON_LOCATION_TRIALS - 1, low, low, high) == low
    assert walk.location_estimate(3, 8e-6, low, high) == 0.5 * (low + high)
    assert walk.location_estimate(walk.NEWTON_LOCATION_TRIALS, 6e-6, low, high) == \
        0.5 * (low + high)
    for trials in range(walk.NEWTON_LOCATION_TRIALS, walk.MAX_LOCATION_TRIALS):
        low = walk.location_estimate(trials, low, low, high)  # the event lies above it
    assert high - low <= 1e-14 * high  # the tightest a location asks: 2e-14 of the step


def test_a_contact_event_is_located_by_newton_on_the_approach():
    """models/contact_loss.toml has 6 000 events a simulated second, nearly all of them points
    lost or regained. A contact event is located as a phase event is: its first estimate is
    the zero of the cubic through the point's approach and approach rate at the step's ends
    (walk.first_estimate), the next ones Newton's on the approach rate at each trial
    (walk.event_slope). DOP853 locates them in 2.62 trial steps an event over 20 ms, where
    secants after the cubic took 3.32 and the chord's zero 4.30."""
    position = shipped_run("contact_loss", "dop853", 0.02)
    assert position.events > 100
    assert position.trial_steps <= 2.9 * position.events


def test_a_contact_events_slope_is_its_approach_rate():
    """Newton's method steps by walk.event_slope, which for a contact must be the time
    derivative of the point's approach: along DOP853's motion of contact_loss at 5 ms, the
    central difference of every point's approach over ±1 µs agrees with it within 0.1 % of
    the largest slope (measured: 1.7e-5 of it)."""
    from herringbone.integrate.compiled import walk
    from herringbone.model import equations

    scene = herringbone.load_scene(MODELS / "contact_loss.toml")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7, "dop853")
    torques, delta = scene.inputs.at(0.0), 1e-6
    run_ = stepper.start(start_position(model, torques[0]))
    approaches, sets = [], []
    for end in (0.005 - delta, 0.005, 0.005 + delta):
        stepper.run_to(run_, end, torques)
        interval = int(run_.place[0])
        sets.append((interval, tuple(run_.loaded)))
        count, points = int(stepper.counts[interval]), stepper.tables[interval]
        approach = np.empty(stepper.tables.shape[2])
        equations.approaches(model.system, points, count, run_.state, approach)
        approaches.append(approach[:count])
        if end == 0.005:
            segment = walk.segment_of(model.system, equations.PeriodTable(*stepper.mesh),
                                      interval, run_.loaded, torques, -1)
            workspace, state = walk.Workspace(*run_.workspace), run_.state.copy()
            slopes = np.array([walk.event_slope(model.system, segment, state, workspace,
                                                walk.Event.CONTACT + i) for i in range(count)])
    assert sets[0] == sets[1] == sets[2]  # (no event in between: one segment throughout)
    difference = (approaches[2] - approaches[0]) / (2.0 * delta)
    assert np.abs(slopes).max() > 0.0
    assert np.allclose(slopes, difference, rtol=0.0, atol=1e-3 * np.abs(slopes).max())


@pytest.mark.parametrize("damping_ratio", [0.0, 0.0016, 0.05, 0.3])
@pytest.mark.parametrize("tolerance", [1e-7, 1e-9])
def test_step_bound_keeps_every_mode_true_to_its_eigenvalue(damping_ratio, tolerance):
    """At the bound each mode's numerical eigenvalue ln R(h·λ)/h is within its allowance
    (EIGENVALUE_ERROR_PER_TOLERANCE·tol of its decay rate plus tol of its frequency), and
    the bound is tight: a tenth longer, the fastest mode is not (unless the cap of 3.5/|λ|max
    holds it first)."""
    from herringbone.integrate.compiled.dop853 import stability_function
    from herringbone.integrate.compiled_stepper import (
        EIGENVALUE_ERROR_PER_TOLERANCE,
        EXPLICIT_STEP_BOUND,
        explicit_step_bound,
    )

    frequency = 6.8e5
    fastest = frequency * complex(-damping_ratio, math.sqrt(1.0 - damping_ratio ** 2))
    modes = np.array([fastest, fastest.conjugate(), 0.3 * fastest, 0.0])
    h = explicit_step_bound(modes, tolerance)

    def error_over_allowance(step):
        mode = modes[0]
        error = abs(np.log(stability_function(step * mode)) / step - mode)
        return error / (EIGENVALUE_ERROR_PER_TOLERANCE * tolerance * -mode.real
                        + tolerance * abs(mode))

    assert error_over_allowance(h) <= 1.0 + 1e-6  # the bisection ends on the allowed side
    assert (h * frequency == pytest.approx(EXPLICIT_STEP_BOUND)
            or error_over_allowance(1.1 * h) > 1.0)
    if damping_ratio == 0.0:  # an undamped mode is held by the tolerance alone
        assert h * frequency < (1.2 if tolerance == 1e-7 else 0.8)


@pytest.mark.parametrize("method", ["dop853", "exponential", "radau"])
def test_balanced_torques_keep_the_angular_momentum(reference_scene, method):
    """With M_load = u·M_motor nothing outside the train changes its angular momentum
    referred to the pinion: every method must keep it over 0.5 s at the default tolerance
    (DOP853 and Radau IIA, its Newton iteration taken to rounding, to 1e-12 of itself, the
    exact segments to rounding)."""
    result = herringbone.simulate(reference_scene, stop_time=0.5, output_interval=1e-3,
                                  method=method)
    momentum = np.sum(momentum_terms(reference_scene, result), axis=0)
    assert np.ptp(momentum) / abs(momentum[0]) < 1e-10


def test_radau_at_the_tightest_tolerance_is_no_runaway():
    """Radau IIA (order 5) follows the undamped scene's 13 kHz ringing at 1e-12 in about 177
    steps per h·|λ|max, past DOP853's runaway bound of 100: its own grows below the default
    tolerance (1 778 there), so the run completes, and it agrees with DOP853 there."""
    scene = herringbone.load_scene(MODELS / "undamped.toml")
    radau = herringbone.simulate(scene, stop_time=0.01, output_interval=1e-4, method="radau",
                                 tolerance=1e-12)
    dop853 = herringbone.simulate(scene, stop_time=0.01, output_interval=1e-4,
                                  method="dop853", tolerance=1e-12)
    assert force_error(radau, dop853, GearTrainModel(scene)) <= 1e-9


def test_simulate_stops_a_runaway_with_a_message_naming_the_torques(reference_scene):
    """A load torque of 1e19 N·m flings the train ever faster, its contact events ever denser:
    simulate ran without end (the FMU's doSteps were bounded, its runs were not). Each of its
    compiled calls now has the FMU's budget of steps, and the message says what to check."""
    runaway = reference_scene.with_inputs(M_motor=500.0, M_load=1e19)
    with pytest.raises(herringbone.StepBudgetExceeded,
                       match=r"the train runs away; check the torques M_motor = 500 and "
                             r"M_load = 1e\+19 N\.m$"):
        herringbone.simulate(runaway, stop_time=0.01, output_interval=1e-3)


# integer_overlap's mesh stiffness is the same in every contact set, so its exact solution is
# the static one: F_mesh stays at the static mesh force (the reference's to 1e-12)
STATIC_SCENE = "integer_overlap"


def static_force_error(method: str, tolerance: float) -> float:
    """The largest |F_mesh − the static mesh force| over 10 ms of STATIC_SCENE by `method`,
    over the force scale."""
    scene = herringbone.load_scene(MODELS / f"{STATIC_SCENE}.toml")
    model = GearTrainModel(scene)
    result = herringbone.simulate(scene, stop_time=0.01, output_interval=1e-4,
                                  tolerance=tolerance, method=method)
    return float(np.abs(result["F_mesh"] - model.static_mesh_force()).max()
                 / model.force_scale())


@pytest.mark.parametrize("method", ["dop853", "exponential", "radau"])
def test_a_static_solution_stays_static(method):
    """integer_overlap's exact solution is static through its switches: each method keeps its
    mesh force at 1e-9 (measured 1.1e-14 to 1.5e-14; Radau IIA's Jacobian of rounding noise
    once gave 2.2e-7)."""
    assert static_force_error(method, 1e-9) < 3e-9


def test_auto_says_why_it_did_not_take_the_exponential_method(reference_scene):
    """lead_error's sets all change as their points travel: "auto" takes DOP853 and says how
    many sets are exact; with the overdamped stiff bearings of
    test_implicit_method_steps_over_overdamped_stiff_modes on top it takes Radau IIA and says
    why; a method asked for by name is not explained."""
    lead = herringbone.load_scene(MODELS / "lead_error.toml")
    auto = CompiledStepper(GearTrainModel(lead), 1e-7)
    assert auto.method == "dop853"
    assert auto.method_note.startswith("0 of 4 contact sets are exact, where the exponential "
                                       "method needs at least 50% (a lead error")
    stiff = CompiledStepper(GearTrainModel(stiff_scene(lead, 2e5)), 1e-7)
    assert stiff.method == "radau"
    assert stiff.method_note.startswith("the train's fastest modes are overdamped")
    assert CompiledStepper(GearTrainModel(lead), 1e-7, "dop853").method_note == ""


def test_a_method_that_does_otherwise_than_its_name_says_so(reference_scene):
    """A mesh 80 times the reference's stiffness makes the modal forms too ill-conditioned to
    take at 1e-10 (exponential.condition_limit): `auto` then takes DOP853, and an explicit
    "exponential" steps every set by DOP853; method_note says so (the run's summary shows it),
    where the plain scene says nothing."""
    stiff = GearTrainModel(reference_scene.with_parameters(c_point=2e10))
    auto = CompiledStepper(stiff, 1e-10)
    assert auto.method == "dop853"
    assert auto.method_note.startswith("the exponential method's modal forms refused (a fast "
                                       "eigenvalue's condition number is")
    assert auto.method_note.endswith("): dop853 instead")
    explicit = CompiledStepper(stiff, 1e-10, "exponential")
    assert explicit.method == "exponential"
    assert "such sets stepped by DOP853" in explicit.method_note
    assert CompiledStepper(GearTrainModel(reference_scene), 1e-7).method_note == ""
