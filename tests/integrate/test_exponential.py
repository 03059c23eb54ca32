"""The exponential method (integrate/compiled/exponential.py): its modal form against scipy's
matrix exponential, which contact sets it takes exactly, agreement with the scipy reference on
the reference scene and on scenes that lose and regain contact, exact re-runs from a saved
position, and DOP853's results, bit for bit, where no segment is exact."""
import contextlib
import math
import warnings
from typing import NamedTuple

import numpy as np
import pytest
import scipy.linalg
from helpers import (
    FORCES,
    MODELS,
    REGRESSION,
    compiled_run,
    force_error,
    regression_scene,
    shipped_drive,
    shipped_run,
)
from helpers import communication_run as run

import herringbone
from herringbone.integrate.compiled import exponential
from herringbone.integrate.compiled_stepper import (
    CompiledStepper,
    StepBudgetExceeded,
    choose_method,
)
from herringbone.integrate.contract import simulate_with, start_position
from herringbone.integrate.stepping import ScipyStepper
from herringbone.model import equations
from herringbone.model.assembly import GearTrainModel


def model_of(name):
    return GearTrainModel(herringbone.load_scene(MODELS / f"{name}.toml"))



@pytest.fixture(scope="module")
def reference_model():
    return model_of("reference")


@pytest.fixture(scope="module")
def tight_reference(reference_model):
    """scipy's DOP853 at 1e-12 over 0.02 s (five mesh periods, forty switches)."""
    return run(ScipyStepper(reference_model, 1e-12), 0.02, 1e-3)


def scales_of(model):
    force = model.force_scale()
    return np.concatenate([model.state_scales(), [force * model.geometry.radius_pinion,
                                                  force * model.geometry.radius_wheel, 1.0]])


def numbered(tables):
    """ExactTables of the same shapes and dtypes as `tables`, every entry a different number
    (the buffers are laid out by the header of sizes, not by the counts in the tables)."""
    count, fields = 0, []
    for value in tables:
        numbers = np.arange(count, count + np.size(value)).reshape(np.shape(value))
        count += np.size(value)
        fields.append(numbers.astype(np.asarray(value).dtype)
                      * (1 + 1j if np.iscomplexobj(value) else 1))
    return exponential.ExactTables(*fields)


@pytest.mark.parametrize("scene_name", ["reference", "staggered", "jump_resonance"])
def test_packed_tables_unpack_to_views_of_the_same_arrays(scene_name):
    """The kernels take the tables as pack_tables' three buffers and unpack them at every
    call (unpack_tables, by offsets into the buffers). Unpacked, tables whose every entry
    differs must be those tables again, field by field, and their scratch fields views into
    the buffers, which the kernels write and later calls read: a field laid out at the wrong
    offset or shape fails here, not as a wrong trajectory. Scenes: every set exact; some
    (staggered: tilt rows, sets not exact); forms with no fast mode (jump_resonance's
    flights)."""
    tables = numbered(CompiledStepper(model_of(scene_name), 1e-7, "exponential").exact_tables)
    buffers = exponential.pack_tables(tables)
    unpacked = exponential.unpack_tables(buffers)
    assert type(unpacked) is exponential.ExactTables
    for name, original, copy in zip(exponential.ExactTables._fields, tables, unpacked,
                                    strict=True):
        assert np.shape(copy) == np.shape(original), name
        assert np.array_equal(copy, original), name
    for name in ("start", "start_slow", "start_fast", "start_size", "modal_slow",
                 "modal_fast", "grid_fast", "aimed_fast", "series"):
        view = getattr(unpacked, name)
        assert any(np.shares_memory(view, buffer) for buffer in buffers), name


def modal_step_error(form, a, b, start, h, state_scales):
    """R·diag(exp(T_slow·h), e^{Λh})·L·X of a modal form (modal_form's R, L, Λ, T_slow) of
    the system (a, b) from the augmented start X, against scipy's expm of the augmented
    matrix: the largest difference in the state's scales."""
    right, left, rates, slow = form
    size = a.shape[0]
    augmented = np.zeros((size + 3, size + 3))
    augmented[:size, :size], augmented[:size, size:] = a, b
    modal = left @ start
    modal[len(slow):] *= np.exp(rates[len(slow):] * h)
    modal[:len(slow)] = scipy.linalg.expm(slow * h) @ modal[:len(slow)]
    exact = scipy.linalg.expm(augmented * h) @ start
    return np.abs(((right @ modal).real - exact)[:size] / state_scales).max()


