"""A run sampled in one compiled call (walk.advance handed the sample times,
CompiledStepper.sample) against one call per sample time (CompiledStepper.run_to, the same loop
handed none, how simulate sampled before): the same outputs to the bit, through simulate_with
with and without a callback, on scenes with a torque step, contact loss and separation, with
DOP853 and with the exponential method where no segment is exact; where segments are exact,
samples taken inside the steps of a run that does not stop for them, within the method's own
error of one that does; the same error, raised after the same samples, where a run fails; and
the one call, compiled without numba's reference counts, frees what it allocates and keeps what
it is given."""

import numba
import numpy as np
import pytest
from helpers import MODELS
from helpers.memory_probe import assert_kept, probe, run_probe

import herringbone
from herringbone.integrate.compiled_stepper import (
    SAMPLES_PER_CALL,
    CompiledStepper,
    StepBudgetExceeded,
)
from herringbone.integrate.contract import (
    IntegrationError,
    SamplingStepper,
    input_pieces,
    output_times,
    simulate_with,
    start_position,
)
from herringbone.model.assembly import GearTrainModel

# (scene, simulated s): each span holds more than SAMPLES_PER_CALL samples at 1e-4 s, so a
# callback's run takes several calls; torque_step's torques jump at 5 ms
SCENES = [("reference", 0.015), ("torque_step", 0.015), ("contact_loss", 0.015),
          ("separation", 0.015)]
OUTPUT_INTERVAL = 1e-4


def one_call_per_sample(stepper, scene, stop_time, output_interval, on_sample=None):
    """simulate_with's run as it sampled before: run_to to every sample time, the outputs named
    and stored one by one (and handed to on_sample), run_to to the end of each piece of the
    input table."""
    model = stepper.model
    times = output_times(stop_time, output_interval)
    results = {name: np.empty(len(times)) for name in model.output_names}

    def store(k, outputs):
        for name, value in outputs.items():
            results[name][k] = value
        if on_sample is not None:
            on_sample(times[k], outputs)

    position = start_position(model, scene.inputs.at(0.0)[0])
    changes = [t for t in scene.inputs.change_times() if 0.0 < t < stop_time]
    for start, end in zip([0.0] + changes, changes + [stop_time]):
        run, torques = stepper.start(position), scene.inputs.at(start)
        for k in [k for k, t in enumerate(times) if position.time <= t < end]:
            stepper.run_to(run, times[k], torques)
            store(k, model.named_outputs(run.outputs))
        stepper.run_to(run, end, torques)
        position = stepper.position(run)
    store(len(times) - 1, model.outputs(position.state, position.segment.contact_set,
                                        position.segment.loaded))
    return dict(time=times, **results)


@pytest.mark.parametrize("name, stop_time, method", [
    *((name, stop_time, "dop853") for name, stop_time in SCENES),
    ("contact_loss", 0.015, "exponential"),  # no exact set: DOP853's steps
])
def test_one_call_per_piece_samples_the_same_to_the_bit(name, stop_time, method):
    scene = herringbone.load_scene(MODELS / f"{name}.toml")
    stepper = CompiledStepper(GearTrainModel(scene), 1e-7, method)
    assert isinstance(stepper, SamplingStepper)
    before = one_call_per_sample(stepper, scene, stop_time, OUTPUT_INTERVAL)
    steps = stepper.accepted_steps
    sampled = simulate_with(stepper, scene, stop_time, OUTPUT_INTERVAL)
    assert stepper.accepted_steps - steps == steps  # the same steps, taken again
    called = []
    watched = simulate_with(stepper, scene, stop_time, OUTPUT_INTERVAL,
                            on_sample=lambda t, outputs: called.append((t, outputs)))
    assert len(before["time"]) > 2 * SAMPLES_PER_CALL
    assert list(sampled) == list(watched) == list(before)
    for name_ in before:
        assert np.array_equal(sampled[name_], before[name_]), name_
        assert np.array_equal(watched[name_], before[name_]), name_
        assert sampled[name_].flags.c_contiguous
    # the callback saw every sample once, in order, with the stored values
    assert [t for t, _ in called] == list(before["time"])
    assert all(outputs[key] == watched[key][k] for k, (_, outputs) in enumerate(called)
               for key in outputs)
    # the physics moved: the mesh force is not a constant (a run that stood still would pass)
    assert np.ptp(sampled["F_mesh"]) > 0.0


