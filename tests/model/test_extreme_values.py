"""Extreme values of the model's inputs (a fuzzer's report, 2026-11-30): each gets one
SceneError naming the culprit and what is allowed, before any work, or runs meaningfully.

Before: edge_ramp = 1e-20 m ran without a mesh force; values inside the old ranges ran without
end (c_point = 9.2e18, m_n = 1e-30), failed inside the model (m_n = 1e-300: ZeroDivisionError;
m_n = 1e300: OverflowError; 1.7e308: AssertionError) or ran meaningless (beta = 1e-30: no mesh
force; c_point = 1: a static deflection of 3.8 km); an int too large for a float raised
OverflowError.
"""
import glob
import math
import warnings

import numpy as np
import pytest
from helpers import MODELS, REGRESSION
from helpers.scene_distribution import draw_scene_data, random_scene

import herringbone
from herringbone.model.assembly import GearTrainModel, natural_modes
from herringbone.model.mesh import Mesh
from herringbone.model.parameters import INPUTS, PARAMETERS, values_problem
from herringbone.model.scene import FASTEST_DAMPING, FASTEST_RING, SceneError, element_rates


def refused(parameters, components=None):
    """The SceneError scene_from_dict raises for these parameters (the test fails if it
    raises none, or another exception)."""
    data = {"parameters": parameters}
    if components is not None:
        data["components"] = components
    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict(data)
    message = str(raised.value)
    assert "\n" not in message and "allowed:" in message, message
    return raised.value


# --- 1. an edge ramp too short to resolve acts as sharp edges ----------------------------------

@pytest.mark.parametrize("ramp", [1e-20, 1e-30, 1e-300, 3e-10])
def test_an_edge_ramp_too_short_to_resolve_acts_as_sharp_edges(ramp):
    """edge_ramp = 1e-20 m gave every point weight 0 ((z + r) − (z − r) rounds to 0): k_mesh,
    F_mesh and n_contacts 0 for the whole run, which ended as a success. A ramp under 1e-8 of
    the wider face (3.5e-10 m here) is taken as sharp edges: the run is the sharp one's."""
    sharp = herringbone.scene_from_dict({"parameters": {"edge_ramp": 0.0}})
    ramped = herringbone.scene_from_dict({"parameters": {"edge_ramp": ramp}})
    assert ramped.parameters["edge_ramp"] == ramp  # the scene keeps what it was given
    a, b = Mesh(sharp.parameters), Mesh(ramped.parameters)
    assert np.array_equal(a.switch_phases, b.switch_phases)
    for interval in range(len(a.switch_phases)):
        assert np.array_equal(a.contact_set(0, interval).table, b.contact_set(0, interval).table)
    span = dict(stop_time=2e-3, output_interval=2e-4)
    run = herringbone.simulate(ramped, **span)
    assert run["F_mesh"].min() > 0.0 and run["n_contacts"].min() >= 4
    assert np.array_equal(run["F_mesh"], herringbone.simulate(sharp, **span)["F_mesh"])


def test_an_edge_ramp_that_resolves_keeps_its_ramp():
    """1e-9 m on the reference's 35 mm faces is above 1e-8 of them: a ramp, its kinks apart."""
    ramped = herringbone.scene_from_dict({"parameters": {"edge_ramp": 1e-9}})
    mesh = Mesh(ramped.parameters)
    assert mesh.edge_ramp == 1e-9
    sharp = herringbone.scene_from_dict({})
    assert len(mesh.switch_phases) > len(Mesh(sharp.parameters).switch_phases)


# --- 2. values that ran without end or for minutes ---------------------------------------------