@pytest.mark.parametrize("variant", [exponential.ALL_LOADED, exponential.NONE_LOADED])
def test_modal_form_is_the_matrix_exponential(reference_model, variant):
    """R·diag(exp(T_slow·h), e^{Λh})·L·X against scipy's expm of the augmented matrix, at
    step sizes from a hundredth of the fastest period to a mesh period, in the state's
    scales: within 1e-9 (measured 1e-12 to 4e-11)."""
    model = reference_model
    lengths, counts, tables = model.mesh.period_table()
    loaded = np.full(counts[0], 1.0 if variant == exponential.ALL_LOADED else 0.0)
    a, b = exponential.linear_system(model.system, tables[0], counts[0], loaded)
    form = exponential.modal_form(a, b, scales_of(model))
    size = a.shape[0]
    start = np.concatenate([np.random.default_rng(1).normal(size=size) * model.state_scales(),
                            [500.0, 1800.0, 1.0]])
    start[model.pinion], start[size // 2 + model.pinion] = 0.1, 157.0
    for h in (1e-6, 1e-4, 4e-3):
        assert modal_step_error(form, a, b, start, h, model.state_scales()) <= 1e-9


def test_the_modes_the_tilt_sees_are_left_out(reference_model):
    """An exact segment starts where the tilt stays zero (variant_of), so the modes that the
    tilt's rows see have no part in it (unseen_by_tilt leaves them out of the tables). Of every
    contact set of the reference scene in both variants: as many modes are left out as there
    are tilt rows (a pair counts twice), the tables keep the others, and a random state moved
    where the rows' products vanish has coordinates on those left out below 1e-10 of those on
    the modes kept, the relative tilt a segment may start with at a tolerance of 1e-7
    (measured 2e-12, the modal form's rounding)."""
    model = reference_model
    lengths, counts, tables = model.mesh.period_table()
    scales = scales_of(model)
    exact_tables = CompiledStepper(model, 1e-7, "exponential").exact_tables
    rng = np.random.default_rng(7)
    for interval in range(len(lengths)):
        for variant in (exponential.ALL_LOADED, exponential.NONE_LOADED):
            loaded = np.full(counts[interval], 1.0 if variant == exponential.ALL_LOADED else 0.0)
            a, b = exponential.linear_system(model.system, tables[interval], counts[interval],
                                             loaded)
            rows = exponential.tilt_rows(model.system, a)
            right, left, rates, slow = exponential.modal_form(a, b, scales)
            kept, weights = exponential.kept_modes(rates[len(slow):])
            fast = len(slow) + kept
            free = exponential.unseen_by_tilt(rows, right[:a.shape[0], fast], scales)
            assert weights[~free].sum() == len(rows) > 0
            assert exact_tables.fast_count[interval * exponential.VARIANTS + variant] == free.sum()
            scaled, scaled_rows = rng.normal(size=a.shape[0]), rows * scales[:a.shape[0]]
            scaled -= np.linalg.pinv(scaled_rows) @ (scaled_rows @ scaled)
            state = np.concatenate([scaled, [1.0, 1.0, 1.0]]) * scales
            modal = np.abs(left[fast] @ state)
            assert modal[~free].max() <= 1e-10 * modal[free].max()


def test_every_direction_of_the_tilt_space_reads_on_the_tables_rows():
    """variant_of measures a segment's start against the tilt rows the tables hold: a state
    whose part in the tilt's space is z (in its scales) must read at least |z|/√rows on one
    of them, or the modes the tilt sees are dropped while they still move. So the rows, in
    the scales, are orthonormal (no singular value below 1). On regain_after_separation,
    whose halves differ by 5 µm, the flight's tilt space takes in the gears' swing on their
    bearings, and rows merely scaled, nearly parallel there (smallest singular value 7e-7),
    read 8e-10 for a swing of 1e-3 of the scales."""
    model = GearTrainModel(regression_scene("regain_after_separation"))
    tables = CompiledStepper(model, 1e-6, "exponential").exact_tables
    scales = model.state_scales()
    counts = tables.tilt_count[np.flatnonzero(tables.valid)]
    assert counts.max() > 0
    for place in np.flatnonzero(tables.valid):
        rows = tables.tilt_rows[place, :tables.tilt_count[place]] * scales
        if len(rows):
            assert np.linalg.svd(rows, compute_uv=False).min() >= 1.0 - 1e-9
            assert np.allclose(rows @ rows.T, np.eye(len(rows)), atol=1e-9)


def test_a_swing_the_tilt_sees_keeps_a_flight_off_the_exact_form():
    """regain_after_separation by the exponential method at 1e-6: the flight's exact form
    drops the modes the tilt sees, the gears' swing on their bearings among them, and a
    segment went on by it while that swing was 1e-3 of its scales: the wheel's bearing forces
    read 0 for the rest of the flight, 1.8e-4 of the force scale off DOP853 at 1e-11 (DOP853
    at 1e-6: 5.1e-7)."""
    scene = regression_scene("regain_after_separation")
    truth = compiled_run(scene, 1e-11, "dop853")
    run = compiled_run(scene, 1e-6, "exponential")
    assert force_error(run, truth, scene) <= 5e-6


def test_a_set_with_a_lead_error_is_not_exact_where_contact_can_be_lost():
    """An exact segment finds and certifies every point's landing or lift-off on one approach
    without lead error (exponential._approach), so where contact can be lost no set whose
    points carry one is exact, in flight (no point loaded) as much as loaded: lead_error's
    sets are exact in neither variant, and without contact loss its flights do not arise and
    its loaded sets stay refused by their lead error slope."""
    scene = herringbone.load_scene(MODELS / "lead_error.toml")
    model = GearTrainModel(scene)
    assert model.contact_loss
    assert not exponential.exact_sets(model.system, model.mesh.period_table()).any()
    engaged = GearTrainModel(scene.with_parameters(contact_loss=False))
    assert not exponential.exact_sets(engaged.system, engaged.mesh.period_table())[
        :, exponential.ALL_LOADED].any()
    free = GearTrainModel(scene.with_parameters(dbeta_left=0.0, dbeta_right=0.0))
    assert exponential.exact_sets(free.system, free.mesh.period_table())[
        :, exponential.NONE_LOADED].all()


def test_a_flight_with_a_lead_error_finds_its_landing():
    """found_79a4848a80 (seeded scene 287: a lead error on both halves, edge ramps, contact
    lost and regained) by the exponential method at 1e-7: its flights were taken as exact,
    and one went on past a landing at 2.84 ms that its lead error brought about, 0.88 of the
    force scale off DOP853 at 1e-11. Now stepped by DOP853 there, it lies 2.6e-8 from it."""
    scene = regression_scene("found_79a4848a80")
    truth = compiled_run(scene, 1e-11, "dop853")
    run = compiled_run(scene, 1e-7, "exponential")
    assert force_error(run, truth, scene) <= 1e-6


@pytest.mark.parametrize("name", ["stiff_bearings", "undamped", "wide_face"])
def test_a_tight_tolerance_leaves_the_exact_segments_exact(name):
    """A call's end lies inside a segment, whose tilt must read zero there for the next call
    to go on exactly (variant_of). At 1e-10 the tilt rows' rounding entries on the pinion
    angle (4e-15, times an angle of hundreds of its scale mid-interval) read 1e-12 against a
    bound of 2.5e-14 on stiff_bearings, and the bound fell below the modal round trip's own
    rounding of an undamped train's tilt (5e-15 against 3e-15): the segments went on by
    DOP853: 41 230, 4 488 and 668 steps in 20 ms against 52, 62 and 44 at 1e-7. The exact
    method's steps hardly depend on the tolerance (the same from 1e-7 to 1e-10; below about
    1e-11 wide_face's forms, of condition 195, are refused): at 1e-10 at most twice those at
    1e-7, and the tilt rows have exact zeros where no power of A
    reaches."""
    steps = {}
    for tolerance in (1e-7, 1e-10):
        model, _, stepper, _ = shipped_drive(name, "exponential", 0.02, 1e-3, tolerance)
        steps[tolerance] = stepper.accepted_steps
    assert steps[1e-10] <= 2 * steps[1e-7]
    assert not stepper.exact_tables.tilt_rows[:, :, model.system.pinion].any()


def test_the_tables_of_a_huge_torque_warn_of_no_overflow(reference_scene):
    """A load torque of 1e300 N·m is finite, so allowed (its run fails, with a message); it
    scales the state to some 1e300. The tilt's rows and the modes' columns are normalized
    after their largest entry, not by norms whose squares overflow: building the tables
    warns of nothing, which a host would print before the FMU's message, and the modes the
    tilt sees are the reference scene's."""
    usual = CompiledStepper(GearTrainModel(reference_scene), 1e-7, "exponential")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        huge = CompiledStepper(GearTrainModel(reference_scene.with_inputs(M_load=1e300)),
                               1e-7, "exponential")
    assert np.array_equal(huge.exact_tables.fast_count, usual.exact_tables.fast_count)


@pytest.mark.parametrize("name, exact", [
    ("reference", True), ("stiff_bearings", True), ("torsional", True), ("separation", True),
    # a lever arm that reaches the forces: the halves do not mirror each other (staggered), a
    # lead error slope (lead_error), edge ramps load a point gradually (low_speed)
    ("staggered", False), ("lead_error", False), ("low_speed", False)])
def test_which_contact_sets_are_exact(name, exact):
    """A set is exact where the loaded points' stiffness and lead error are constant along
    the face and their lever arms cancel (module docstring); where one is, the frozen linear
    system's derivative equals the model's at a state where the tilt is zero, whatever the
    axial travel."""
    model = model_of(name)
    stepper = CompiledStepper(model, 1e-7, "exponential")
    valid = stepper.exact_tables.valid.reshape(-1, exponential.VARIANTS)[:,
                                                                        exponential.ALL_LOADED]
    assert bool(valid.all()) is exact
    if not exact:
        return
    lengths, counts, tables = model.mesh.period_table()
    position = start_position(model, 500.0)
    state = position.state.copy()
    for interval in range(len(lengths)):
        loaded = np.ones(counts[interval])
        a, b = exponential.linear_system(model.system, tables[interval], counts[interval],
                                         loaded)
        for travel_angle in (0.0, 0.5 * lengths[interval], lengths[interval]):
            state[model.pinion] = travel_angle
            contact_set = model.mesh.contact_set(0, interval)
            true = model.derivative(state, contact_set, loaded, 500.0, 1800.0)
            frozen = a @ state + b @ [500.0, 1800.0, 1.0]
            assert np.abs((frozen - true) / model.state_scales()).max() <= 1e-9 * np.abs(
                true / model.state_scales()).max()


def test_agrees_with_the_reference(reference_model, tight_reference):
    """Within 1e-7 of the force scale of scipy's DOP853 at 1e-12 over forty switches, with the
    same contact counts."""
    fast = run(CompiledStepper(reference_model, 1e-7, "exponential"), 0.02, 1e-3)
    assert force_error(fast, tight_reference, reference_model) <= 1e-7
    assert np.array_equal(fast["n_contacts"], tight_reference["n_contacts"])


def test_accuracy_across_switches_is_set_by_the_event_time_tolerance(reference_model,
                                                                     tight_reference):
    """Between switches the method is exact, so its error is where it places the switches:
    first order in the event time tolerance δt (a switch δt late leaves about |λ|max·δt of
    the force that switched), down to the reference's own error at the default (1e-2 of the
    step tolerance over |λ|max, 1.2e-14 s here). Measured over forty switches: 7.8e-6,
    1.2e-7, 7.8e-10 at δt = 1e-9, 1e-11, 1e-13 s; 1.3e-10 at the default."""
    errors = [force_error(run(CompiledStepper(reference_model, 1e-7, "exponential",
                                              event_time_tolerance=tolerance), 0.02, 1e-3),
                          tight_reference, reference_model)
              for tolerance in (1e-9, 1e-11, 1e-13)]
    assert errors[0] > 20.0 * errors[1] > 400.0 * errors[2]
    default = run(CompiledStepper(reference_model, 1e-7, "exponential"), 0.02, 1e-3)
    assert force_error(default, tight_reference, reference_model) <= 1e-9


@pytest.mark.parametrize("source", ["models:separation", "models:from_rest",
                                    "regression:regain_after_separation"])
def test_contact_loss_scenes_agree_with_the_reference(source):
    """Scenes where the whole train lifts off and lands again (its points all at once: no
    lead error), with the debug contact check on: within 1e-6 of the force scale of the
    reference at 1e-12, the same contact counts."""
    folder, name = source.split(":")
    scene = herringbone.load_scene((MODELS if folder == "models" else REGRESSION)
                                   / f"{name}.toml")
    model = GearTrainModel(scene)
    stop_time = min(scene.experiment.stop_time, 0.02)
    reference = herringbone.reference_simulate(scene, stop_time=stop_time, tolerance=1e-12)
    stepper = CompiledStepper(model, 1e-7, "exponential", check_contact=True)
    fast = simulate_with(stepper, scene, stop_time=stop_time)
    assert force_error(fast, reference, model) <= 1e-6
    assert np.array_equal(fast["n_contacts"], reference["n_contacts"])


def test_a_saved_position_reruns_identically(reference_model):
    """The FMU's rollback: a run from a saved position repeats the run that went on from it,
    bit for bit (nothing of the run lives outside its position)."""
    stepper = CompiledStepper(reference_model, 1e-7, "exponential")
    saved = stepper.advance(start_position(reference_model, 500.0), 0.0037, (500.0, 1800.0))
    first = stepper.advance(saved, 0.0091, (500.0, 1800.0))
    again = stepper.advance(saved, 0.0091, (500.0, 1800.0))
    assert np.array_equal(first.state, again.state)
    assert first.segment.contact_set.index == again.segment.contact_set.index


def test_without_an_exact_segment_it_is_dop853_bit_for_bit():
    """On a scene none of whose sets is exact (staggered halves) every segment is stepped by
    DOP853, with DOP853's bound and controller: the same results to the last bit."""
    model = model_of("staggered")
    runs = [run(CompiledStepper(model, 1e-7, method), 0.005, 1e-3)
            for method in ("dop853", "exponential")]
    assert all(np.array_equal(runs[0][name], runs[1][name]) for name in runs[0])


def test_auto_takes_it_where_enough_sets_are_exact():
    """auto: the exponential method where the scene's contact sets are all exact, or half of
    them (low_speed: its edge ramps vary the sets where a point enters or leaves) and DOP853
    would be taken; DOP853 or Radau IIA by their rule where fewer are (staggered: a quarter)."""
    assert choose_method(model_of("reference")) == "exponential"
    assert choose_method(model_of("stiff_bearings")) == "exponential"
    assert choose_method(model_of("low_speed")) == "exponential"
    assert choose_method(model_of("staggered")) == "dop853"


def test_overdamped_stiff_modes_cost_it_nothing(reference_model):
    """Bearings of 1e11 N/m with 2e5 N·s/m of damping under light bodies: eigenvalues up to
    ~2e7 1/s, for which DOP853 needs thousands of steps a millisecond for stability alone and
    Radau IIA hundreds for accuracy. The exponential method takes them exactly: it agrees
    with DOP853 at 1e-11 and takes fewer steps than Radau IIA."""
    scene = reference_model.scene.with_parameters(
        **{f"c_brg_{g}_{s}": 1e11 for g in ("pinion", "wheel") for s in ("left", "right")},
        **{f"h_brg_{g}_{s}": 2e5 for g in ("pinion", "wheel") for s in ("left", "right")},
        m_pinion=0.0929436, m_wheel=1.20455, I_pinion=2.18927e-5, I_wheel=0.00367713)
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7, "exponential")
    implicit = CompiledStepper(model, 1e-7, "radau")
    truth = run(CompiledStepper(model, 1e-11, "dop853"), 1e-3, 1e-4)
    assert force_error(run(stepper, 1e-3, 1e-4), truth, model) <= 1e-6
    run(implicit, 1e-3, 1e-4)
    assert stepper.accepted_steps < implicit.accepted_steps


