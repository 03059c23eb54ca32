"""Mesh-phase theory (docs/model.md section 8) against the articles and the mesh; the scene
report."""
import math
import re

import numpy as np
import pytest

import herringbone
from herringbone.analysis.phasing import (
    alternation_law,
    contact_count,
    count_intervals,
    phase_overlap,
    scene_phasing,
    spur_contact_ratio,
)
from herringbone.analysis.report import scene_report
from herringbone.cli import main as herringbone_main
from herringbone.model.geometry import GearGeometry
from herringbone.model.mesh import Mesh
from herringbone.shipped import scene_files

REFERENCE = herringbone.scene_from_dict({})
P_X = GearGeometry.from_parameters(REFERENCE.parameters).axial_pitch


# --- Petrovsky: phase overlap -------------------------------------------------------------------

def test_phase_overlap_of_the_elementary_rack_is_0_839():
    eps_q = phase_overlap(alpha_k=math.radians(27.5), alpha_l=math.radians(7.5),
                          rho_f=0.75, rho_a=0.70)
    assert eps_q == pytest.approx(0.8386, abs=1e-4)
    assert round(eps_q, 3) == 0.839


def test_phase_overlap_of_a_rack_without_profile_is_one():
    assert phase_overlap(alpha_k=0.0, alpha_l=0.0, rho_f=0.75, rho_a=0.70) == 1.0


# --- involute spur contact ratio ----------------------------------------------------------------

def line_of_action_contact_ratio(z1, z2, x1, x2, alpha=math.radians(20), ha=1.0, m=1.0):
    """ε_α = (√(ra1²−rb1²) + √(ra2²−rb2²) − a_w·sin α_w)/(π·m·cos α), α_w by bisection."""
    target = 2 * (x1 + x2) * math.tan(alpha) / (z1 + z2) + math.tan(alpha) - alpha
    low, high = 0.0, 1.5
    for _ in range(200):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if math.tan(middle) - middle < target else (low, middle)
    alpha_w = 0.5 * (low + high)
    a_w = m * (z1 + z2) / 2 * math.cos(alpha) / math.cos(alpha_w)
    shortening = x1 + x2 - (a_w / m - (z1 + z2) / 2)
    path = -a_w * math.sin(alpha_w)
    for z, x in ((z1, x1), (z2, x2)):
        r_a = m * (z / 2 + ha + x - shortening)
        r_b = m * z / 2 * math.cos(alpha)
        path += math.sqrt(r_a ** 2 - r_b ** 2)
    return path / (math.pi * m * math.cos(alpha))


def test_spur_contact_ratio_of_a_standard_20_20_pair_is_the_textbook_1_557():
    assert spur_contact_ratio(20, 20) == pytest.approx(1.5568, abs=1e-4)


@pytest.mark.parametrize("z1, z2, x1, x2", [(20, 20, 0.0, 0.0), (20, 40, 0.5, 0.3),
                                            (12, 30, 0.4, 0.0), (17, 60, 0.3, -0.3),
                                            (25, 25, -0.2, -0.1)])
def test_spur_contact_ratio_agrees_with_the_line_of_action(z1, z2, x1, x2):
    assert spur_contact_ratio(z1, z2, x1, x2) == pytest.approx(
        line_of_action_contact_ratio(z1, z2, x1, x2), abs=1e-9)


def test_spur_contact_ratio_of_shifted_pairs():
    assert spur_contact_ratio(20, 40, 0.5, 0.3) == pytest.approx(1.4090, abs=1e-4)
    # x1 = −x2 keeps α_w = α and the tips move: d_a = 19.6, 61.4 modules, tan α_a = 0.7113,
    # 0.4311; (17·0.7113 + 60·0.4311 − 77·tan 20°)/2π = 1.5807, less than 1.649 unshifted
    assert spur_contact_ratio(17, 60, 0.3, -0.3) == pytest.approx(1.5807, abs=1e-4)
    assert spur_contact_ratio(17, 60) == pytest.approx(1.649, abs=1e-3)


# --- Kryukov & Savelieva: alternation laws ------------------------------------------------------