@pytest.mark.parametrize("name, value", [
    ("c_point", 9.2e18), ("C_shaft_in", 9.2e18), ("C_shaft_out", 9.2e18),
    ("c_brg_pinion_left", 9.2e18), ("c_brg_wheel_right", 9.2e18), ("b_left", 9.2e18),
    ("b_right", 9.2e18), ("groove", 9.2e18), ("m_n", 1e-30), ("m_n", 9.2e18),
    ("beta", 1e-30), ("c_point", 1.0),
])
def test_a_value_that_ran_without_end_or_meaningless_is_refused_by_its_range(name, value):
    error = refused({name: value})
    assert error.key == name
    assert error.problem.startswith(f"{name} is {value!r}")
    assert f"allowed: {PARAMETERS[name].allowed.describe()}" in error.problem


@pytest.mark.parametrize("module", [1e-6, 1e-7])
def test_a_face_of_more_than_200_axial_pitches_is_refused_naming_the_module(module):
    """m_n = 1e-7 m put 43 000 axial pitches on the 35 mm face (two contact points each, a
    stream each): `info` took 5.5 s, m_n = 1e-30 never returned. At most 200 a face."""
    if not PARAMETERS["m_n"].allowed.contains(module):
        error = refused({"m_n": module})
        assert error.key == "m_n"
        return
    error = refused({"m_n": module})
    assert error.key == "b_left"
    assert "m_n 1e-06 m" in error.problem and "at most 200 pitches a face" in error.problem
    # the same module on faces of 200 pitches is a train
    pitch = math.pi * module / math.sin(PARAMETERS["beta"].default)
    herringbone.scene_from_dict({"parameters": {"m_n": module, "b_left": 200 * pitch,
                                                "b_right": 200 * pitch, "m_pinion": 1.0}})


# --- 3. values that failed inside the model ----------------------------------------------------

@pytest.mark.parametrize("name, value", [
    ("m_n", 1e-300), ("I_pinion", 5e-324), ("I_wheel", 5e-324), ("beta", 5e-324),
    ("m_n", 1e300), ("b_left", 1e300), ("b_right", 1e300), ("groove", 1e300),
    ("m_n", 1.7e308), ("c_point", 1e300), ("a_left", 1e300), ("m_pinion", 1e300),
    ("m_pinion", 1e-300), ("C_shaft_in", 1e-300), ("h_brg_wheel_left", 1e300),
    ("zeta_mesh", 1e300), ("J_pinion", 1e-300), ("dbeta_left", 1e300), ("edge_ramp", 1e300),
])
def test_a_value_that_failed_inside_the_model_is_refused_naming_it(name, value):
    """ZeroDivisionError (_damp_the_mesh), OverflowError (the derived J), a bare
    AssertionError (_assemble_rows), "SVD did not converge": each value is now out of its
    parameter's range, one line naming it."""
    error = refused({name: value})
    assert error.key == name and error.problem.startswith(f"{name} is {value!r}")


@pytest.mark.parametrize("changes, element, key", [
    ({"I_pinion": 1e-18}, "on which the input shaft rings at", "I_pinion"),
    ({"I_motor": 1e-18}, "on which the input shaft rings at", "I_motor"),
    ({"J_wheel": 1e-18}, "on which the left wheel bearing rings at", "J_wheel"),
    ({"m_pinion": 1e-9}, "on which the left pinion bearing rings at", "J_pinion"),
    ({"h_brg_pinion_left": 1e11}, "which damps the left pinion bearing at",
     "h_brg_pinion_left"),
    ({"h_shaft_in": 1e10}, "which damps the input shaft at", "h_shaft_in"),
    ({"I_pinion": 1e-10, "zeta_mesh": 10.0, "motor": False}, "which damps the mesh",
     "zeta_mesh"),
    ({"I_pinion": 1e-12, "motor": False}, "on which the mesh rings at", "I_pinion"),
], ids=["light-pinion", "light-motor", "light-wheel-tilt", "light-pinion-mass",
        "bearing-damping", "shaft-damping", "mesh-damping", "mesh"])