def test_exact_steps_are_rejected_only_where_the_modes_swing_the_pinion_speed():
    """An exact step is accepted only where it is certified to keep the pinion speed's sign
    (keeps_sign), and the loop grows the step until one is not. On the reference scene the
    fast modes swing the speed by 0.6 to 12 % of its 157 rad/s: every step is certified, none
    rejected. After torque_step's tenfold torque step (5 ms) the torsional mode swings it by
    40 to 160 %: long steps fail the certificate (measured: 25 rejected in 50 ms, 0.4 a
    located event), and Run.rejected_steps counts them."""
    assert shipped_run("reference", "exponential", 0.02, 1e-3).rejected_steps == 0
    before_step = shipped_run("torque_step", "exponential", 0.005, 1e-3)
    swinging = shipped_run("torque_step", "exponential", 0.05, 1e-3)
    assert before_step.rejected_steps == 0
    assert swinging.rejected_steps >= 10


def test_an_exact_step_is_judged_by_what_its_certificate_says():
    """walk.control_exact_step: a certified step lets the next grow fourfold, unless the step
    before it was rejected. One whose phase events are sure but not a point's approach is
    rejected and tried at a quarter, not below DOP853's step bound (the floor), at which it
    is accepted as DOP853's would be; one whose phase events are unsure goes on shrinking to
    TURN_BACK_FLOOR of the floor."""
    from herringbone.integrate.compiled.walk import TURN_BACK_FLOOR, StepPlan, control_exact_step

    certified, sure, unsure = exponential.CERTIFIED, exponential.PHASE_SURE, exponential.UNSURE
    floor = 1e-5
    plan = StepPlan(4e-4, 4e-4, False, False)
    assert control_exact_step(certified, plan, floor, False) == (True, 1.6e-3)
    assert control_exact_step(certified, plan, floor, True) == (True, 4e-4)
    assert control_exact_step(sure, plan, floor, False) == (False, 1e-4)
    assert control_exact_step(unsure, plan, floor, False) == (False, 1e-4)
    short = StepPlan(2e-5, 2e-5, False, False)
    assert control_exact_step(sure, short, floor, False) == (False, floor)
    at_floor = StepPlan(floor, floor, False, False)
    assert control_exact_step(sure, at_floor, floor, True) == (True, floor)
    assert control_exact_step(unsure, at_floor, floor, False) == (False, 0.25 * floor)
    finest = StepPlan(TURN_BACK_FLOOR * floor, TURN_BACK_FLOOR * floor, False, False)
    assert control_exact_step(unsure, finest, floor, False) == (True, 4 * finest.h_step)
    # cut short: keeps what the loop wanted, untried, or grows from its own if that is more
    landing = StepPlan(1e-4, 8e-4, True, False)
    assert control_exact_step(certified, landing, floor, False) == (True, 8e-4)
    assert control_exact_step(certified, landing, floor, True) == (True, 8e-4)
    aimed = StepPlan(5e-4, 8e-4, False, True)
    assert control_exact_step(certified, aimed, floor, False) == (True, 2e-3)


def test_the_step_size_an_exact_run_carries_stays_near_the_steps_it_takes():
    """Steps cut short by the end of a call or aimed at a phase event used to grow the size
    they were cut from fourfold each, untried: over 30 ms the reference scene driven every
    1 ms carried a step size of 1.1e44 s, high_speed driven every 0.1 ms an infinite one,
    and separation's next uncut step was refused twice over after a few aimed ones. Now it
    is at most four times the longest step taken, which a call's length bounds."""
    for name, communication_step in (("reference", 1e-3), ("high_speed", 1e-4)):
        _, _, _, run = shipped_drive(name, "exponential", 0.03, communication_step)
        assert run.clock[1] <= 4 * communication_step * (1 + 1e-9)


def test_a_landing_is_closed_in_on_without_retrying_what_was_refused():
    """Where contact is lost, the step that can be certified shrinks as the approach closes on
    a landing (or a lift-off) until only DOP853's step bound crosses it. A step grown
    fourfold right after a rejection tried again what had just been refused: separation
    rejected 94 exact steps in 50 ms (1 ms calls) and undamped, rattling from 50 ms on, 2170
    in 100 ms. Kept at its size, they reject 49 and 1368 (exact evaluations, accepted,
    rejected and trial, 8 % and 10 % fewer; torque_step's within 1 %)."""
    assert shipped_run("separation", "exponential", 0.05, 1e-3).rejected_steps <= 70
    assert shipped_run("undamped", "exponential", 0.1, 1e-3).rejected_steps <= 1700


def test_a_step_over_which_the_approach_is_monotone_is_certified_across_a_lift_off():
    """Near a lift-off or a landing the 13 kHz modes' ringing keeps keeps_sign from
    certifying the approach itself, and every step that reached past the crossing was
    refused: it was closed in on by quartering down to the exact floor. Where the approach's
    rate keeps its sign over the step (approach_monotone) the step crosses once, as its ends
    show, and is taken. separation, 50 ms, 1 ms calls: 23 rejected and 261 accepted exact
    steps, against 46 and 286 without it; the events as DOP853 finds them (the same contact
    counts: test_contact_loss_scenes_agree_with_the_reference)."""
    _, _, stepper, run = shipped_drive("separation", "exponential", 0.05, 1e-3)
    assert run.rejected_steps <= 32
    assert stepper.accepted_steps <= 275


def test_a_flight_inside_an_uncertified_exact_step_is_found():
    """A step the certificate cannot clear is taken at the exact floor, h·|λ|max = 3.5, 28 µs
    on found_e759bc9542, and the cubic through the approach's values and slopes at its ends
    did not see the lift-off and landing 2.3 µs apart inside it (at 7.07 ms): from 7.05 ms
    the run found no event, and its mesh pulled at −33 N in tension. The approach's own modal
    solution inside the step (exponential.approach_dip) shows where it went past zero: the
    run finds the flight and ends where DOP853 does from the same position (2.5e-10 of the
    state's scales apart at 1e-11). Its samples carry no tension."""
    scene = regression_scene("found_e759bc9542")
    model = GearTrainModel(scene)
    torques = scene.inputs.at(0.004)  # the motor's torque after its drop at 3.17 ms
    runs = {}
    for method in ("exponential", "dop853"):
        stepper = CompiledStepper(model, 1e-11, method)
        run_ = stepper.start(start_position(model, scene.inputs.at(0.0)[0]))
        stepper.run_to(run_, 0.0031738, scene.inputs.at(0.0))
        stepper.run_to(run_, 0.00705, torques)
        before = run_.events
        times = np.linspace(0.00705, 0.0071, 51)[1:]
        rows = np.empty((len(times), len(run_.outputs)))
        stepper.sample(run_, times, rows, 0.0071, torques)
        runs[method] = (run_.events - before, rows[:, equations.F_MESH].min(),
                        run_.state.copy())
    events, least_force, state = runs["exponential"]
    assert events >= 2 and least_force >= 0.0
    assert np.max(np.abs(state - runs["dop853"][2]) / model.state_scales()) < 1e-8


def test_the_approachs_march_clears_a_loaded_step_and_gives_up_on_one_without_load(
        reference_model):
    """approach_dip over a step at the exact floor: from the static start under the scene's
    torques, the approach clears the step (−1: no dip); at rest without load, its points in
    contact, the approach stays at zero, no interval is ever cleared, and the march gives up
    after DIP_EVALUATIONS evaluations (NaN: the step has the cubic's check) rather than
    crawling through the step by its narrowest intervals."""
    stepper = CompiledStepper(reference_model, 1e-7, "exponential")
    count, loaded = int(stepper.counts[0]), np.ones(stepper.tables.shape[2])
    train, tables = exponential.exact_train(reference_model.system), stepper.exact_buffers
    h = stepper.exact_floor
    for state, torques, expected in (
            (start_position(reference_model, 500.0).state, (500.0, 1800.0), -1.0),
            (np.zeros(2 * reference_model.size), (0.0, 0.0), math.nan)):
        exact = exponential.variant_of(tables, 0, count, loaded, state)
        assert exact >= 0
        dip = exponential.approach_dip(train, tables, exact, state, *torques, h, 1.0)
        assert dip == expected or (math.isnan(expected) and math.isnan(dip))


