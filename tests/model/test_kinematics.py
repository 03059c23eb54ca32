"""Rigid kinematics: speed ratio and the contact count of the four streams (docs/model.md
sections 3, 8)."""
import math

import numpy as np
import pytest
from helpers.independent_model import contact_points

import herringbone
from herringbone.analysis.phasing import alternation_law, scene_phasing


def test_mean_speed_ratio_is_one_over_u(reference_scene):
    results = herringbone.reference_simulate(reference_scene, stop_time=0.04,
                                             output_interval=1e-5)
    u = reference_scene.parameters["z_wheel"] / reference_scene.parameters["z_pinion"]
    # the mean ratio differs from 1/u only by the change of dte over the run: |Δdte|/(Rw·Δφw)
    ratio = np.trapezoid(results["w_wheel"], results["time"]) / np.trapezoid(
        results["w_pinion"], results["time"])
    assert ratio == pytest.approx(1 / u, rel=1e-4)
    assert np.ptp(results["w_pinion"]) > 0  # the mesh does excite the train


@pytest.mark.parametrize("changes, law", [
    ({}, [6, 4, 6, 4]),
    ({"stagger": 0.5}, [5, 4, 5, 4, 5, 4, 5, 4]),
    ({"stagger": 0.25, "phase0": 0.3}, None),
    ({"eps_q": 0.3, "b_right": 0.05}, None),
])
def test_contact_count_follows_the_streams(reference_scene, changes, law):
    """Without torque the train turns rigidly at w0, so φp(t) = w0·t exactly and n_contacts must
    equal the number of points on the faces, counted from docs/model.md section 3 by hand."""
    scene = reference_scene.with_parameters(contact_loss=False, **changes).with_inputs(
        M_motor=0.0, M_load=0.0)
    w0 = scene.parameters["w0_pinion"]
    period = 2 * math.pi / scene.parameters["z_pinion"] / w0
    results = herringbone.reference_simulate(scene, stop_time=period,
                                             output_interval=period / 997)
    # the last sample, t = one period, falls on a switch: rounding may put it on either side
    inside = results["time"] < period * (1 - 1e-9)
    expected = [len(contact_points(scene.parameters, w0 * t)) for t in results["time"][inside]]
    assert results["n_contacts"][inside] == pytest.approx(expected)
    runs = "-".join(str(int(n)) for i, n in enumerate(results["n_contacts"][inside])
                    if i == 0 or n != results["n_contacts"][i - 1])
    # the alternation law of the four streams (Kryukov & Savelieva, docs/model.md section 8)
    assert runs == alternation_law(scene_phasing(scene).streams)
    if law is not None:
        assert runs == "-".join(map(str, law))