def test_two_in_phase_streams_of_1_6_alternate_4_2():
    assert alternation_law([(1.6, 0.0), (1.6, 0.0)]) == "4-2"


def test_alternation_laws_of_shifted_streams():
    assert alternation_law([(1.5, 0.0), (1.5, 0.25)]) == "3-4-3-2"
    assert alternation_law([(1.6, 0.0), (1.6, 0.5)]) == "4-3-4-3"
    assert alternation_law([(3.0, 0.3)]) == "3"
    # read from phase 0, not wrapped: the law ends on its first value
    assert alternation_law([(1.5, 0.1)]) == "1-2-1"


def test_count_function_of_the_phase():
    streams = [(1.5, 0.0), (1.5, 0.25)]
    assert [contact_count(streams, phi) for phi in (0.1, 0.3, 0.6, 0.8, 1.1)] == [3, 4, 3, 2, 3]
    # at a breakpoint the count is that of the interval starting there
    assert contact_count(streams, 0.25) == 4 and contact_count(streams, 0.75) == 2
    assert count_intervals(streams) == [(0.0, 0.25, 3), (0.25, 0.5, 4), (0.5, 0.75, 3),
                                        (0.75, 1.0, 2)]


def test_coinciding_breakpoints_leave_no_zero_length_interval():
    # one stream leaves as the other enters (within rounding): the count never dips
    assert alternation_law([(1.5, 0.0), (1.5, 0.5 + 1e-13)]) == "3"
    assert alternation_law([(1.5, 0.5), (1.5, -1e-13)]) == "3"
    assert alternation_law([(1.5, 0.5), (1.5, 1.0 - 1e-13)]) == "3"
    intervals = count_intervals([(1.5, 0.0), (1.5, 0.5 + 1e-13)])
    assert [count for _, _, count in intervals] == [3, 3]
    assert all(end - start > 1e-3 for start, end, _ in intervals)


# --- a herringbone scene ------------------------------------------------------------------------

def scene(**parameters):
    return herringbone.scene_from_dict({"parameters": parameters})


def test_reference_scene_phasing():
    phasing = scene_phasing(REFERENCE)
    assert phasing.eps_beta_left == phasing.eps_beta_right == pytest.approx(1.0820, abs=1e-4)
    assert phasing.q21 == pytest.approx(0.8 * 0.032347, abs=1e-6)
    assert [eps for eps, _ in phasing.streams] == [phasing.eps_beta_left] * 4
    assert [delay for _, delay in phasing.streams] == pytest.approx([0.0, 0.2, 0.0, 0.2])
    assert phasing.law == "6-4-6-4"
    assert phasing.k_eps == 4
    assert phasing.k_eps_ratio == pytest.approx(4 / (2 * 1.0820), abs=1e-4)


def test_staggered_scene_alternates_5_4_four_times():
    phasing = scene_phasing(scene(stagger=0.5).parameters)  # a parameter dict works too
    assert [delay for _, delay in phasing.streams] == pytest.approx([0.0, 0.2, 0.5, 0.7])
    assert phasing.law == "5-4-5-4-5-4-5-4"
    assert phasing.k_eps == 4


@pytest.mark.parametrize("face_width", [2 * P_X, math.nextafter(2 * P_X, 0.0),
                                        math.nextafter(2 * P_X, 1.0)])
@pytest.mark.parametrize("stagger", [0.0, 0.3])
def test_integer_axial_overlap_gives_k_eps_over_eps_beta_of_2(face_width, stagger):
    phasing = scene_phasing(scene(b_left=face_width, b_right=face_width, stagger=stagger))
    assert phasing.law == "8"
    assert phasing.k_eps == 8
    assert phasing.k_eps_ratio == pytest.approx(2.0, abs=1e-12)


MESH_SCENES = {
    "reference": {},
    "stagger 0.5": {"stagger": 0.5},
    "stagger 0.25": {"stagger": 0.25},
    "eps_q 0.3": {"eps_q": 0.3},
    "phase0 0.4": {"phase0": 0.4},
    "b_left != b_right": {"b_left": 0.05},
    "integer eps_beta": {"b_left": 2 * P_X, "b_right": 2 * P_X},
    "integer, staggered": {"b_left": 2 * P_X, "b_right": 2 * P_X, "stagger": 0.3},
    "halves 1.5 and 0.5": {"b_left": 1.5 * P_X, "b_right": 0.5 * P_X, "eps_q": 0.5},
    "short halves": {"b_left": 0.3 * P_X, "b_right": 0.6 * P_X, "stagger": 0.7, "phase0": 0.9},
}