def test_an_exact_step_is_taken_uncertified_up_to_the_loops_own_step_bound():
    """DOP853's step bound is tightened where the fast modes are lightly damped, for DOP853's
    own error (undamped: 8.1e-6 s). An exact step makes no error: it is taken uncertified up
    to DOP853's own bound without it, h·|λ|max = EXPLICIT_STEP_BOUND (4.2e-5 s), what it
    hides between its ends shown by its modal solution (test_a_flight_inside_an_uncertified_
    exact_step_is_found). undamped, rattling from 50 ms on, took 34.6e3 accepted
    exact steps a simulated second at DOP853's bound, 13.6e3 at its own (measured over 100 ms,
    1 ms calls), within 1.3e-10 of the reference over 50 ms (benchmarks/exponential.py)."""
    from herringbone.integrate.compiled_stepper import EXPLICIT_STEP_BOUND

    stepper = shipped_drive("undamped", "exponential", 0.1, 1e-3)[2]
    assert stepper.exact_floor == pytest.approx(EXPLICIT_STEP_BOUND / stepper.fastest_rate)
    assert stepper.exact_floor > 4.0 * stepper.max_step
    assert stepper.accepted_steps <= 2000


def test_a_pinion_turning_back_across_a_switch_inside_a_step_is_not_lost():
    """torque_step at tenfold torque, driven as the FMU drives it (1 ms calls): between 71 and
    72 ms the torsional mode swings the pinion speed through zero just after a switch, and
    the pinion turns back into the contact interval before and returns within 7 µs. Taken
    uncertified at the step bound (34 µs, DOP853's), a step saw the pinion inside its
    interval at both ends and lost both switches: four events in that ms where scipy's
    DOP853 finds six, and the forces 4.8e-4 of the force scale off from then on. A step now
    knows where its phase events are unsure (neither the speed's sign nor the angle's place
    in the interval certified) and goes below the step bound there: within 1e-6 of the
    reference at 72 ms (measured 1.1e-10)."""
    model, scene, stepper, run = shipped_drive("torque_step", "exponential", 0.071, 1e-3)
    position, torques = stepper.position(run), scene.inputs.at(0.071)
    events = run.events
    stepper.run_to(run, 0.072, torques)
    truth = ScipyStepper(model, 1e-10).advance(position, 0.072, torques)
    assert run.events - events == 6
    expected = model.outputs(truth.state, truth.segment.contact_set, truth.segment.loaded)
    outputs = stepper.position(run)
    found = model.outputs(outputs.state, outputs.segment.contact_set, outputs.segment.loaded)
    assert force_error({k: [v] for k, v in found.items()},
                       {k: [v] for k, v in expected.items()}, model) <= 1e-6


def test_a_step_certified_to_keep_the_pinion_inside_its_interval_keeps_it():
    """exponential.angle_inside, on exact steps of 1 µs to 1 ms from torque_step's state at
    71 ms (1 ms calls), where the pinion has just entered a contact interval and a torsional
    mode swings its speed through zero: wherever it says the angle stays above 0 and below
    the interval's length over the step, the angle sampled at 401 times of the step does;
    and it says so of the short steps, not of the long ones."""
    model, scene, stepper, run = shipped_drive("torque_step", "exponential", 0.071, 1e-3)
    state, torques = run.state.copy(), scene.inputs.at(0.071)
    interval = int(run.place[0])
    verdicts, inside = angle_verdicts(model, stepper, run, state, torques, interval,
                                      np.geomspace(1e-6, 1e-3, 13))
    assert all(inside[verdicts])
    assert verdicts[0] and not verdicts[-1]


def angle_verdicts(model, stepper, run, state, torques, interval, steps, samples=401):
    """For exact steps of each length in `steps` (s) from `state` in contact interval
    `interval`: exponential.angle_inside's verdict, and whether the angle sampled at
    `samples` times of the step stays above 0 and below the interval's length."""
    train, buffers = exponential.exact_train(model.system), stepper.exact_buffers
    pinion = train.pinion
    length = stepper.lengths[interval]
    exact = exponential.variant_of(buffers, interval, stepper.counts[interval], run.loaded,
                                   state)
    assert exact >= 0
    out, verdicts, inside = np.empty_like(state), [], []
    for h in steps:
        exponential.step(train, buffers, exact, state, *torques, h, True, 1.0, length, out)
        verdicts.append(exponential.angle_inside(train, buffers, exact, h, state[pinion],
                                                 out[pinion], length))
        angles = []
        for t in np.linspace(0.0, h, samples)[1:]:
            exponential.state_after(train, buffers, exact, state, *torques, t, out)
            angles.append(out[pinion])
        inside.append(0.0 < min(angles) and max(angles) < length)
    return np.array(verdicts), np.array(inside)


def test_the_angle_is_certified_inside_as_far_as_it_stays_there_after_a_switch():
    """Right after torque_step's switches (20 to 30 ms, 1 ms calls) the pinion angle starts
    at its interval's start and the fast modes swing its speed by as much as its mean: the
    magnitudes alone (keeps_sign) certified steps of 6 µs to 63 µs where the angle stays
    inside for 13 µs to 2 ms. On the grid of exponential.inside_on_grid, from the angle's
    values and rates (the modes' phases), angle_inside certifies a step exactly where the
    angle sampled at 201 times stays inside, on 13 lengths from 1 µs to 2 ms after each of
    six switches (measured also on the 21 states of the steps torque_step rejected by 30 ms,
    41 lengths from 0.2 µs to 2 ms and 600 samples each)."""
    model, scene, stepper, run = shipped_drive("torque_step", "exponential", 0.02, 1e-3)
    torques, states = scene.inputs.at(0.02), 0
    while run.time < 0.03 and states < 6:
        events = run.events
        with contextlib.suppress(StepBudgetExceeded):
            stepper.run_to(run, 0.03, torques, max_steps=1)
        interval = int(run.place[0])
        if run.events == events or run.state[model.system.pinion] > 1e-9 or (
                exponential.variant_of(stepper.exact_buffers, interval,
                                       stepper.counts[interval], run.loaded, run.state) < 0):
            continue
        states += 1
        verdicts, inside = angle_verdicts(model, stepper, run, run.state.copy(), torques,
                                          interval, np.geomspace(1e-6, 2e-3, 13), 201)
        assert np.array_equal(verdicts, inside)
    assert states == 6


def test_the_grid_takes_torque_steps_turns_in_fewer_exact_evaluations():
    """torque_step, 50 ms driven every 1 ms: with the angle certified on inside_on_grid's
    grid, 296 exact evaluations (211 accepted steps, 25 rejected, 60 trials) for its 63
    events, against 430 (302, 48, 80) with the magnitudes alone."""
    _, _, stepper, run = shipped_drive("torque_step", "exponential", 0.05, 1e-3)
    assert run.events == 63
    assert run.rejected_steps <= 32
    assert stepper.accepted_steps + run.rejected_steps + run.trial_steps <= 330


def test_the_interval_bound_lies_below_every_function_it_admits():
    """exponential._interval_low: over 2000 random functions (a line plus four sines) on
    intervals of random width, the bound from the values and rates at the ends and the
    largest |f''| is never above the least of f sampled at 2001 points; for a parabola
    curving down it is the lower end exactly, for one curving up by `curve` over the width
    w it is curve·w²/4 below the least value (the two tangent parabolas meet halfway)."""
    rng = np.random.default_rng(24)
    for _ in range(2000):
        width = float(np.exp(rng.uniform(np.log(1e-6), np.log(1e-2))))
        sizes, rates = rng.normal(size=4), np.exp(rng.uniform(0.0, 2.0, 4)) / width
        phases, line = rng.uniform(0.0, 2 * np.pi, 4), rng.normal(size=2) * (1.0, 1 / width)
        s = np.linspace(0.0, width, 2001)[:, None]
        values = line[0] + line[1] * s[:, 0] + (sizes * np.sin(rates * s + phases)).sum(1)
        rates_at = line[1] + (sizes * rates * np.cos(rates * s[[0, -1]] + phases)).sum(1)
        curve = float((np.abs(sizes) * rates ** 2).sum())
        low = exponential._interval_low(values[0], rates_at[0], values[-1], rates_at[1], curve,
                                        width)
        assert low <= values.min() + 1e-12 * np.abs(values).max()
    curve, width = 3.0, 0.5
    assert exponential._interval_low(1.0, 2.0, 1.0 + 2.0 * width - 0.5 * curve * width ** 2,
                                     2.0 - curve * width, curve, width) == 1.0
    assert exponential._interval_low(curve * width ** 2 / 8, -curve * width / 2,
                                     curve * width ** 2 / 8, curve * width / 2, curve,
                                     width) == pytest.approx(-curve * width ** 2 / 4)


