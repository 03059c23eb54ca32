"""Static equilibrium at t = 0 (docs/model.md sections 6-7): every output of the first sample."""
import math
from dataclasses import replace

import numpy as np
import pytest
from helpers import force_error
from helpers.independent_model import bearing_positions, radii, static_state

import herringbone
from herringbone.integrate.contract import start_position
from herringbone.model import scene as scene_module
from herringbone.model.assembly import GearTrainModel
from herringbone.model.parameters import PARAMETERS, POSITIVE
from herringbone.model.scene import SceneError

STATIC_TOLERANCE = 1e-9  # relative: the start is an exact linear solve


def first_sample(scene):
    results = herringbone.reference_simulate(scene, stop_time=1e-5, output_interval=1e-5)
    return {name: values[0] for name, values in results.items()}


def lever_rule(point_forces, zeta_left, zeta_right):
    """Bearing reactions of a body loaded by −F_k at lever arms ζ_k (the pinion's side)."""
    total = sum(f for _, _, f in point_forces)
    moment = sum(f * zeta for _, zeta, f in point_forces)
    right = (moment - total * zeta_left) / (zeta_right - zeta_left)
    return total - right, right


@pytest.mark.parametrize("changes", [
    {},
    {"b_left": 0.030, "b_right": 0.045, "a_left": 0.015, "a_right": 0.035},
    {"b_left": 0.050, "a_right": 0.0, "groove": 0.0, "c_brg_pinion_left": 2e8},
    {"dbeta_left": 7.5e-5, "dbeta_right": -2.5e-5},
])
def test_static_equilibrium(reference_scene, changes):
    scene = reference_scene.with_parameters(**changes)
    p = scene.parameters
    motor_torque = scene.inputs.M_motor[0]
    rp, rw = radii(p)
    out = first_sample(scene)
    mesh_force = motor_torque / rp
    assert out["F_mesh"] == pytest.approx(mesh_force, rel=STATIC_TOLERANCE)
    assert out["T_shaft_in"] == pytest.approx(motor_torque, rel=STATIC_TOLERANCE)
    assert out["T_shaft_out"] == pytest.approx(motor_torque * rw / rp, rel=STATIC_TOLERANCE)

    _, point_forces = static_state(p, motor_torque)
    zeta_left, zeta_right = bearing_positions(p)
    left, right = lever_rule(point_forces, zeta_left, zeta_right)
    scale = STATIC_TOLERANCE * mesh_force
    # the pinion is pushed by −F_k, the wheel by +F_k
    assert out["F_brg_pinion_left"] == pytest.approx(-left, abs=scale)
    assert out["F_brg_pinion_right"] == pytest.approx(-right, abs=scale)
    assert out["F_brg_wheel_left"] == pytest.approx(left, abs=scale)
    assert out["F_brg_wheel_right"] == pytest.approx(right, abs=scale)
    assert out["F_brg_pinion_left"] + out["F_brg_pinion_right"] == pytest.approx(-mesh_force,
                                                                                 abs=scale)
    for half in ("left", "right"):
        expected = sum(f for h, _, f in point_forces if h == half)
        assert out[f"F_mesh_{half}"] == pytest.approx(expected, abs=scale)


def test_symmetric_gear_splits_load_evenly(reference_scene):
    out = first_sample(reference_scene)
    assert out["F_mesh_left"] == pytest.approx(out["F_mesh"] / 2, rel=1e-12)
    assert out["F_brg_pinion_left"] == pytest.approx(-out["F_mesh"] / 2, rel=1e-12)
    assert out["n_contacts"] == 6
    assert out["k_mesh"] == pytest.approx(6 * 2.5e8)


def test_torsional_scene_statics(torsional_scene):
    out = first_sample(torsional_scene)
    rp, rw = radii(torsional_scene.parameters)
    assert out["F_mesh"] == pytest.approx(500 / rp, rel=STATIC_TOLERANCE)
    # rigid bearings: dte is the mesh approach alone, F / Σc
    assert out["dte"] == pytest.approx(out["F_mesh"] / out["k_mesh"], rel=STATIC_TOLERANCE)
    assert not any(name.startswith("F_brg") for name in out)