def test_an_element_faster_than_any_gear_train_is_refused_naming_it(changes, element, key):
    """Each value is in its range, but with the reference's others an element rings or damps
    faster than any gear train: I_pinion = 1e-18 failed at the first step ("the step size fell
    below the time's resolution"), m_pinion = 1e-9 and h_brg_pinion_left = 1e11 ran 2 ms for
    over a minute, and `info` lost a mode to rounding."""
    components = {"motor": changes.pop("motor", True)}
    error = refused(changes, components)
    assert error.problem.startswith(f"{key} is ") and element in error.problem
    assert error.key == key
    assert "allowed: up to 1e+08 rad/s" in error.problem \
        or "allowed: up to 1e+09 1/s" in error.problem


def test_a_derived_inertia_out_of_its_range_is_named_with_what_it_follows():
    """J_wheel, not given, follows m_wheel and the geometry: a 1e7 kg wheel of 1 m module and
    1000 teeth is 7e11 kg.m2 about its diameter."""
    error = refused({"m_n": 1.0, "z_wheel": 1000, "m_wheel": 1e7})
    assert error.key == "J_wheel"
    assert "m_wheel 1e+07 kg" in error.problem and "(give J_wheel)" in error.problem


def test_every_single_value_at_a_bound_of_its_range_builds_a_train_or_is_refused():
    """Each parameter at each end of its range, the others the reference's: a scene whose
    model and natural modes are finite, the fastest within what an element may ring at (where
    c_point = 1e300 had `info` list modes of 3e149 Hz), or one SceneError (a value that does
    not go with the others)."""
    for name, p in PARAMETERS.items():
        if p.kind is bool:
            continue
        for bound, is_open in ((p.allowed.low, p.allowed.low_open),
                               (p.allowed.high, p.allowed.high_open)):
            if bound is None or is_open:
                continue
            try:
                scene = herringbone.scene_from_dict({"parameters": {name: p.kind(bound)}})
            except SceneError as error:
                assert "\n" not in str(error) and "allowed:" in str(error)
                continue
            model = GearTrainModel(scene)
            assert np.all(np.isfinite(model.eigenvalues())), (name, bound)
            frequencies, _, _ = natural_modes(scene)
            assert np.all(np.isfinite(frequencies)), (name, bound)
            assert frequencies.max() <= 3.0 * FASTEST_RING / (2.0 * math.pi), (name, bound)


# --- the scenes the project ships and the tests draw stay allowed ------------------------------

class CornerSampler:
    """The random scenes' sampler contract at the ends of each span (Hypothesis favours them):
    every draw is its span's low or high end, as a seeded coin says."""

    def __init__(self, seed):
        self.rng = np.random.default_rng(seed)

    def _end(self, low, high):
        return high if self.rng.uniform() < 0.5 else low

    uniform = log_uniform = _end

    def integer(self, low, high):
        return int(self._end(low, high))

    def chance(self, probability):
        return bool(self.rng.uniform() < 0.5)


def test_shipped_and_drawn_scenes_stay_well_inside_the_bounds():
    """Every scene of models/, examples/ and tests/regression/, the seeded random scenes and
    draws at the ends of every span load, and ring and damp at a tenth of the bounds or less
    (the fastest: stiff_bearings, 2.7e6 rad/s)."""
    scenes = [herringbone.load_scene(path) for path in sorted(
        glob.glob(str(MODELS / "*.toml")) + glob.glob(str(MODELS.parent / "examples" / "*.toml"))
        + glob.glob(str(REGRESSION / "**" / "*.toml"), recursive=True))]
    scenes += [random_scene(seed) for seed in range(200)]
    scenes += [herringbone.scene_from_dict(draw_scene_data(CornerSampler(seed)))
               for seed in range(200)]
    for scene in scenes:
        for what, _, _, _, ring, damping, _ in element_rates(scene.parameters,
                                                             scene.components):
            assert ring <= 0.1 * FASTEST_RING and damping <= 0.1 * FASTEST_DAMPING, \
                (scene.name, what, ring, damping)


# --- 4. Python ints too large for a float ------------------------------------------------------

HUGE = 10 ** 400