def straight_through(stepper, scene, stop_time, output_interval):
    """simulate_with's run without its samples: run_to to where each of its calls ends (every
    SAMPLES_PER_CALL-th sample time, the end of each piece of the input table). Returns
    (the outputs at the end, accepted steps)."""
    times = output_times(stop_time, output_interval)
    position, steps = start_position(stepper.model, scene.inputs.at(0.0)[0]), \
        stepper.accepted_steps
    for start, end in input_pieces(scene, stop_time):
        run, torques = stepper.start(position), scene.inputs.at(start)
        piece = times[(position.time <= times) & (times < end)]
        for stop in [*piece[SAMPLES_PER_CALL::SAMPLES_PER_CALL], end]:
            stepper.run_to(run, stop, torques)
        position = stepper.position(run)
    return position.outputs, stepper.accepted_steps - steps


@pytest.mark.parametrize("name", ["reference", "torque_step", "separation"])
def test_exact_segments_take_their_samples_inside_their_steps(name):
    """The exponential method where its segments are exact: the sampled run takes the steps,
    and ends on the state, of a run that does not stop at the samples (to the bit), and its
    samples, from the exact solution inside those steps, are within the method's own error
    (where it places the events: 1.3e-10 of the force scale on the reference scene) of a run
    that stops at each; with a callback, the same to the bit."""
    scene = herringbone.load_scene(MODELS / f"{name}.toml")
    stepper = CompiledStepper(GearTrainModel(scene), 1e-7, "exponential")
    model = stepper.model
    stopping = one_call_per_sample(stepper, scene, 0.015, OUTPUT_INTERVAL)
    stopping_steps = stepper.accepted_steps
    end_outputs, steps = straight_through(stepper, scene, 0.015, OUTPUT_INTERVAL)
    before = stepper.accepted_steps
    sampled = simulate_with(stepper, scene, 0.015, OUTPUT_INTERVAL)
    assert stepper.accepted_steps - before == steps < stopping_steps
    slots = dict(model.output_layout)
    assert all(sampled[name_][-1] == end_outputs[slots[name_]] for name_ in model.output_names)
    forces = [name_ for name_ in model.output_names if name_.startswith("F_")]
    error = max(np.abs(sampled[name_] - stopping[name_]).max() for name_ in forces)
    assert error < 1e-9 * model.force_scale()
    assert np.array_equal(sampled["n_contacts"], stopping["n_contacts"])
    watched = simulate_with(stepper, scene, 0.015, OUTPUT_INTERVAL, on_sample=lambda t, o: None)
    assert all(np.array_equal(sampled[name_], watched[name_]) for name_ in sampled)
    assert np.ptp(sampled["F_mesh"]) > 0.0


def test_a_sample_at_a_switch_stands_where_its_own_time_puts_it():
    """high_speed's switches fall on its sample grid (a mesh period of 1e-4 s at constant
    speed). At a tolerance of 1e-2 a switch is located to 1.2e-9 s, and the sampled run took
    the sample at 36 ms, which lay between the crossing and the bracket's end, from the contact
    set before it: n_contacts 4 where the run stopping there finds 6, F_mesh 0.42 of the force
    scale off. A sample within the location's window is now taken only where the event has
    not crossed at its own time: the same contact counts as the run that stops at each sample,
    the forces within 1e-5 of the force scale (each 6.3e-6 from scipy's DOP853 at 1e-10)."""
    scene = herringbone.load_scene(MODELS / "high_speed.toml")
    stepper = CompiledStepper(GearTrainModel(scene), 1e-2, "exponential")
    stopping = one_call_per_sample(stepper, scene, 0.04, 1e-3)
    sampled = simulate_with(stepper, scene, 0.04, 1e-3)
    assert np.array_equal(sampled["n_contacts"], stopping["n_contacts"])
    forces = [name for name in stepper.model.output_names if name.startswith("F_")]
    error = max(np.abs(sampled[name] - stopping[name]).max() for name in forces)
    assert error < 1e-5 * stepper.model.force_scale()