EXPECTED_LAWS = {"reference": "6-4-6-4", "stagger 0.5": "5-4-5-4-5-4-5-4",
                 "stagger 0.25": "6-5-4-5-4-5-4-5", "eps_q 0.3": "6-4-6-4",
                 "phase0 0.4": "4-6-4-6-4", "b_left != b_right": "6-5-7-6-5-4",
                 "integer eps_beta": "8", "integer, staggered": "8", "halves 1.5 and 0.5": "4"}


@pytest.mark.parametrize("name", MESH_SCENES)
def test_contact_count_follows_the_law_of_the_mesh(name):
    """In every interval between the mesh's switches the count of the streams is the number of
    points the mesh puts in contact, so n_contacts (no contact lost) follows the law."""
    parameters = scene(**MESH_SCENES[name]).parameters
    phasing, mesh = scene_phasing(parameters), Mesh(parameters)
    ends = np.append(mesh.switch_phases[1:], mesh.switch_phases[0] + 1.0)
    for interval, (start, end) in enumerate(zip(mesh.switch_phases, ends)):
        assert contact_count(phasing.streams, 0.5 * (start + end)) == \
            len(mesh.contact_set(0, interval)), f"interval {interval} [{start:.4f}, {end:.4f})"
    if name in EXPECTED_LAWS:
        assert phasing.law == EXPECTED_LAWS[name]


# --- the scene report ---------------------------------------------------------------------------

def mode_lines(text):
    return [line for line in text.splitlines() if re.match(r"\s+\d+\s+[\d.]+ Hz  ", line)]


NAMES = ["phi_motor", "phi_pinion", "psi_pinion", "x_pinion", "phi_wheel", "psi_wheel",
         "x_wheel", "phi_load"]


def use_stand_in_modes(monkeypatch):
    """Four modes: rigid (the reference's ratio 3.6), torsional, tilt, lateral — unit masses,
    so shares are v_i²."""
    shapes = np.zeros((8, 4))
    shapes[[0, 1, 4, 7], 0] = [1.0, 1.0, 1 / 3.6, 1 / 3.6]
    shapes[:, 1] = [0.9, 0.4, 0.1, 0, 0, 0, 0, 0.1]
    shapes[:, 2] = [0, 0.1, 0.9, 0.2, 0, 0.3, 0, 0]
    shapes[:, 3] = [0, 0, 0, 0.1, 0, 0.1, 1.0, 0]
    monkeypatch.setattr(herringbone.analysis.report, "natural_modes",
                        lambda scene, pinion_angle=None: (
                            np.array([1e-5, 113.0, 688.0, 13800.0]), shapes, list(NAMES)))
    monkeypatch.setattr(herringbone.analysis.report, "mass_matrix", lambda scene: np.eye(8))


def test_scene_report_with_a_stand_in_model(monkeypatch):
    use_stand_in_modes(monkeypatch)
    text = scene_report(REFERENCE)
    for expected in ("21.705 mm", "78.137 mm", "3.6 (36/10)", "32.347 mm", "1.0820, 1.0820",
                     "25.878 mm", "6-4-6-4", "K_eps                  4 points",
                     "250.00 Hz", "1500 rpm", "1.082e+09 N/m"):
        assert expected in text, expected
    assert [line.split("Hz")[1].split()[0] for line in mode_lines(text)] == \
        ["rigid", "torsional", "tilt", "lateral"]
    assert "torsional (99 % of kinetic energy)" in text  # (0.81 + 0.16 + 0.01)/0.99
    assert "tilt (95 % of kinetic energy)" in text  # (0.81 + 0.09)/0.95
    # 113 Hz meets k·f_mesh at 60·113/(k·10) rpm; 13.8 kHz only at k = 3 below 30 000 rpm
    assert "678 (71.0)" in text and "339 (35.5)" in text and "226 (23.7)" in text
    row = next(line for line in text.splitlines() if line.strip().startswith("13800.00"))
    assert row.split()[1:] == ["-", "-", "27600", "(2890.3)"]