@pytest.mark.parametrize("name", [*PARAMETERS, *INPUTS])
def test_an_int_too_large_for_a_float_is_named_not_an_overflow_error(name):
    """float(10**400) raises OverflowError: number_problem took it unguarded, for every
    parameter and input of a scene."""
    table = "inputs" if name in INPUTS else "parameters"
    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict({table: {name: HUGE}})
    message = str(raised.value)
    assert raised.value.key == name and "\n" not in message
    assert "an integer of 401 digits" in message and str(HUGE) not in message


@pytest.mark.parametrize("call, words", [
    (lambda s: s.with_parameters(z_pinion=HUGE),
     "with_parameters: z_pinion is an integer of 401 digits, too large for a float; allowed: "
     "a whole number [1, 1000]"),
    (lambda s: s.with_inputs(M_load=-HUGE),
     "with_inputs: M_load is a negative integer of 401 digits, too large for a float"),
    (lambda s: s.with_inputs(table=[[0, HUGE, 1800]]),
     "table row 0 is [0, an integer of 401 digits, 1800]; allowed: three finite numbers"),
    (lambda s: herringbone.scene_from_dict({"experiment": {"stop_time": HUGE}}),
     "[experiment] stop_time is an integer of 401 digits, too large for a float"),
    (lambda s: herringbone.scene_from_dict({"components": {"motor": 10 ** 5000}}),
     "[components] motor must be true or false, got an integer of 5001 digits"),
    (lambda s: herringbone.scene_from_dict({"parameters": {"contact_loss": 10 ** 5000}}),
     "contact_loss must be true or false, got an integer of 5001 digits"),
], ids=["with_parameters", "with_inputs", "table", "experiment", "component", "flag"])
def test_an_int_too_large_for_a_float_in_any_table_or_call_is_named(reference_scene, call,
                                                                     words):
    with pytest.raises(SceneError) as raised:
        call(reference_scene)
    assert words in str(raised.value)


def test_a_swept_value_too_large_for_a_float_is_named():
    assert values_problem("c_point", [2.5e8, HUGE]) == (
        "c_point is an integer of 401 digits, too large for a float; allowed: [1000, 1e+13] N/m")


# --- 4, 5. the run arguments: their home, herringbone/arguments.py, is another's to edit now ----


@pytest.mark.parametrize("argument", ["stop_time", "output_interval", "tolerance", "max_step"])
def test_a_run_argument_too_large_for_a_float_is_named(reference_scene, argument):
    """simulate(stop_time=10**400) raised OverflowError: int too large to convert to float."""
    with pytest.raises(ValueError, match=rf"^{argument} is an integer of 401 digits, too large "
                                         "for a float; allowed: "):
        herringbone.simulate(reference_scene, **{argument: HUGE})


def test_a_max_step_under_any_trains_time_scale_is_refused_before_any_work(reference_scene):
    """max_step = 1e-300 passed the check ("> 0") and failed at the first step with an
    IntegrationError ("the step size fell below the time's resolution")."""
    with pytest.raises(ValueError, match=r"^max_step is 1e-300; allowed: >= 1e-12 or inf"):
        herringbone.simulate(reference_scene, stop_time=1e-3, max_step=1e-300)


def test_a_max_step_whose_rounding_outweighs_its_steps_is_warned_of(reference_scene):
    """Below 1e-7 s each decade of max_step costs ten times the time and adds error (1.3e-8 of
    the force at 1e-9 s over 10 ms of the reference scene, against 1.9e-10 at 1e-6 s): the run
    goes on, with a MaxStepWarning saying so; at 1e-7 s none."""
    from herringbone.arguments import MaxStepWarning

    with pytest.warns(MaxStepWarning, match=r"^max_step 1e-09 s takes at least 1e\+09 steps a "
                                            r"simulated second, and below 1e-07 s their "
                                            "rounding adds more error"):
        result = herringbone.simulate(reference_scene, stop_time=2e-6, output_interval=1e-6,
                                      max_step=1e-9)
    assert len(result["time"]) > 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", MaxStepWarning)
        herringbone.simulate(reference_scene, stop_time=2e-6, output_interval=1e-6,
                             max_step=1e-7)