def failing_run(sample_in_one_call, motor_torque):
    """The torsional scene at a motor torque (N·m) that ends it, sampled every 1e-4 s to 5 ms
    either in one call (CompiledStepper.sample) or by run_to per sample: (the error raised, the
    sample times handed out before it)."""
    scene = herringbone.load_scene(MODELS / "torsional.toml")
    stepper = CompiledStepper(GearTrainModel(scene), 1e-7, "dop853")
    run = stepper.start(start_position(stepper.model, 500.0))
    times, torques = output_times(5e-3, 1e-4)[1:], (motor_torque, 1800.0)
    seen = []
    with pytest.raises(IntegrationError) as error:
        if sample_in_one_call:
            rows = np.empty((len(times), len(run.outputs)))
            stepper.sample(run, times, rows, 5e-3, torques,
                           on_sample=lambda t, outputs: seen.append(t))
        else:
            for t in times:
                stepper.run_to(run, t, torques)
                seen.append(t)
    return error.value, seen


@pytest.mark.parametrize("motor_torque, failure", [
    (1e80, "the pinion left its contact interval unseen"),  # (the check after each stretch)
    (1e300, "the step size fell below the time's resolution"),  # (walk.advance's own status)
])
def test_a_failing_run_fails_alike_after_the_same_samples(motor_torque, failure):
    one_call, seen_one_call = failing_run(True, motor_torque)
    per_sample, seen_per_sample = failing_run(False, motor_torque)
    assert str(one_call) == str(per_sample)
    assert type(one_call) is type(per_sample)
    assert seen_one_call == seen_per_sample
    assert failure in str(one_call)


def test_the_step_budget_bounds_the_whole_call():
    """A budget of the steps half a run takes stops it there, with StepBudgetExceeded naming
    the sample time it fell short of, the rows before it written as run_to writes them."""
    scene = herringbone.load_scene(MODELS / "reference.toml")
    stepper = CompiledStepper(GearTrainModel(scene), 1e-7, "dop853")
    start = start_position(stepper.model, 500.0)
    times, torques = output_times(4e-3, 1e-4)[1:], scene.inputs.at(0.0)
    rows = np.empty((len(times), stepper.model.output_layout_size))
    stepper.sample(stepper.start(start), times, rows, 4e-3, torques)
    steps = stepper.accepted_steps
    run, budget_rows = stepper.start(start), np.full_like(rows, np.nan)
    seen = []
    with pytest.raises(StepBudgetExceeded) as error:
        stepper.sample(run, times, budget_rows, 4e-3, torques, max_steps=steps // 2,
                       on_sample=lambda t, outputs: seen.append((t, outputs["F_mesh"])))
    written = int(np.isfinite(budget_rows[:, 0]).sum())
    assert 0 < written < len(times)
    # the callback was handed every row written, before the error
    assert [t for t, _ in seen] == list(times[:written])
    slot = dict(stepper.model.output_layout)["F_mesh"]
    assert [force for _, force in seen] == list(rows[:written, slot])
    assert np.array_equal(budget_rows[:written], rows[:written])
    assert f"short of t = {times[written]:.9g} s" in str(error.value)
    assert times[written - 1] <= run.time < times[written]


def test_rows_of_the_wrong_shape_are_refused():
    scene = herringbone.load_scene(MODELS / "reference.toml")
    stepper = CompiledStepper(GearTrainModel(scene), 1e-7, "dop853")
    run = stepper.start(start_position(stepper.model, 500.0))
    with pytest.raises(ValueError, match="rows"):
        stepper.sample(run, np.array([1e-4, 2e-4]), np.empty((2, 3)), 3e-4, (500.0, 1800.0))
    assert run.time == 0.0


