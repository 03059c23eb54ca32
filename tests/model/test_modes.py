"""Natural frequencies of the reference scene at φp = 0 (docs/model.md section 10)."""
import math

import numpy as np
import pytest
import scipy.linalg
from helpers.independent_model import ORDER, mass_matrix, stiffness_matrix

import herringbone.model.assembly

MODEL_MD_FREQUENCIES_HZ = [113, 688, 1.50e3, 2.10e3, 4.44e3, 12.0e3, 13.8e3]


def frequencies(stiffness, mass):
    eigenvalues = scipy.linalg.eigh(stiffness, mass, eigvals_only=True)
    return np.sqrt(np.clip(eigenvalues, 0, None)) / (2 * math.pi)


def test_independent_assembly_matches_model_md(reference_scene):
    p = reference_scene.parameters
    f = frequencies(stiffness_matrix(p, 0.0), mass_matrix(p))
    assert f[0] < 1e-3  # the rigid rotation
    # docs/model.md gives three significant figures: 0.5 % covers their rounding
    assert f[1:] == pytest.approx(MODEL_MD_FREQUENCIES_HZ, rel=5e-3)


def test_package_modes_match_independent_assembly(reference_scene):
    p = reference_scene.parameters
    expected = frequencies(stiffness_matrix(p, 0.0), mass_matrix(p))
    f, shapes, names = herringbone.model.assembly.natural_modes(reference_scene, pinion_angle=0.0)
    assert names == ORDER
    assert f[1:] == pytest.approx(expected[1:], rel=1e-9)
    # the zero mode is the rigid rotation: angles in the ratio 1 : 1 : 1/u : 1/u
    rigid = shapes[:, 0] / shapes[1, 0]
    u = p["z_wheel"] / p["z_pinion"]
    assert rigid == pytest.approx([1, 1, 0, 0, 1 / u, 0, 0, 1 / u], abs=1e-9)


def test_mean_stiffness_is_period_average(reference_scene):
    """The mean mesh stiffness of docs/model.md (about 1.08e9 N/m) is Σ over streams of c·b/p_x."""
    model = herringbone.model.assembly.GearTrainModel(reference_scene)
    assert model.mesh.mean_stiffness() == pytest.approx(1.082e9, rel=1e-3)
    angles = np.linspace(0, 2 * math.pi / 10, 2001)[:-1]
    sampled = np.mean([stiffness_matrix(reference_scene.parameters, a) for a in angles], axis=0)
    assert model.mean_stiffness_matrix() == pytest.approx(sampled, rel=2e-3, abs=1e-3)
