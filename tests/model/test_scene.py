"""Scene files: defaults, and one clear message for each kind of bad input."""
import pickle

import pytest

import herringbone
from herringbone import SceneError, load_scene
from herringbone.model.scene import Experiment

BAD_SCENES = [
    ('[parameters]\nm_pinion = -1.0\n', "m_pinion", "allowed: [1e-09, 1e+07] kg"),
    ('[parameters]\nbeta = 1.6\n', "beta", "allowed: [0.01, 1.4] rad"),
    ('[parameters]\nbeta = 0.0\n', "beta", "allowed: [0.01, 1.4] rad"),
    ('[parameters]\neps_q = 1.0\n', "eps_q", "[0, 1)"),
    ('[parameters]\nstagger = -0.1\n', "stagger", "[0, 1)"),
    ('[parameters]\nb_left = 0.0\n', "b_left", "allowed: [1e-06, 10] m"),
    ('[parameters]\nc_point = -2.5e8\n', "c_point", "allowed: [1000, 1e+13] N/m"),
    ('[parameters]\nz_pinion = 0\n', "z_pinion", "a whole number [1, 1000]"),
    ('[parameters]\nz_wheel = 3.5\n', "z_wheel", "whole number"),
    ('[parameters]\nm_n = "4 mm"\n', "m_n", "must be a number"),
    ('[parameters]\ncontact_loss = 1\n', "contact_loss", "true or false"),
    ('[parameters]\nmodule = 0.004\n', "module", "unknown parameter"),
    ('[parameters]\nM_motor = 500\n', "M_motor", "[inputs]"),
    ('[parameters]\nbearings = false\n', "bearings",
     "unknown parameter 'bearings': bearings is a component; allowed: a scene's [components] "
     "sets it"),
    ('[parameters]\nzeta_mesh = nan\n', "zeta_mesh", "allowed: [0, 10]"),
    ('[parameters]\nw0_pinion = inf\n', "w0_pinion", "[-100000, 100000] rad/s"),
    ('[components]\nbearings = false\n[parameters]\nc_brg_wheel_left = 1e9\n',
     "c_brg_wheel_left", "leaves out"),
    ('[components]\ngearbox = true\n', "gearbox", "motor, load, bearings"),
    ('[components]\nmotor = "yes"\n', "motor", "true or false"),
    ('[experiment]\nstop_time = -1\n', "stop_time", "> 0"),
    ('[experiment]\nstop_time = 0.01\noutput_interval = 0.1\n', "output_interval", "stop_time"),
    ('[experiment]\nduration = 1\n', "duration", "stop_time, output_interval"),
    ('[inputs]\nM_motor = nan\n', "M_motor", "finite"),
    ('[inputs]\ntable = [[0.1, 500, 1800]]\n', "table", "time 0"),
    ('[inputs]\ntable = [[0, 500], [1, 600, 2000]]\n', "row 0", "three finite numbers"),
    ('[inputs]\ntable = [[0, 500, 1800], [0, 600, 2000]]\n', "table", "increase"),
    ('[inputs]\nM_motor = 500\ntable = [[0, 500, 1800]]\n', "table", "not both"),
    ('[solver]\nrtol = 1e-6\n', "solver", "[parameters]"),
    ('[parameters\nbeta = 0.3\n', "not a valid TOML", ""),
]


@pytest.mark.parametrize("text, culprit, allowed", BAD_SCENES)
def test_bad_scene_gets_one_clear_message(tmp_path, text, culprit, allowed):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as error:
        herringbone.load_scene(path)
    message = str(error.value)
    assert str(path) in message and culprit in message and allowed in message


def test_missing_scene_file(tmp_path):
    with pytest.raises(SceneError, match="no such scene file"):
        herringbone.load_scene(tmp_path / "absent.toml")


def test_a_folder_is_not_taken_for_a_missing_scene_file(tmp_path):
    with pytest.raises(SceneError) as error:
        herringbone.load_scene(tmp_path)
    message = str(error.value)
    assert message.startswith(f"{tmp_path}: a folder, not a scene file; allowed: a scene file")
    assert "\n" not in message


def test_defaults_are_the_reference_values(tmp_path, reference_scene):
    path = tmp_path / "empty.toml"
    path.write_text("")
    scene = herringbone.load_scene(path)
    assert scene.parameters == reference_scene.parameters
    assert scene.inputs.at(0.0) == (500.0, 1800.0)
    # J from the solid cylinder m(3R² + L²)/12, R the pitch radius, L = bL + bR + groove
    assert scene.parameters["J_pinion"] == pytest.approx(
        0.929436 * (3 * 0.021704758 ** 2 + 0.08 ** 2) / 12, rel=1e-8)