def drive_every_ms(name, span, in_one_call, check_contact=False):
    """The exponential method's outputs every 1 ms over `span` (s) of shipped scene `name`
    (rows by model.output_layout), the scene's torques held from each piece's start: driven
    by a call every 1 ms as the FMU drives it (run_to), or `in_one_call` per piece of the
    torque schedule, sampled inside it (CompiledStepper.sample); a debug run (contact checked
    inside every step) where `check_contact`. Returns (the outputs, the stepper, its Run)."""
    scene = herringbone.load_scene(MODELS / f"{name}.toml")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7, "exponential", check_contact=check_contact)
    run = stepper.start(start_position(model, scene.inputs.at(0.0)[0]))
    count = round(span / 1e-3)
    rows, times = np.empty((count, model.output_layout_size)), (np.arange(count) + 1) * 1e-3
    if not in_one_call:
        for k in range(count):
            stepper.run_to(run, times[k], scene.inputs.at(k * 1e-3))
            rows[k] = run.outputs
        return rows, stepper, run
    edges = np.searchsorted(times - 1e-3, scene.inputs.change_times(), side="left")
    for first, after in zip([0, *edges], [*edges, count]):
        if first < after:
            stepper.sample(run, times[first:after], rows[first:after], times[after - 1],
                           scene.inputs.at(first * 1e-3))
    return rows, stepper, run


SHIPPED = sorted(path.stem for path in MODELS.glob("*.toml"))


@pytest.mark.parametrize("name", [name for name in SHIPPED if name != "undamped"])
def test_the_host_s_communication_step_does_not_change_the_run(name):
    """Every shipped scene by the exponential method over 100 ms, twice its published span:
    driven every 1 ms as the FMU is, its outputs every 1 ms are those of the same run in one
    call a piece of the torque schedule, within 1e-6 of the force scale, with the same
    events (measured: 4.3e-10 at most, torque_step's). A step that lost a switch in one
    drive and not the other fails here (torque_step's lost turn-back: 6.2e-4). undamped is
    left out: it rattles chaotically from 50 ms on (the integrators part from each other
    there; docs/exponential-integrator.md)."""
    stepped, _, stepped_run = drive_every_ms(name, 0.1, in_one_call=False)
    sampled, _, sampled_run = drive_every_ms(name, 0.1, in_one_call=True)
    model = model_of(name)
    columns = {name: column for name, column in model.output_layout if name in FORCES}
    assert stepped_run.events == sampled_run.events
    assert force_error({force: stepped[:, column] for force, column in columns.items()},
                       {force: sampled[:, column] for force, column in columns.items()},
                       model) <= 1e-6


def drive_with_a_check(name, span, in_one_call, check_contact):
    """drive_every_ms's run, a debug run or not: (final state, outputs every 1 ms, accepted and
    rejected steps, events, switches chained, landings and lift-offs chained)."""
    rows, stepper, run = drive_every_ms(name, span, in_one_call, check_contact)
    return (run.state.copy(), rows, stepper.accepted_steps, run.rejected_steps, run.events,
            run.switches_chained, run.contacts_chained)


@pytest.mark.parametrize("name, share", [("high_speed", 0.9), ("reference", 0.85)])
@pytest.mark.parametrize("in_one_call", [False, True])
def test_switches_chained_are_the_loops_to_the_bit(name, share, in_one_call):
    """Phase switches taken one after another (walk.chain_switches) give the run the loop's
    own iteration gives it, to the bit: over 20 ms (both drives of drive_every_ms),
    the final state, the outputs every 1 ms and the accepted and rejected steps and events
    equal those of a debug run, which checks inside every step and chains nothing. The
    chain takes `share` of the events at least (measured 0.99 on high_speed, whose events
    are nearly all switches of exact sets; 0.90 on the reference scene, one switch a sample,
    whose sampled run chained 0.30 while a step that passed a sample was left to the loop),
    so a chain that stopped chaining fails here too."""
    chained = drive_with_a_check(name, 0.02, in_one_call, check_contact=False)
    checked = drive_with_a_check(name, 0.02, in_one_call, check_contact=True)
    assert np.array_equal(chained[0], checked[0]) and np.array_equal(chained[1], checked[1])
    assert chained[2:5] == checked[2:5]
    assert checked[5] == 0 and chained[5] >= share * chained[4] and chained[6] == 0


@pytest.mark.parametrize("in_one_call", [False, True])
def test_landings_and_lift_offs_chained_lie_where_the_loop_locates_them(in_one_call):
    """jump_resonance has six events a mesh period: four phase switches, a lift-off and a
    landing. The chain steps onto the landings and lift-offs too (walk.aimed_contact: just
    past the first crossing of the approach's modal solution, marched for from the
    segment's start), where the loop located each by its steps and trials: over 20 ms (both
    drives of drive_every_ms) the forces every 1 ms lie within 1e-9 of the force scale of a
    debug run's, which chains nothing (measured 8.5e-13), with the same events; the chain
    takes 0.95 of them at least (measured 0.97 by calls of 1 ms, 0.98 in one call), and
    0.28 at least are landings and lift-offs (0.30 and 0.31). A call's last step is chained
    too: left to the loop, the lift-off and the landing of a 1 ms call's last mesh period
    brought the calls' share down to 0.92 and 0.25."""
    chained = drive_with_a_check("jump_resonance", 0.02, in_one_call, check_contact=False)
    checked = drive_with_a_check("jump_resonance", 0.02, in_one_call, check_contact=True)
    model = model_of("jump_resonance")
    columns = {name: column for name, column in model.output_layout if name in FORCES}
    assert force_error({force: chained[1][:, column] for force, column in columns.items()},
                       {force: checked[1][:, column] for force, column in columns.items()},
                       model) <= 1e-9
    assert chained[4] == checked[4] and checked[5] == checked[6] == 0
    assert chained[5] + chained[6] >= 0.95 * chained[4] and chained[6] >= 0.28 * chained[4]


def interval_left(stepper, position, torques, by, halvings=30, changed=None):
    """When (s after `position`) the run leaves its contact interval (or, given, when
    changed(stepper, position, torques, h) first holds), found by bisection on exact runs to
    2^-`halvings` of `by` (s), by which it must have happened."""
    def left(h):
        if changed is not None:
            return changed(stepper, position, torques, h)
        moved = stepper.advance(position, position.time + h, torques)
        return moved.segment.contact_set.index != position.segment.contact_set.index
    low, high = 0.0, by
    assert left(high)
    for _ in range(halvings):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if left(middle) else (middle, high)
    return high


def states_inside_intervals(stepper, torques):
    """From four times of a run from the scene's start with the torques held: its Position,
    the exact form of its contact set with every point loaded, and that set's interval length
    (rad)."""
    model = stepper.model
    for time in (0.0037, 0.0052, 0.0101, 0.0133):
        position = stepper.advance(start_position(model, torques[0]), time, torques)
        interval = position.segment.contact_set.index
        yield (position, interval * exponential.VARIANTS + exponential.ALL_LOADED,
               stepper.lengths[interval])


def test_the_modal_solution_gives_the_phase_event_to_rounding(reference_model):
    """exponential.modal_phase_event_ahead, from four states inside a contact interval of the
    reference scene: the time at which the angle's modal solution leaves the interval
    (CROSSING) lies within four event time tolerances (4.3e-14 s, 1.5e-10 of that time) of the
    crossing found by bisection on exact runs, which place a crossing within two of them
    (measured 3.0e-14 s at most); asked about a horizon a thousandth of that time, it
    foresees no event there."""
    model, torques = reference_model, (500.0, 1800.0)
    stepper = CompiledStepper(model, 1e-7, "exponential")
    for position, exact, length in states_inside_intervals(stepper, torques):
        arguments = (exponential.exact_train(model.system), stepper.exact_buffers, exact,
                     position.state, *torques, length)
        ahead, aim = exponential.modal_phase_event_ahead(*arguments, 1.0)
        crossing = interval_left(stepper, position, torques, 1.01 * ahead, halvings=48)
        assert aim == exponential.CROSSING
        assert abs(ahead - crossing) <= 4.0 * stepper.event_time_tolerance
        assert exponential.modal_phase_event_ahead(*arguments, 1e-3 * ahead)[0] == np.inf


def test_halley_s_step_cubes_the_error_and_its_size_bounds_it():
    """exponential._halley_change on f(t) = e^t − 2 from 0.5 (the root ln 2, 0.193 away):
    each step leaves an error below the cube of the one before (measured 5.4e-4 after the
    first, where Newton's step leaves 2.0e-2, its square's half), and _cubed_error, the size
    _modal_crossing stops on, is no smaller than that error."""
    root, t = np.log(2.0), 0.5
    newton = t - (np.exp(t) - 2.0) / np.exp(t)
    for _ in range(2):
        change = exponential._halley_change(np.exp(t) - 2.0, np.exp(t), np.exp(t))
        before, t = t - root, t - change
        assert abs(t - root) <= abs(before) ** 3
        derivative = np.exp(t + change)  # (f', f'' and f''' where the step was taken)
        assert exponential._cubed_error(change, derivative, derivative, derivative) >= abs(
            t - root)
    assert abs(newton - root) >= 0.5 * (0.5 - root) ** 2


def test_the_near_exponential_is_exp_to_rounding():
    """exponential._near_exponential, the series that takes an aimed step's e^{λ·h} from the
    aim's e^{λ·t}: within 2.3e-16 of exp at every |Re| + |Im| up to NEAR_EXPONENT, in eight
    directions of the complex plane. Its x³ term dropped, it would miss by 1.7e-13 there."""
    for size in (1e-8, 1e-6, exponential.NEAR_EXPONENT):
        for angle in np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False):
            x = size * complex(np.cos(angle), np.sin(angle)) / (
                abs(np.cos(angle)) + abs(np.sin(angle)))
            assert abs(exponential._near_exponential(x) - np.exp(x)) <= 2.3e-16, (size, angle)