def test_scene_report_on_the_real_model():
    from herringbone.model import assembly as model
    frequencies, shapes, names = model.natural_modes(REFERENCE, pinion_angle=None)
    assert len(names) == 8 and shapes.shape == (8, 8) and abs(frequencies[0]) < 1e-3
    text = scene_report(REFERENCE)
    assert "rigid rotation" in text and "250.00 Hz" in text
    assert [line.split("Hz")[1].split()[0] for line in mode_lines(text)] == [
        "rigid", "torsional", "torsional", "lateral", "tilt", "lateral", "torsional", "tilt"]


def test_a_slow_elastic_mode_is_not_taken_for_the_rigid_rotation():
    """A soft motor shaft (1e-4 N·m/rad against a motor of 1e3 kg·m²) rings at 8 mHz, under
    1e-6 of the fastest mode, where rounding of the rigid rotation's zero could lie: the
    rigid rotation is told by its shape, so the report names one, and the slow mode is the
    motor against the rest of the train at sqrt(C·(1/I_motor + 1/J))/(2π), J the rest's
    inertia referred to the pinion."""
    from herringbone.analysis.campbell import elastic_frequencies
    from herringbone.model.assembly import GearTrainModel

    scene = REFERENCE.with_parameters(C_shaft_in=1e-4, I_motor=1e3)
    model = GearTrainModel(scene)
    inertia = dict(zip(model.coordinates, model.mass))
    rest = inertia["phi_pinion"] + (inertia["phi_wheel"] + inertia["phi_load"]) \
        / model.geometry.ratio ** 2
    expected = math.sqrt(1e-4 * (1 / 1e3 + 1 / rest)) / (2 * math.pi)
    assert expected < 1e-6 * 13354.5
    text = scene_report(scene)
    modes = [line.split("Hz") for line in text.splitlines() if " Hz  " in line]
    assert [character.split()[0] for _, character in modes[:3]] == \
        ["rigid", "torsional", "torsional"] and text.count("rigid rotation") == 1
    assert float(modes[1][0].split()[1]) == pytest.approx(expected, rel=1e-3)
    frequencies = elastic_frequencies(scene)
    assert len(frequencies) == 7 and frequencies[0] == pytest.approx(expected, rel=1e-3)


def test_a_mode_too_slow_for_double_precision_says_so():
    """An eigenvalue ω² is resolved to about machine epsilon times the fastest's: a motor of
    1e8 kg·m² on a shaft of 1e-6 N·m/rad (0.78 mHz beside 13 kHz) is listed with the share
    rounding may move it by, and lies within it of the two-inertia frequency; a load of 1e8
    kg·m² on such a shaft (0.19 mHz) is rounding, the line says so, and no resonance speeds
    are listed for it; at 8 mHz no caveat. The rigid rotation is line 1 and the slow mode
    line 2 whichever of the two the eigensolver returns as the slower (one machine's LAPACK
    returned the rigid rotation second, and the slow mode's ω² below zero)."""
    from herringbone.model.assembly import GearTrainModel

    def slow_mode(**values):
        scene = REFERENCE.with_parameters(**values)
        lines = scene_report(scene).splitlines()
        assert next(line for line in lines if line.startswith("   1 ")).endswith(
            "0.00 Hz  rigid rotation")
        slow = next(line for line in lines if line.startswith("   2 "))
        if slow.endswith("too slow to resolve"):
            assert not any(line.startswith("        0.00  ") for line in lines)  # a speed row
        return slow, GearTrainModel(scene)

    line, model = slow_mode(C_shaft_in=1e-6, I_motor=1e8)
    inertia = dict(zip(model.coordinates, model.mass))
    rest = inertia["phi_pinion"] + (inertia["phi_wheel"] + inertia["phi_load"]) \
        / model.geometry.ratio ** 2
    expected = math.sqrt(1e-6 * (1 / 1e8 + 1 / rest)) / (2 * math.pi)
    share = float(line.split("±")[1].split(" %")[0]) / 100
    assert line.endswith("% by rounding beside 13354 Hz") and 0.01 < share < 0.1
    assert abs(float(line.split()[1]) / expected - 1) <= share
    line, _ = slow_mode(C_shaft_out=1e-6, I_load=1e8)
    assert line.endswith("rounding beside 13354 Hz, not a frequency: too slow to resolve")
    line, _ = slow_mode(C_shaft_in=1e-4, I_motor=1e3)
    assert line.endswith("(100 % of kinetic energy)")