def test_input_table_is_held_between_rows():
    scene = herringbone.scene_from_dict({"inputs": {"table": [[0, 500, 1800], [0.5, 600, 2000]]}})
    assert scene.inputs.at(0.0) == (500, 1800)
    assert scene.inputs.at(0.4999) == (500, 1800)
    assert scene.inputs.at(0.5) == (600, 2000)
    assert scene.inputs.at(7.0) == (600, 2000)


def test_shipped_scenes_load():
    from conftest import MODELS
    names = sorted(p.stem for p in MODELS.glob("*.toml"))
    for name in ["reference", "torsional", "staggered", "lead_error"]:
        assert name in names
    for name in names:
        herringbone.load_scene(MODELS / f"{name}.toml")


def test_scene_error_carries_its_fields():
    """SceneError names the file, table and key apart, and its text joins them (issue 17)."""
    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict({"parameters": {"z_pinion": 0}}, source="x.toml")
    error = raised.value
    assert (error.source, error.table, error.key) == ("x.toml", "parameters", "z_pinion")
    assert error.problem == "z_pinion is 0; allowed: a whole number [1, 1000]"
    assert str(error) == "x.toml: [parameters] z_pinion is 0; allowed: a whole number [1, 1000]"
    again = pickle.loads(pickle.dumps(error))
    assert (str(again), again.key) == (str(error), "z_pinion")


@pytest.mark.parametrize("path, shown", [(None, "None (NoneType)"), (123, "123 (int)"),
                                         ("", "'' (empty)"), ([1, 2], "[1, 2] (list)"),
                                         (herringbone.load_scene("reference"), "a Scene")])
def test_a_path_that_names_no_file_is_blamed_on_the_argument(path, shown):
    """load_scene of something that is no path, or of '' (which pathlib reads as the current
    folder), names its argument, what it got and what is allowed: not a TypeError, not "."."""
    with pytest.raises(SceneError) as raised:
        herringbone.load_scene(path)
    message = str(raised.value)
    assert message.startswith(f"load_scene: path is {shown}; allowed: a scene file"), message
    assert "shipped scene" in message and "\n" not in message
    assert raised.value.key == "path"


@pytest.mark.parametrize("data", [[1, 2], None, "reference"])
def test_scene_from_dict_of_no_dict_names_its_argument(data):
    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict(data)
    message = str(raised.value)
    assert message.startswith(f"scene_from_dict: data is {data!r} ({type(data).__name__}); "
                              "allowed: a dict of the scene file's tables"), message
    assert "unknown table" not in message


def test_a_value_of_with_parameters_or_with_inputs_is_not_blamed_on_the_file(reference_scene):
    """The file said nothing wrong: the message names the call that handed the value over;
    its fields still say which table and key (the FMU words them its own way)."""
    cases = [(lambda: reference_scene.with_parameters(zeta_mesh=-1.0),
              "with_parameters: zeta_mesh is -1.0; allowed: [0, 10]", "parameters"),
             (lambda: reference_scene.with_parameters(c_pont=1e8),
              "with_parameters: unknown parameter 'c_pont'; did you mean 'c_point'?",
              "parameters"),
             (lambda: reference_scene.with_parameters(motor=False),
              "with_parameters: unknown parameter 'motor': motor is a component; allowed: a "
              "scene's [components] sets it", "parameters"),
             (lambda: reference_scene.with_inputs(M_motor=float("nan")),
              "with_inputs: M_motor is nan; allowed: any finite number, in N.m", "inputs"),
             (lambda: reference_scene.with_inputs(table=[[0.1, 500.0, 1800.0]]),
              "with_inputs: table row 0 is at time 0.1 s; allowed: a table that starts at "
              "time 0 s", "inputs")]
    for provoke, expected, table in cases:
        with pytest.raises(SceneError) as raised:
            provoke()
        error = raised.value
        assert str(error) == expected
        assert (error.table, error.call, error.source) == (table, expected.split(":")[0],
                                                           reference_scene.source)
        assert str(pickle.loads(pickle.dumps(error))) == expected
    # a value of the file is still the file's
    with pytest.raises(SceneError, match=r"^x\.toml: \[parameters\] zeta_mesh is -1\.0"):
        herringbone.scene_from_dict({"parameters": {"zeta_mesh": -1.0}}, source="x.toml")