def test_a_step_aimed_at_the_crossing_takes_the_aim_s_exponentials(reference_model):
    """The step aimed just past the angle's modal crossing (the crossing plus a location
    tolerance) ends so near the aim's last evaluation that its e^{λ·h} are that evaluation's
    times the near series (|λ·(h − t)| within NEAR_EXPONENT on every mode, from four states
    of the reference scene; measured 1e-8 at most), and its end is the one the exponentials
    themselves give, within 1e-14 of the state's scales (measured 3e-16). The aim's own
    exponentials without the series would miss by about |λ·(h − t)|."""
    model, torques = reference_model, (500.0, 1800.0)
    stepper = CompiledStepper(model, 1e-7, "exponential")
    tables, scales = exponential.unpack_tables(stepper.exact_buffers), model.state_scales()
    for position, exact, length in states_inside_intervals(stepper, torques):
        arguments = (exponential.exact_train(model.system), stepper.exact_buffers, exact,
                     position.state, *torques)
        ahead, aim = exponential.modal_phase_event_ahead(*arguments, length, 1.0)
        h = ahead + stepper.event_time_tolerance
        rates = tables.rates[exact, :tables.fast_count[exact]]
        near = rates * (h - tables.start[exponential.AIMED_AT])
        assert aim == exponential.CROSSING
        assert np.all(np.abs(near.real) + np.abs(near.imag) <= exponential.NEAR_EXPONENT)
        aimed, fresh = np.empty_like(position.state), np.empty_like(position.state)
        exponential.state_after(*arguments, h, aimed)
        tables.start[exponential.AIMED_AT] = np.nan  # (no aim: the exponentials themselves)
        exponential.state_after(*arguments, h, fresh)
        assert np.abs((aimed - fresh) / scales).max() <= 1e-14


def test_the_slow_polynomial_s_derivatives_are_horner_s():
    """exponential._polynomial_derivatives: a quartic's value and first three derivatives at
    a point, as numpy's Polynomial gives them, to rounding."""
    terms, t = np.array([1.0, 2.0, -3.0, 0.5, 4.0]), 0.7
    polynomial = np.polynomial.Polynomial(terms)
    expected = [polynomial.deriv(order)(t) for order in range(4)]
    assert np.allclose(exponential._polynomial_derivatives(terms, 4, t), expected,
                       rtol=1e-14, atol=0.0)


@pytest.mark.parametrize("scene_name", ["reference", "jump_resonance"])
def test_the_tabulated_slow_polynomial_is_the_slow_block_s_exponential(scene_name):
    """exponential._slow_polynomial from the tables' rows (angle_polynomial,
    approach_polynomial, row·T_slow^n/n!): the slow part of the pinion angle and of a point's
    approach as a polynomial in t must be their row of the slow columns times
    expm(T_slow·t)·z_slow (scipy), at times up to 1 ms (three mesh periods of the reference
    scene), within 1e-12 of the sum of the products' magnitudes, on every exact form, from
    random slow coordinates. A row tabulated without its 1/n!, or one power off, misses by
    far more."""
    model = model_of(scene_name)
    tables, pinion = CompiledStepper(model, 1e-7, "exponential").exact_tables, model.system.pinion
    rng = np.random.default_rng(7)
    for exact in np.flatnonzero(tables.valid):
        size = tables.slow_count[exact]
        block = tables.slow[exact, :size, :size]
        start = rng.normal(size=size)
        tables.start_slow[:size] = start
        for rows, row in ((tables.angle_polynomial[exact], tables.slow_right[exact, pinion]),
                          (tables.approach_polynomial[exact], tables.approach_slow[exact])):
            exponential._slow_polynomial(tables, exact, rows)
            terms = tables.modal_slow[:size].copy()
            for t in (1e-5, 1e-4, 1e-3):
                propagator = scipy.linalg.expm(block * t)
                expected = row[:size] @ propagator @ start
                scale = np.abs(row[:size]) @ np.abs(propagator) @ np.abs(start)
                assert abs(np.polynomial.polynomial.polyval(t, terms) - expected) \
                    <= 1e-12 * scale, (exact, t)


@pytest.mark.parametrize("scene_name", ["reference", "jump_resonance"])
def test_the_slow_series_runs_over_the_block_s_nonzero_entries_to_the_bit(scene_name):
    """exponential._slow_series sums each row of T_slow·term over the columns slow_columns
    lists: they must be every column whose entry is not zero, rising, so that its series is
    to the bit the dense one (every row summed over every column in order, as here in
    Python's floats, which are IEEE doubles), on every exact form, from random slow
    coordinates, over steps of 1e-5 to 1e-3 s. A column left out, or one listed twice, moves
    the last bits or more; and the series must be expm(T_slow·h) of the start (scipy) within
    1e-12 of the products' magnitudes."""
    model = model_of(scene_name)
    tables = CompiledStepper(model, 1e-7, "exponential").exact_tables
    rng = np.random.default_rng(11)
    for exact in np.flatnonzero(tables.valid):
        size = tables.slow_count[exact]
        block = tables.slow[exact, :size, :size]
        for i in range(size):
            count = tables.slow_columns[exact, i, 0]
            assert list(tables.slow_columns[exact, i, 1:count + 1]) == \
                list(np.flatnonzero(block[i])), (exact, i)
        start = rng.normal(size=size)
        for h in (1e-5, 1e-4, 1e-3):
            tables.start_slow[:size] = start
            exponential._slow_series(tables, exact, h)
            assert np.array_equal(tables.modal_slow[:size], dense_series(block, start, h)), \
                (exact, h)
            propagator = scipy.linalg.expm(block * h)
            assert np.all(np.abs(tables.modal_slow[:size] - propagator @ start)
                          <= 1e-12 * (np.abs(propagator) @ np.abs(start))), (exact, h)


def dense_series(block, start, h):
    """exp(block·h)·start as exponential._slow_series sums it, but over every column of each
    row: the terms T·term·h/n added until the largest falls to SERIES_FLOOR of the largest
    start coordinate."""
    size, term = len(start), [float(value) for value in start]
    total, largest = list(term), max(abs(value) for value in term)
    for order in range(1, exponential.MAX_SERIES_TERMS):
        following = []
        for i in range(size):
            row = 0.0
            for j in range(size):
                row += float(block[i, j]) * term[j]
            following.append(row * (h / order))
        term = following
        total = [value + change for value, change in zip(total, term)]
        if max(abs(value) for value in term) <= exponential.SERIES_FLOOR * largest:
            break
    return np.array(total)


def contact_changed(stepper, position, torques, h):
    """Whether an exact run from `position` has changed its loaded points, or left its
    contact set, by `h` s after it."""
    moved = stepper.advance(position, position.time + h, torques)
    return (moved.segment.contact_set.index != position.segment.contact_set.index
            or not np.array_equal(moved.segment.loaded, position.segment.loaded))


def test_the_modal_solution_gives_a_lift_off_and_a_landing_to_rounding():
    """exponential.approach_crossing, the first estimate of a contact event in an exact
    segment: from the states just after six events of jump_resonance (lift-offs, landings and
    phase switches), where the next event is a lift-off or a landing, the time at which the
    approach's modal solution crosses zero, searched from the end of a bracket a thousandth
    longer than the time to it, lies within four event time tolerances (1.6e-13 s) of the
    crossing found by bisection on exact runs (measured 1.8e-18 s at most, three lift-offs
    and three landings). So does approach_first_crossing, the chain's, from the state alone
    over ten times the time to it (the loaded set's own solution crosses back and forth
    after a lift-off; the first crossing is the event)."""
    scene = herringbone.load_scene(MODELS / "jump_resonance.toml")
    model, torques = GearTrainModel(scene), scene.inputs.at(0.0)
    stepper, train = CompiledStepper(model, 1e-7, "exponential"), exponential.exact_train(
        model.system)
    position, checked = stepper.advance(start_position(model, torques[0]), 0.01, torques), 0
    while checked < 6:
        by = 2e-5  # the next event, by doubling then bisection
        while not contact_changed(stepper, position, torques, by):
            by *= 2.0
        high = interval_left(stepper, position, torques, by, halvings=46,
                             changed=contact_changed)
        after = stepper.advance(position, position.time + high, torques)
        if after.segment.contact_set.index == position.segment.contact_set.index:
            interval = position.segment.contact_set.index
            count = int(stepper.counts[interval])
            exact = exponential.variant_of(stepper.exact_buffers, interval, count,
                                           position.segment.loaded, position.state)
            assert exact >= 0
            rising = not position.segment.loaded.any()
            crossing = exponential.approach_crossing(
                train, stepper.exact_buffers, exact, position.state, *torques,
                1.001 * high, rising, 1.001 * high)
            assert abs(crossing - high) <= 4.0 * stepper.event_time_tolerance
            first = exponential.approach_first_crossing(
                train, stepper.exact_buffers, exact, position.state, *torques,
                10.0 * high, -1.0 if rising else 1.0)
            assert abs(first - high) <= 4.0 * stepper.event_time_tolerance
            checked += 1
        position = after


