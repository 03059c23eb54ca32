"""The measurement behind docs/exponential-variable-segments.md: a Lawson Runge-Kutta scheme on
the contact set's modal form (tests/helpers/lawson.py) for the segments that the exponential
method cannot take exactly. Checked here: the scheme itself (exact where the frozen form is the
true system, and as accurate as the tolerance asks against scipy's DOP853 at 1e-12 where it is
not), and the step counts that made it not worth compiling (benchmarks/exponential_variable.py
prints them for four scenes with the compiled costs)."""
import numpy as np
import pytest
import scipy.linalg
from helpers import MODELS, held_speed, lawson
from scipy.integrate import solve_ivp

import herringbone

# A Lawson-DOP853 step costs a DOP853 step (1.76 µs compiled) plus, for each of its 11 later
# stages, a product by L and one by R (0.32 µs together), at least: 3.0 DOP853 steps. On the
# tabulated forms it pays only where it takes fewer than a third of DOP853's steps; on a
# Jacobian refreshed at every step it adds that Jacobian's modal form (a compiled eig of the
# 19×19 Â alone: 0.19 ms, a hundred DOP853 steps), so a tenth of the steps would not do.
FROZEN_BREAK_EVEN = 1.0 / 3.0
JACOBIAN_FAR_FROM_PAYING = 1.0 / 10.0


def segments(name, count=2):
    return lawson.segments_after_switches(herringbone.load_scene(MODELS / f"{name}.toml"),
                                          count, 0.01)


def test_lawson_step_exact_where_the_frozen_form_is_the_system():
    """On the reference scene a segment's frozen linear system is exact (its tilt stays zero):
    N vanishes, so the Lawson scheme's error estimate is rounding and a whole segment takes
    the few steps the controller needs to grow to it, landing on the matrix exponential's
    solution."""
    _, stepper, found = segments("reference", 1)
    segment, state, span = found[0]
    result = lawson.integrate(segment, state, span, stepper.absolute_tolerance,
                              stepper.step_tolerance, stepper.max_step / 4,
                              form=lawson.frozen(segment))
    exact = (scipy.linalg.expm(lawson.frozen_form(segment) * span)
             @ np.concatenate([state, lawson.inputs(segment)]))[:len(state)]
    assert result.accepted <= 4 and result.rejected == 0
    assert np.max(np.abs(result.state - exact) / stepper.absolute_tolerance) < 1e-2


@pytest.mark.parametrize("name", ["lead_error", "contact_loss"])
def test_lawson_agrees_with_scipy_on_segments_that_are_not_exact(name):
    """Where N does not vanish (lead-error slopes; a partially loaded set) the scheme, frozen
    form or Jacobian at each step, ends each segment within a few absolute tolerances of
    scipy's DOP853 at 1e-12, as the plain DOP853 pair does."""
    _, stepper, found = segments(name, 2)
    absolute, relative = stepper.absolute_tolerance, stepper.step_tolerance
    scales = absolute / relative
    for segment, state, span in found:
        reference = solve_ivp(lambda _t, x, s=segment: lawson.rate(s, x), (0.0, span), state,
                              method="DOP853", rtol=1e-12, atol=1e-5 * absolute).y[:, -1]
        forms = (None, lawson.frozen(segment), lawson.linearized(segment, scales))
        for form in forms:
            result = lawson.integrate(segment, state, span, absolute, relative,
                                      stepper.max_step / 4, form=form)
            assert np.max(np.abs(result.state - reference) / absolute) < 5.0


@pytest.mark.parametrize("name", ["lead_error", "staggered"])
def test_lawson_steps_do_not_pay(name):
    """The figure that kept the scheme out of the compiled loop: over whole segments from
    their switches, Lawson-DOP853 on the set's frozen form takes more than a third of
    DOP853's steps (with the stepper's step bound), so at three DOP853 steps' cost a step it
    is slower; on the Jacobian refreshed at every step (the limit of any finer table) it
    still takes more than a tenth of them, each at the cost of a modal decomposition."""
    _, stepper, found = segments(name, 2)
    absolute, relative = stepper.absolute_tolerance, stepper.step_tolerance
    scales = absolute / relative
    steps = {"dop853": 0, "frozen": 0, "jacobian": 0}
    for segment, state, span in found:
        h = stepper.max_step / 4
        steps["dop853"] += lawson.integrate(segment, state, span, absolute, relative, h,
                                            max_step=stepper.max_step).accepted
        steps["frozen"] += lawson.integrate(
            segment, state, span, absolute, relative, h,
            form=lawson.frozen(segment)).accepted
        steps["jacobian"] += lawson.integrate(
            segment, state, span, absolute, relative, h,
            form=lawson.linearized(segment, scales)).accepted
    assert steps["frozen"] > FROZEN_BREAK_EVEN * steps["dop853"]
    assert steps["jacobian"] > JACOBIAN_FAR_FROM_PAYING * steps["dop853"]