def test_every_range_that_refuses_inf_says_finite():
    """Range.contains refuses inf, so the words of every parameter and input with an open end
    say "finite" (c_point = inf was told "allowed: > 0 N/m", which inf satisfies)."""
    from herringbone.model.parameters import INPUTS, PARAMETERS

    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict({"parameters": {"c_point": float("inf")}})
    assert raised.value.problem == "c_point is inf; allowed: [1000, 1e+13] N/m"
    for name, p in {**PARAMETERS, **INPUTS}.items():
        if p.kind is not float:
            continue
        table = "inputs" if name in INPUTS else "parameters"
        with pytest.raises(SceneError) as raised:
            herringbone.scene_from_dict({table: {name: float("inf")}})
        assert "finite" in raised.value.problem or p.allowed.high is not None, name


def test_a_lead_error_is_refused_as_the_slope_it_is():
    """dbeta_* is a lead deviation per axial travel, written in rad as small slopes are: its
    message says so, and not "an angle in radians" as a helix angle's does."""
    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict({"parameters": {"dbeta_left": 0.5}})
    assert raised.value.problem == (
        "dbeta_left is 0.5 rad; allowed: [-0.1, 0.1] rad (a slope, the lead deviation per unit "
        "of axial travel f_Hb/b: 10 µm over 35 mm is 2.86e-4)")
    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict({"parameters": {"beta": 5.0}})
    assert raised.value.problem.endswith("rad, an angle in radians")


def test_a_flag_of_the_wrong_kind_is_shown_with_what_it_got():
    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict({"parameters": {"contact_loss": "yes"}})
    assert raised.value.problem == "contact_loss must be true or false, got str 'yes'"


@pytest.mark.parametrize("text, words", [
    ("[experimnt]\nstop_time = 0.1\n", "unknown table [experimnt]; did you mean 'experiment'?"),
    ("stop_time = 0.1\n[parameters]\nzeta_mesh = 0.1\n",
     "stop_time stands outside any table; allowed: under [experiment]"),
    ("zeta_mesh = 0.1\n", "zeta_mesh stands outside any table; allowed: under [parameters]"),
    ("foo = 1\n", "foo stands outside any table; allowed: keys under a table, [parameters]"),
])
def test_a_key_outside_its_table_or_a_misspelt_table_is_named_with_its_home(tmp_path, text,
                                                                           words):
    """A key written above every table is told the table it belongs under, and a misspelt
    table gets "did you mean"."""
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as error:
        load_scene(path)
    assert words in str(error.value)



def test_a_short_run_without_its_output_interval_samples_at_its_end(tmp_path):
    """stop_time alone, shorter than output_interval's default (1e-4 s), was refused as
    "output_interval 0.0001 exceeds stop_time 5e-05", a key the file does not hold: the
    default is then the stop time (one sample at the run's end)."""
    path = tmp_path / "short.toml"
    path.write_text("[experiment]\nstop_time = 5e-5\n")
    assert herringbone.load_scene(path).experiment == Experiment(5e-5, 5e-5)
    path.write_text("[experiment]\nstop_time = 0.2\n")
    assert herringbone.load_scene(path).experiment == Experiment(0.2, 1e-4)


def test_a_flag_may_be_numpys_bool():
    """np.bool_ is no bool: it was refused ("must be true or false, got bool np.False_")
    where numpy's numbers are taken; it is taken as the bool it is."""
    import numpy as np

    scene = herringbone.load_scene("reference").with_parameters(contact_loss=np.bool_(False))
    assert scene.parameters["contact_loss"] is False
    table = herringbone.scene_from_dict({"components": {"bearings": np.bool_(False)}})
    assert table.components["bearings"] is False


def test_an_edge_ramp_over_half_the_narrower_face_is_refused(tmp_path):
    """edge_ramp is the contact ellipse's half-length in metres: one over half the narrower
    face (1 given for 1 mm: 30 face widths) leaves no point ever fully loaded, and is refused
    naming it, from a file and from with_parameters, even where a face is narrowed."""
    path = tmp_path / "ramp.toml"
    path.write_text("[parameters]\nedge_ramp = 1\n")
    with pytest.raises(SceneError, match=r"\[parameters\] edge_ramp is 1.0 m, over half the "
                                         r"narrower face width \(0.035 m\); allowed: <= 0.0175"):
        herringbone.load_scene(path)
    ramped = herringbone.scene_from_dict({"parameters": {"edge_ramp": 0.005}})
    with pytest.raises(SceneError, match="with_parameters: edge_ramp is 0.005 m"):
        ramped.with_parameters(b_right=0.008)
    assert ramped.with_parameters(b_right=0.01).parameters["edge_ramp"] == 0.005