def test_a_contact_event_of_an_exact_set_takes_one_trial_or_two():
    """The location of a lift-off or a landing in an exact segment starts from the modal
    solution's crossing and needs no trial just before it (the set's points cross together):
    over 50 ms of jump_resonance, 1 181 events (398 of them lift-offs and landings), at most
    0.8 trial steps an event (measured 0.67, probes of grazing included; 2.3 from the cubic's
    estimate with a trial just before each crossing), and the same accepted steps."""
    scene = herringbone.load_scene(MODELS / "jump_resonance.toml")
    model, torques = GearTrainModel(scene), scene.inputs.at(0.0)
    stepper = CompiledStepper(model, 1e-7, "exponential")
    run_ = stepper.start(start_position(model, torques[0]))
    stepper.run_to(run_, 0.05, torques)
    assert run_.events > 1000
    assert run_.trial_steps <= 0.8 * run_.events


@pytest.mark.parametrize("name", ["reference", "jump_resonance"])
def test_the_modal_phase_event_is_a_smooth_function_of_the_state(name):
    """Along a line of states (steps of 1e-12 of the state scales) from four states of a run,
    the modal solution's phase event moves smoothly: its second differences within 1e-13 of
    it (measured 4.9e-15 and 3.7e-15). Where Newton's iterate met the interval's end to the
    bit, a bracket that took it for a low end bisected away from the root and the search
    stopped short: 2e-10 on the reference scene, 6e-2 on jump_resonance, which the period
    map's forward differences read as a multiplier 5e-5 off."""
    scene = herringbone.load_scene(MODELS / f"{name}.toml")
    model, torques = GearTrainModel(scene), scene.inputs.at(0.0)
    stepper, train = CompiledStepper(model, 1e-7, "exponential"), exponential.exact_train(
        model.system)
    for position, exact, length in states_inside_intervals(stepper, torques):
        ahead = np.array([exponential.modal_phase_event_ahead(
            train, stepper.exact_buffers, exact,
            position.state + k * 1e-12 * model.state_scales(), *torques, length, 1.0)[0]
            for k in range(-20, 21)])
        assert np.all(np.isfinite(ahead))
        assert np.abs(np.diff(ahead, 2)).max() <= 1e-13 * ahead[20]


def test_a_first_step_is_aimed_just_past_the_phase_event(reference_model):
    """The first step after a switch, and a call's first step, are aimed past the modal
    solution's crossing by the location tolerance, so that the crossing is located without a
    trial step. Over 20 ms of the reference scene (20 events): in one call 1.3 accepted
    steps and 0.15 trial steps an event (1.4 and 2.0 aimed by the slow motion, 2.25 and more
    from φp's speed and acceleration, which the switch sets ringing); in calls of 1 ms, as
    the FMU makes them, 44 accepted steps and 3 trials (56 and 36 where a call's first step
    was aimed from φp's speed and acceleration)."""
    model, torques = reference_model, (500.0, 1800.0)
    aimed = CompiledStepper(model, 1e-7, "exponential")
    run = aimed.start(start_position(model, torques[0]))
    aimed.run_to(run, 0.02, torques)
    assert aimed.accepted_steps <= 1.5 * run.events and run.trial_steps <= 0.3 * run.events
    stepped = CompiledStepper(model, 1e-7, "exponential")
    run = stepped.start(start_position(model, torques[0]))
    for k in range(20):
        stepped.run_to(run, (k + 1) * 1e-3, torques)
    assert stepped.accepted_steps <= 1.15 * (20 + run.events)
    assert run.trial_steps <= 0.3 * run.events


def test_an_opening_step_is_not_planned_past_where_the_event_has_surely_happened():
    """Where the fast modes swing the pinion angle by more than PREDICTION_SPREAD of the way,
    slow_phase_event_ahead's time is too loose an aim, but the event has surely happened by
    then. The opening step is planned no further: the reference scene's opening steps into
    its two short intervals had grown to milliseconds (phase_event_ahead, from the ringing
    acceleration, foresaw no event), crossed it early on (330 µs into 4.9 ms), and the cubic
    through their ends located it in three trials. Over 50 ms in one call: 2.00 trials an
    event (2.47 before)."""
    _, _, _, run = shipped_drive("reference", "exponential", 0.05)
    assert run.trial_steps <= 2.1 * run.events


def test_a_flight_with_nothing_elastic_is_a_polynomial_propagated_exactly():
    """The gear pair alone (jump_resonance) with its points unloaded is two free bodies with
    nothing elastic between them: Â is nilpotent, every eigenvalue zero, and no basis of
    eigenvectors diagonalizes it. Its modal form is then the slow block alone, the polynomial
    exp(T_slow·h), with no fast mode, and it is scipy's expm to 1e-12 of the state's scales.
    Every set is exact, so "auto" takes the exponential method: over 5 ms of lift-offs
    within 1e-8 of the force scale of scipy's DOP853 at 1e-12 (measured 4.0e-9; DOP853 at the
    same tolerance 3.0e-7)."""
    scene = herringbone.load_scene(MODELS / "jump_resonance.toml")
    model = GearTrainModel(scene)
    lengths, counts, tables = model.mesh.period_table()
    a, b = exponential.linear_system(model.system, tables[0], counts[0], np.zeros(counts[0]))
    assert np.all(np.linalg.eigvals(a) == 0.0)
    form = exponential.modal_form(a, b, scales_of(model))
    assert len(form[3]) == a.shape[0] + exponential.INPUTS  # the slow block is all of Â
    start = np.array([0.004, -0.001, 2500.0, 690.0, 100.0, 360.0, 1.0])
    for h in (1e-6, 1e-4, 1e-3):
        assert modal_step_error(form, a, b, start, h, model.state_scales()) <= 1e-12
    stepper = CompiledStepper(model, 1e-7)
    assert stepper.method == "exponential" and stepper.exact_tables.valid.all()
    result = simulate_with(stepper, scene, stop_time=0.005, output_interval=1e-4)
    reference = herringbone.reference_simulate(scene, stop_time=0.005, output_interval=1e-4,
                                               tolerance=1e-12)
    assert result["n_contacts"].min() == 0  # the mesh lifts off
    assert force_error(result, reference, model) <= 1e-8


def test_a_scene_without_a_modal_form_runs_by_runge_kutta_under_auto_and_by_parts_as_asked():
    """found_aaeb0efe2e without its edge ramps: every loaded set exact, but its flights have
    no modal form (test_free_bodies_that_rounding_makes_diagonalizable_have_no_modal_form).
    "auto" takes DOP853 or Radau IIA instead; "exponential" propagates the loaded sets exactly
    and steps the flights by DOP853: over its first three lift-offs (8.7 ms) within 1e-8 of
    the force scale of scipy's DOP853 at 1e-10 (measured 2.1e-10; DOP853 at the same
    tolerance 5.9e-7)."""
    scene = regression_scene("found_aaeb0efe2e").with_parameters(edge_ramp=0.0)
    model = GearTrainModel(scene)
    assert choose_method(model) == "exponential"  # every loaded set is exact
    assert CompiledStepper(model, 1e-7).method in ("dop853", "radau")
    stepper = CompiledStepper(model, 1e-7, method="exponential")
    valid = stepper.exact_tables.valid.reshape(-1, exponential.VARIANTS)
    assert valid[:, exponential.ALL_LOADED].all() and not valid.all()
    result = simulate_with(stepper, scene, stop_time=0.0087, output_interval=1e-5)
    reference = herringbone.reference_simulate(scene, stop_time=0.0087, output_interval=1e-5)
    assert result["n_contacts"].min() == 0  # the mesh lifts off
    assert force_error(result, reference, model) <= 1e-8


def test_free_bodies_that_rounding_makes_diagonalizable_have_no_modal_form():
    """tests/regression/found_aaeb0efe2e.toml has no bearings: with its points unloaded the
    pinion is one free body and the wheel with its load another. Their zero eigenvalues sit on
    chains that rounding splits into ±9.3e-3 s⁻¹ with nearly parallel eigenvectors, so numpy's
    eig finds a basis where jump_resonance's has none, of condition 7e4; an exact step on it
    moved the wheel 1e-4 rad off scipy's expm, and a run at 12 600 rad/s backwards lost a
    phase event and failed. modal_form refuses such a form as it refuses a singular one: the
    unloaded sets are stepped by DOP853, the loaded ones stay exact (half of them: the others
    load a point on an edge ramp), and every form it keeps is the matrix exponential to 1e-9
    of the state's scales (a state of that run)."""
    model = GearTrainModel(regression_scene("found_aaeb0efe2e"))
    lengths, counts, tables = model.mesh.period_table()
    variants = {}
    for variant in (exponential.ALL_LOADED, exponential.NONE_LOADED):
        loaded = np.full(counts[0], 1.0 if variant == exponential.ALL_LOADED else 0.0)
        a, b = exponential.linear_system(model.system, tables[0], counts[0], loaded)
        try:
            variants[variant] = exponential.modal_form(a, b, scales_of(model)), a, b
        except np.linalg.LinAlgError as refusal:
            assert "condition number" in str(refusal)
    assert list(variants) == [exponential.ALL_LOADED]
    valid = CompiledStepper(model, 1e-7, "exponential").exact_tables.valid.reshape(
        -1, exponential.VARIANTS)
    assert valid[:, exponential.ALL_LOADED].any() and not valid[:, exponential.NONE_LOADED].any()
    form, a, b = variants[exponential.ALL_LOADED]
    start = np.array([0.0882, 0.0172, -29.3, -12624.0, -3033.0, -3800.0, 67.4, 134.7, 1.0])
    for h in (1e-7, 1e-6, 5e-6):
        assert modal_step_error(form, a, b, start, h, model.state_scales()) <= 1e-9