@pytest.mark.parametrize("times, culprit", [
    # as np.arange's last time can land, a rounding past the end it was meant to stop at
    (np.array([1e-4, np.nextafter(3e-4, 1.0)]), r"times\[1\] = 0.00030000000000000003 s is past"),
    (np.array([2e-4, 1e-4]), r"times\[1\] = 0.0001 s falls below times\[0\]"),
    (np.array([1e-4, np.nan, 2e-4]), r"times\[1\] is not a number"),
])
def test_sample_times_past_the_end_or_falling_are_refused_before_a_step(times, culprit):
    """A run stops at `end`: a row for a time past it would be left as it was, whatever an
    empty array held (a test that sampled np.arange's times to its own end read one such row
    as a force of -0.076 N in one CI run of six)."""
    scene = herringbone.load_scene(MODELS / "reference.toml")
    stepper = CompiledStepper(GearTrainModel(scene), 1e-7, "exponential")
    run = stepper.start(start_position(stepper.model, 500.0))
    rows = np.full((len(times), len(run.outputs)), np.nan)
    with pytest.raises(ValueError, match=culprit):
        stepper.sample(run, times, rows, 3e-4, scene.inputs.at(0.0))
    assert run.time == 0.0 and np.isnan(rows).all()


# test_compiled_memory's check, of one call of CompiledStepper.sample through 40 sample times
PROBE = probe(
    setup="""
rows = np.empty((40, len(run.outputs)))
stepper.sample(run, np.array([1e-4]), rows[:1], 1e-4, torques)
times = 1e-4 + interval * np.arange(1, 41)
""", body="""
before = rtsys.get_allocation_stats()
stepper.sample(run, times, rows, times[-1] + interval, torques)
after = rtsys.get_allocation_stats()
extra = {"sampled": bool(np.ptp(rows, axis=0).max() > 0.0)}
""", given="times, rows")


@pytest.mark.parametrize("scene, method, interval", [
    ("reference", "exponential", 2e-4),
    ("contact_loss", "dop853", 2e-4),
    ("stiff_bearings", "radau", 2e-6),  # Radau IIA allocates its Newton arrays at every step
])
def test_one_call_frees_what_it_allocates_and_keeps_what_it_was_given(scene, method, interval):
    figures = run_probe(PROBE, scene, method, interval)
    assert figures["arrays"] >= 12 and figures["sampled"], figures
    assert_kept(figures)
    if method == "radau":
        assert figures["allocated"] > 0  # the check sees the allocations it counts


@pytest.mark.parametrize("stop_time, output_interval, last_three", [
    (0.3, 0.1, [0.1, 0.2, 0.3]),          # 3·0.1 is 0.30000000000000004, a rounding past
    (0.05, 0.007, [0.042, 0.049, 0.05]),  # stop_time added where h does not divide it
])
def test_the_samples_end_at_the_stop_time_itself(stop_time, output_interval, last_three):
    """A run samples up to its stop time inclusive and no further: the last sample time is
    the stop time, exactly, so that no run integrates a rounding past it."""
    times = output_times(stop_time, output_interval)
    assert times[-1] == stop_time
    np.testing.assert_allclose(times[-3:], last_three, rtol=1e-12)
    assert np.all(np.diff(times) > 0.0)


def test_every_drive_hands_the_loop_arguments_of_the_same_types(monkeypatch):
    """run_to (the FMU's step, no samples), sample, and the stepper's advance with a callback
    and advance_sampled into an array (herringbone run's and simulate's) call walk.advance with
    arguments of the same numba types: one compiled loop a method serves them all, where
    another type anywhere would compile the loop again (minutes on two cores)."""
    from herringbone.integrate.compiled import walk

    loop, types_seen = walk.advance, []

    def recorded(*arguments):
        types_seen.append(tuple(numba.typeof(argument) for argument in arguments))
        return loop(*arguments)

    monkeypatch.setattr(walk, "advance", recorded)
    scene = herringbone.load_scene(MODELS / "reference.toml")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7)
    torques = scene.inputs.at(0.0)
    start = start_position(model, torques[0])
    run = stepper.start(start)
    stepper.run_to(run, 1e-4, torques)
    stepper.sample(run, [2e-4, 3e-4], np.empty((2, len(run.outputs))), 4e-4, torques)
    stepper.advance(start, 1e-3, torques, [2e-4, 5e-4], lambda t, outputs: None)
    times = np.arange(100) * 1e-5
    stepper.advance_sampled(start, 1e-3, torques, times, np.empty((100, len(run.outputs))))
    # run_to, sample, advance (2 times: one call), advance_sampled (100 times: two calls)
    assert len(types_seen) == 5 and len(set(types_seen)) == 1, set(types_seen)