def test_helix_error_moves_load_to_the_other_half(reference_scene):
    """A positive helix error of a half adds interference to its points, so it takes load from
    the other half; the sign flipped moves it back."""
    base = first_sample(reference_scene)
    for half, other in (("left", "right"), ("right", "left")):
        for sign in (1.0, -1.0):
            out = first_sample(reference_scene.with_parameters(**{f"dbeta_{half}": sign * 5e-5}))
            shift = out[f"F_mesh_{half}"] - base[f"F_mesh_{half}"]
            assert sign * shift > 0.01 * base["F_mesh"]  # 5e-5 rad: 1.4 % of the load
            assert out[f"F_mesh_{other}"] - base[f"F_mesh_{other}"] == pytest.approx(-shift,
                                                                                  rel=1e-9)


@pytest.mark.parametrize("phase0", [0.0, 1.1754943508222875e-38])
def test_a_train_turning_backwards_from_a_switch_starts_static_in_the_set_it_turns_into(
        reference_scene, phase0):
    """The reference scene turned backwards (w0_pinion −157.08 rad/s) starts at φp = 0, on a
    switch: its contact set is the one that ends there, the one the pinion turns into, and the
    start is that set's static equilibrium, so the mesh force holds until the next switch
    (2.9 ms away). Started in the set that begins there (six points, not four), the train left
    it at once: the two integrators gave the outputs before and after that switch at t = 0,
    0.33 of the force scale apart, and the run opened with a transient. A phase0 of 1e-38 (the
    property tests' draw: tests/regression/found_1553e03b40.toml) put that switch at phase
    1.0 instead of 0 (Python's −1e-38 % 1.0 is 1.0), where the rule did not see it."""
    scene = reference_scene.with_parameters(w0_pinion=-157.08, phase0=phase0)
    model = GearTrainModel(scene)
    contact_set = start_position(model, scene.inputs.at(0.0)[0]).segment.contact_set
    assert contact_set.pinion_angle + contact_set.length == pytest.approx(0.0, abs=1e-12)
    compiled = herringbone.simulate(scene, stop_time=0.002, output_interval=1e-5)
    reference = herringbone.reference_simulate(scene, stop_time=0.002, output_interval=1e-5)
    assert force_error(compiled, reference, model) <= STATIC_TOLERANCE
    for run in (compiled, reference):
        assert np.ptp(run["F_mesh"]) <= STATIC_TOLERANCE * model.force_scale()
        assert np.all(run["n_contacts"] == len(contact_set))


def test_stiffnesses_too_far_apart_for_double_precision_are_named_not_a_linalg_error(
        monkeypatch):
    """c_point = 1e30 N/m beside bearings of 5e8 N/m makes the stiffness matrix singular in
    double precision: the run says so, naming the two extremes, where numpy said "Singular
    matrix". The ranges refuse such a c_point now (a thousand times a mill gear's: 1e13 N/m),
    and no train within them was found singular; the message stays for one, taken here with
    the range and the time scales lifted."""
    with pytest.raises(SceneError, match=r"c_point is 1e\+30 N/m; allowed: \[1000, 1e\+13\]"):
        herringbone.load_scene("reference").with_parameters(c_point=1e30)
    monkeypatch.setitem(PARAMETERS, "c_point", replace(PARAMETERS["c_point"], allowed=POSITIVE))
    monkeypatch.setattr(scene_module, "FASTEST_RING", math.inf)
    monkeypatch.setattr(scene_module, "FASTEST_DAMPING", math.inf)
    scene = herringbone.load_scene("reference").with_parameters(c_point=1e30)
    with pytest.raises(ValueError) as error:
        herringbone.simulate(scene, stop_time=1e-3, output_interval=1e-4)
    message = str(error.value)
    assert "stiffness matrix is singular in double precision" in message
    assert "c_point = 1e+30 N/m" in message and "c_brg_pinion_left = 5e+08 N/m" in message