# --- a transition at a held speed, corrected to first order (tests/helpers/held_speed.py) ------

@pytest.mark.parametrize("name", ["lead_error", "contact_loss"])
def test_a_segment_is_linear_in_the_state_where_the_pinion_angle_is_given(name):
    """The premise of the held-speed transition: for a given pinion angle the model's
    derivative is A(s)·x + B(s)·u, exponential.linear_system on the point table moved to that
    angle; with s the state's own angle it is the model's derivative (equations.derivative)
    to rounding, at the segment's start and at states strayed from it."""
    model, _, found = segments(name)
    scales = model.state_scales()
    random = np.random.default_rng(3)
    for segment, state, span in found:
        for stray in [np.zeros_like(state), *(random.normal(size=(3, len(state))) * scales)]:
            x = state + 0.1 * stray
            x[model.pinion] = state[model.pinion] + random.uniform(0.0, 0.9) * span \
                * state[len(state) // 2 + model.pinion]
            expected = lawson.rate(segment, x)
            assert np.allclose(held_speed.rate_at(segment, x, x[model.pinion]), expected,
                               rtol=1e-12, atol=1e-12 * np.abs(expected).max())


def test_a_held_speed_run_corrected_to_first_order_leaves_the_departure_squared():
    """On lead_error's sets (a lead-error slope drives the tilt, so the lever arms' travel
    reaches the forces) the segment run with its points moved at the train's rigid speed
    lands 6.5e-6 and 1.6e-5 of the force scale from the model's own run, and its first-order
    correction in the pinion's departure 2.9e-9 and 4.3e-9 (docs/exponential-variable-
    segments.md): within a tenth of the bar's 1e-7 and a thousandth of the held run's error."""
    model, stepper, found = segments("lead_error")
    absolute = 1e-7 * stepper.absolute_tolerance
    for segment, state, span in found:
        nominal = held_speed.held_motion(segment, state, model.pinion)
        own = held_speed.model_end(segment, state, span, absolute)
        held = held_speed.corrected_end(segment, state, span, absolute, nominal, model.pinion,
                                        order=0)
        corrected = held_speed.corrected_end(segment, state, span, absolute, nominal,
                                             model.pinion)
        held_error = held_speed.force_error_between(model, segment, held, own)
        corrected_error = held_speed.force_error_between(model, segment, corrected, own)
        assert held_error > 1e-6, held_error
        assert corrected_error < 1e-8 and corrected_error < held_error / 1000, (
            corrected_error, held_error)


def test_the_correction_is_a_quadratic_form_that_tables_made_once_per_set_hold():
    """The held-speed run and its first-order correction, made once for a set and a held
    motion as a transition of [x; u] and a quadratic form of it (held_speed.set_tables),
    give the jointly integrated correction from any start: on lead_error's first set to
    1e-10 of the force scale from the start they were made at, and within 1e-8 of the model's
    own run from a start strayed by 1e-3 of every state scale (2.2e-9 measured)."""
    model, stepper, found = segments("lead_error", 1)
    segment, state, span = found[0]
    absolute = 1e-7 * stepper.absolute_tolerance
    nominal = held_speed.held_motion(segment, state, model.pinion)
    tables = held_speed.set_tables(segment, span, nominal, model.pinion,
                                   held_speed.augmented_scales(model))
    joint = held_speed.corrected_end(segment, state, span, absolute, nominal, model.pinion)
    assert held_speed.force_error_between(
        model, segment, held_speed.tabulated_end(tables, segment, state), joint) < 1e-10
    strayed = state + 1e-3 * model.state_scales() * np.random.default_rng(1).normal(
        size=len(state))
    strayed[model.pinion] = state[model.pinion]
    own = held_speed.model_end(segment, strayed, span, absolute)
    assert held_speed.force_error_between(
        model, segment, held_speed.tabulated_end(tables, segment, strayed), own) < 1e-8


def test_the_second_order_term_takes_contact_loss_below_the_bar():
    """contact_loss's held runs lie ten times further off than the other scenes', and its
    first-order correction leaves 4.9e-8 and 2.5e-7 of the force scale on its first two sets;
    the second-order term in the departure takes them to 2.9e-11 and 9.5e-11
    (docs/exponential-variable-segments.md): below 1e-9 and a hundredth of the first order's."""
    model, stepper, found = segments("contact_loss")
    absolute = 1e-7 * stepper.absolute_tolerance
    for segment, state, span in found:
        nominal = held_speed.held_motion(segment, state, model.pinion)
        own = held_speed.model_end(segment, state, span, absolute)
        first, second = (
            held_speed.force_error_between(model, segment, held_speed.corrected_end(
                segment, state, span, absolute, nominal, model.pinion, order), own)
            for order in (1, 2))
        assert second < 1e-9 and second < first / 100, (second, first)