def test_scene_report_says_what_its_contact_count_assumes(monkeypatch):
    """The contact-point law is that of every point loaded and sharp edges; the report says
    so, and says where a scene's ramp or contact loss makes a run count otherwise."""
    use_stand_in_modes(monkeypatch)
    plain = scene_report(REFERENCE.with_parameters(contact_loss=False))
    assert "(the phasing law: every point loaded, sharp edges)" in plain
    assert "widens each point's span" not in plain and "(contact_loss:" not in plain
    both = scene_report(REFERENCE.with_parameters(edge_ramp=1e-3, contact_loss=True))
    assert "(edge_ramp 1 mm widens each point's span" in both
    assert "(contact_loss: a point whose teeth part carries no load" in both


def test_info_prints_the_report(tmp_path, capsys, monkeypatch):
    use_stand_in_modes(monkeypatch)
    path = tmp_path / "staggered.toml"
    path.write_text("[parameters]\nstagger = 0.5\n")
    assert herringbone_main(["info", str(path)]) == 0
    assert "5-4-5-4-5-4-5-4" in capsys.readouterr().out


def test_info_reports_a_bad_scene_in_one_line(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("[parameters]\neps_q = 1.5\n")
    assert herringbone_main(["info", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1 and "eps_q" in captured.err
    assert herringbone_main(["info", str(tmp_path / "missing.toml")]) == 2
    assert "no such scene file" in capsys.readouterr().err


# --- a face too narrow for continuous contact ---------------------------------------------------

@pytest.mark.parametrize("name", sorted(scene_files()))
def test_every_shipped_scene_keeps_a_point_on_the_face(name):
    parameters = herringbone.load_scene(name).parameters
    assert Mesh(parameters).share_without_contact() == 0.0


def test_a_narrow_face_is_without_contact_outside_its_two_stream_spans(monkeypatch):
    """Both halves alike, each stream of ε = b/p_x on the face for that fraction of the period:
    the pre- and post-pole streams (delays 0 and 0.2) together cover 2ε of it, and K_ε = 0.
    `info` says how much of the period no point is on the face."""
    scene = REFERENCE.with_parameters(b_left=1e-4, b_right=1e-4)
    eps = 1e-4 / P_X
    assert scene_phasing(scene).k_eps == 0
    assert Mesh(scene.parameters).share_without_contact() == pytest.approx(1.0 - 2.0 * eps,
                                                                           abs=1e-12)
    use_stand_in_modes(monkeypatch)
    assert ("(no point is on the face for 99.4 % of each mesh period: the pair transmits no "
            "torque then" in scene_report(scene))
    assert "no point is on the face" not in scene_report(REFERENCE)


def test_the_rigid_rotation_is_listed_at_zero_hertz(monkeypatch):
    """Beside modes in the MHz (inertias of 1e-9 kg·m²) the rigid rotation's eigenvalue is
    rounding of a zero, 0.01 Hz, which `info` printed as a frequency."""
    use_stand_in_modes(monkeypatch)
    modes = herringbone.analysis.report.natural_modes(REFERENCE)
    monkeypatch.setattr(herringbone.analysis.report, "natural_modes",
                        lambda scene, pinion_angle=None: (
                            np.array([0.013, 113.0, 688.0, 2.2e6]), modes[1], modes[2]))
    (rigid,) = [line for line in scene_report(REFERENCE).splitlines()
                if line.endswith("rigid rotation")]
    assert rigid.split() == ["1", "0.00", "Hz", "rigid", "rotation"]