def test_a_stiff_mesh_keeps_the_exponential_method_while_its_rounding_is_within_the_tolerance():
    """The reference scene with c_point = 2e10 N/m (80 times its own): the modal forms'
    eigenvalues have a condition number of 1.5e3, whose rounding (2.7e-16·κ² = 6e-10 of the
    force scale) is within 1e-7 and not within 1e-10. At 1e-7 `auto` takes the exponential
    method, 1.8e-9 off DOP853 at 1e-11 over 5 ms (measured); at 1e-10 it takes DOP853, and
    says why."""
    scene = herringbone.load_scene(MODELS / "reference.toml").with_parameters(c_point=2e10)
    model = GearTrainModel(scene)
    truth = simulate_with(CompiledStepper(model, 1e-11, "dop853"), scene, 0.005, 1e-4)
    stepper = CompiledStepper(model, 1e-7)
    assert stepper.method == "exponential" and stepper.exact_tables.valid.any()
    run = simulate_with(stepper, scene, 0.005, 1e-4)
    assert force_error(run, truth, scene) <= 1e-8
    tight = CompiledStepper(model, 1e-10)
    assert tight.method == "dop853"
    assert "condition number is 1.49e+03, over 609 at the tolerance 1e-10" in tight.method_note


class ModalStep(NamedTuple):
    """The fields of ExactTables that exponential.keeps_sign reads, for one exact form."""

    fast_count: np.ndarray
    rates: np.ndarray
    start_size: np.ndarray
    start_fast: np.ndarray
    modal_fast: np.ndarray


def random_function(rng, rate=False):
    """A function of the kind keeps_sign bounds: a cubic slow part plus three to seven
    damped modes from 1e2 to 1e5 1/s (ζ from 1e-4 to 0.3), some swinging more than the slow
    part, over a step of 1e-6 to 1e-3 s. Returns (its value at times t, the ModalStep of the
    step, the modes' rows and their magnitudes, the SlowBound, h); with `rate`, the value
    and the SlowBound of its rate instead (the same draws: the same function)."""
    count = int(rng.integers(3, 8))
    speed = np.exp(rng.uniform(np.log(1e2), np.log(1e5), count))
    damping = np.exp(rng.uniform(np.log(1e-4), np.log(0.3), count))
    rates = speed * (-damping + 1j * np.sqrt(1.0 - damping ** 2))
    rows = rng.normal(size=count) + 1j * rng.normal(size=count)
    start = (rng.normal(size=count) + 1j * rng.normal(size=count)) * np.exp(
        rng.uniform(-3.0, 0.0, count)) / np.abs(rows)
    h = float(np.exp(rng.uniform(np.log(1e-6), np.log(1e-3))))
    terms = np.array([rng.uniform(0.5, 4.0)] + list(rng.normal(size=3) / h ** np.arange(1, 4)
                                                     * np.exp(rng.uniform(-4.0, 0.0, 3))))
    modes = rows * rates if rate else rows
    if rate:
        terms = terms[1:] * np.arange(1, 4)

    def value(t):
        t = np.asarray(t)[..., None]
        slow = (terms * t ** np.arange(len(terms))).sum(axis=-1)
        return slow + (modes * start * np.exp(rates * t)).real.sum(axis=-1)

    powers = np.abs(terms[1:]) * h ** np.arange(1, len(terms))
    step = ModalStep(np.array([count]), rates[None, :], np.abs(start), start.copy(),
                     start * np.exp(rates * h))
    slow = exponential.SlowBound(terms[0], powers.sum(), powers[1:].sum())
    return value, step, rows[None, :], np.abs(rows)[None, :], slow, h


def test_a_step_certified_to_keep_its_sign_keeps_it():
    """exponential.keeps_sign on 3000 random functions (random_function): wherever it
    certifies that f > 0 (or f < 0) over the step, f sampled at 4001 times of the step keeps
    that sign (the sign of the ends alone is wrong on 59 of the 2 835 it would certify). The
    chord bound certifies what the first bound (slow part less all that can move) cannot: at
    least a fifth of those certified (measured 1 149 of 2 470, of the 2 776 functions that
    keep their sign)."""
    rng = np.random.default_rng(24)
    certified = by_chord = 0
    for _ in range(3000):
        value, step, rows, sizes, slow, h = random_function(rng)
        values = value(np.linspace(0.0, h, 4001))
        swing = float((sizes[0] * step.start_size).sum())
        for sign in (1.0, -1.0):
            if exponential.keeps_sign(step, 0, h, sizes, rows, slow, swing, sign,
                                      values[0], values[-1]):
                certified += 1
                by_chord += not sign * slow.start > slow.drift + swing
                assert (sign * values).min() > 0.0
    assert by_chord >= 0.2 * certified > 0


def test_a_rate_certified_to_keep_its_sign_keeps_it():
    """exponential._keeps_sign of a function's rate (`derivative`: each mode's row times its
    eigenvalue, its magnitude times |λ|) on 3000 random functions (random_function): wherever
    it certifies that f' > 0 (or < 0) over the step, f' sampled at 4001 times of the step
    keeps that sign, so f is monotone there (approach_monotone's certificate). It certifies
    at least a third of the rates that keep their sign (measured 549 of 1 287)."""
    rng = np.random.default_rng(24)
    certified = kept = 0
    for _ in range(3000):
        rate, step, rows, sizes, slow, h = random_function(rng, rate=True)
        values = rate(np.linspace(0.0, h, 4001))
        swing = float((sizes[0] * np.abs(step.rates[0]) * step.start_size).sum())
        for sign in (1.0, -1.0):
            kept += (sign * values).min() > 0.0
            if exponential._keeps_sign(step, 0, h, sizes, rows, slow, swing, sign,
                                       values[0], values[-1], True):
                certified += 1
                assert (sign * values).min() > 0.0
    assert certified >= kept / 3 > 0


def test_the_chord_bound_is_the_least_of_the_parabola_through_the_ends():
    """exponential.chord_low on 2000 random ends and bows (a fifth with no bow): the least of
    the parabola start + (end − start)·s − bow·s·(1 − s) sampled at 20 001 points of [0, 1]
    lies within 1e-9·bow above it and never below it; it is never below the smaller end less
    bow/4 (the parabola's depth with equal ends), and where the ends differ by at least `bow`
    it is the smaller end."""
    rng = np.random.default_rng(7)
    s = np.linspace(0.0, 1.0, 20001)
    for _ in range(2000):
        start, end = rng.normal(size=2) * np.exp(rng.uniform(-3.0, 1.0, 2))
        bow = 0.0 if rng.uniform() < 0.2 else float(np.exp(rng.uniform(-4.0, 2.0)))
        low = exponential.chord_low(start, end, bow)
        sampled = (start + (end - start) * s - bow * s * (1.0 - s)).min()
        assert low <= sampled + 1e-12 and sampled - low <= 1e-9 * bow + 1e-15
        assert low >= min(start, end) - 0.25 * bow - 1e-15
        if abs(start - end) >= bow:
            assert low == min(start, end)


def test_a_step_ends_with_the_approach_slopes_of_its_end():
    """The grazing check of a step starts from the approach slopes at its start, which the
    step before it handed on: after every step of separation's run, those slopes are the
    approach rates at the run's state (equations.approach_rates), to rounding, or marked not
    taken (NaN: after an exact step, which needs none; the next check takes them), never an
    older step's."""
    from herringbone.integrate.compiled import walk
    from herringbone.integrate.compiled_stepper import StepBudgetExceeded
    from herringbone.model import equations

    scene = herringbone.load_scene(MODELS / "separation.toml")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7, "exponential")
    run_ = stepper.start(start_position(model, 500.0))
    stepper.run_to(run_, 0.0045, (500.0, 0.0))
    rate, expected = np.empty(len(run_.state)), np.empty(stepper.tables.shape[2])
    taken = not_taken = 0
    for _ in range(200):
        try:
            stepper.run_to(run_, 0.01, (500.0, 0.0), max_steps=1)
        except StepBudgetExceeded:
            pass
        interval, count = int(run_.place[0]), int(stepper.counts[int(run_.place[0])])
        points = stepper.tables[interval]
        equations.derivative(model.system, points, count, run_.loaded, 500.0, 0.0, run_.state,
                             rate)
        equations.approach_rates(model.system, points, count, run_.state, rate, expected)
        slopes = run_.workspace[1][walk.Values.SLOPES_BEFORE, :count]  # (its values)
        if np.isnan(slopes[0]):
            not_taken += 1
            continue
        taken += 1
        assert np.allclose(slopes, expected[:count], rtol=1e-9,
                           atol=1e-9 * np.abs(expected[:count]).max())
    assert taken >= 5 and not_taken >= 20, (taken, not_taken)



def test_a_train_at_rest_on_an_end_of_its_interval_stands_in_long_steps(reference_scene):
    """At rest with no torque, its pinion where a point enters and every point touching
    unloaded, the train stands: nothing bounds the angle inside its interval or the approach
    away from zero (both are zero), and the steps had shrunk to a sixty-fourth of the exact
    floor, 30 700 in 20 ms driven every 1 ms (DOP853 takes 602). Standing, it is certified in
    steps that grow (25), and the state stays exactly where it was."""
    scene = reference_scene.with_parameters(w0_pinion=0.0).with_inputs(M_motor=0.0,
                                                                       M_load=0.0)
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7, method="exponential")
    at_rest = stepper.start(start_position(model, 0.0))
    start = at_rest.state.copy()
    for k in range(1, 21):
        stepper.run_to(at_rest, k * 1e-3, (0.0, 0.0))
    assert stepper.accepted_steps <= 100
    assert np.array_equal(at_rest.state, start)
