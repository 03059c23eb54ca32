"""`herringbone sweep` as a user runs it: what it refuses, in one line and exit code 2 before
any work (an FMU of another scene, a file that is no FMU, points with no steady running, an
-o that names a file), and that where the points run does not choose the method.
In-process (`main([...])`, capsys), the work replaced by a refusal where none may begin."""
import zipfile

import pandas as pd
import pytest
from helpers import MODELS

from herringbone.cli import main

REFERENCE = str(MODELS / "reference.toml")
SPEEDS = ["--speeds", "300", "400", "2"]


def one_error_line(capsys) -> str:
    """The one line on stderr, `herringbone sweep: …`; nothing on stdout, no traceback."""
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1, captured.err
    assert captured.err.startswith("herringbone sweep: "), captured.err
    assert "Traceback" not in captured.err and "distributed.worker" not in captured.err
    return captured.err


@pytest.fixture
def no_work(monkeypatch):
    """A point run, a branch followed or a Dask cluster started fails the test."""
    import herringbone.analysis.distributed_run as distributed_run
    import herringbone.analysis.sweep as sweep_module

    def refuse(*args, **kwargs):
        raise AssertionError("the sweep began before its arguments were checked")

    for module, name in ((sweep_module, "run_point"), (sweep_module, "shooting_sweep"),
                         (distributed_run, "map_points")):
        monkeypatch.setattr(module, name, refuse)


def scene_file(folder, **inputs) -> str:
    """models/reference.toml with other [inputs] constants, written in `folder`."""
    text = (MODELS / "reference.toml").read_text()
    text = text[:text.index("[inputs]")] + "[inputs]\n" + "".join(
        f"{name} = {value}\n" for name, value in inputs.items())
    path = folder / "changed.toml"
    path.write_text(text)
    return str(path)


def test_an_fmu_of_another_scene_is_refused_by_the_parameter_that_differs(scene_fmu, capsys,
                                                                         no_work):
    """The reference scene's FMU under a sweep of the staggered scene ran the reference and
    labelled the table staggered; now the first difference is named. The API likewise."""
    import herringbone

    fmu = scene_fmu("reference")
    arguments = ["sweep", "staggered", *SPEEDS, "--through-fmu", str(fmu), "--workers", "0"]
    assert main(arguments) == 2
    error = one_error_line(capsys)
    assert (f"through-fmu {fmu}: built from another scene than staggered: stagger is 0.0 in "
            "the FMU's scene, 0.5 in staggered; allowed: an FMU of the sweep's scene "
            "(herringbone build-fmu staggered)") in error  # a shipped scene by its name
    staggered = herringbone.load_scene("staggered")
    with pytest.raises(ValueError, match="stagger is 0.0 in the FMU's scene"):
        herringbone.sweep(staggered, speeds=[300.0, 400.0], fmu=fmu, workers=0)
    # what each point sets is no difference: the stagger swept through the reference's FMU
    from herringbone.analysis.sweep_fmu import check_fmu
    check_fmu(fmu, staggered, ["stagger"])
    check_fmu(fmu, herringbone.load_scene("reference"), ["w0_pinion"])


@pytest.mark.parametrize("content, name, words", [
    (b"not a zip\n", "x.fmu", "not an FMU (an FMU is a zip archive"),
    (None, "a_scene.toml", "not an FMU file (its suffix is .toml, not .fmu)"),
    (b"", "empty.fmu", "not an FMU (an FMU is a zip archive"),
    ("zip", "other.fmu", "not a gear FMU (it carries no resources/scene.toml)"),
    (None, "missing.fmu", "no such FMU file"),
])
def test_a_through_fmu_that_is_no_gear_fmu_gets_one_line(content, name, words, tmp_path,
                                                         capsys, no_work):
    path = tmp_path / name
    if content == "zip":
        with zipfile.ZipFile(path, "w") as archive:
            archive.writestr("modelDescription.xml", "<fmiModelDescription/>")
    elif content is not None:
        path.write_bytes(content)
    elif name.endswith(".toml"):
        path.write_text((MODELS / "reference.toml").read_text())
    assert main(["sweep", REFERENCE, *SPEEDS, "--through-fmu", str(path)]) == 2
    error = one_error_line(capsys)
    assert f"--through-fmu {path}: {words}" in error and "allowed: the path of a gear FMU" in error


def test_workers_0_runs_the_default_method_here(tmp_path, capsys):
    """--workers 0 says where the points run (here), not how: the default speed sweep stays
    shooting (it switched to time integration), and --method shooting takes it too."""
    for extra, folder in (([], "default"), (["--method", "shooting"], "asked")):
        assert main(["sweep", REFERENCE, *SPEEDS, "--workers", "0", "--no-progress", *extra,
                     "-o", str(tmp_path / folder)]) == 0
        table = pd.read_csv(tmp_path / folder / "reference_sweep_w0_pinion.csv")
        assert set(table["method"]) == {"shooting"} and set(table["stability"]) == {"stable"}
        assert "on_grid" in table
    assert "shooting and continuation" in capsys.readouterr().out


def test_dask_workers_with_shooting_are_refused_in_one_line(capsys, no_work):
    for extra, given in ((["--workers", "2"], "--workers 2"),
                         (["--scheduler", "tcp://127.0.0.1:1"], "--scheduler tcp://127.0.0.1:1"),
                         (["--method", "shooting", "--workers", "2"], "--workers 2")):
        assert main(["sweep", REFERENCE, *SPEEDS, *extra]) == 2
        error = one_error_line(capsys)
        assert error.startswith(f"herringbone sweep: {given}: allowed: only with --method time")


@pytest.mark.parametrize("inputs, method, words", [
    ({"M_motor": 500.0, "M_load": 100.0}, [], ("M_load = 100 N·m does not balance M_motor = "
                                               "500 N·m", "allowed: M_load = u·M_motor = 1800")),
    ({"M_motor": 500.0, "M_load": 100.0}, ["--method", "time", "--workers", "0"],
     ("M_load = 100 N·m does not balance", "u·M_motor = 1800")),
    ({"M_motor": -500.0, "M_load": -1800.0}, [], ("M_motor = -500 N·m", "back flanks",
                                                  "allowed: M_motor > 0")),
])
def test_torques_with_no_steady_running_are_refused_before_any_work(inputs, method, words,
                                                                    tmp_path, capsys, no_work):
    """Unbalanced torques were swept by time into rows labelled 300 rad/s of a train at
    18 000 rad/s; negative ones, every orbit failing, into a KeyError in the report."""
    assert main(["sweep", scene_file(tmp_path, **inputs), *SPEEDS, *method]) == 2
    error = one_error_line(capsys)
    assert all(word in error for word in words), error


@pytest.mark.parametrize("arguments, words", [
    (["torque_step", *SPEEDS], "a sweep point needs constant input torques"),
    (["from_rest", "--param", "zeta_mesh", "0.02", "0.05", "2"], "w0_pinion is 0"),
])
def test_a_point_that_cannot_run_is_refused_before_any_worker_starts(arguments, words, capsys,
                                                                     no_work):
    """Found on Dask's workers before, after their tracebacks and about 8 s."""
    assert main(["sweep", *arguments]) == 2
    error = one_error_line(capsys)
    assert words in error and "allowed" in error


def test_a_refused_point_names_a_shipped_scene_as_typed(capsys, no_work):
    """A grid of both torques leaves the balance at some of its points: refused naming the
    scene as typed (`reference`), not its file in site-packages."""
    assert main(["sweep", "reference", "--param", "M_motor", "250", "500", "2", "--param",
                 "M_load", "900", "1800", "2"]) == 2
    error = one_error_line(capsys)
    assert error.startswith("herringbone sweep: reference at M_motor = 250, M_load = 1800: "
                            "M_load = 1800 N·m does not balance"), error


@pytest.mark.parametrize("name", ["x.csv", "curve.PNG", "table.parquet"])
def test_an_output_that_names_a_file_is_refused_and_no_folder_made(name, tmp_path, capsys,
                                                                   no_work):
    output = tmp_path / "w" / name
    assert main(["sweep", REFERENCE, *SPEEDS, "-o", str(output)]) == 2
    error = one_error_line(capsys)
    assert f"--output {output}: names a" in error and "-o is a folder for sweep" in error
    assert not (tmp_path / "w").exists()


def test_a_sweep_through_the_fmu_says_its_figures_are_of_the_recorded_samples(
        scene_fmu, tmp_path, capsys):
    """Its figures are those of the FMU's outputs at the recorded samples, which read the
    ringing's peaks low: the command's summary says so (the API's describe did, and the
    command did not hand it the option)."""
    assert main(["sweep", REFERENCE, *SPEEDS, "--through-fmu", str(scene_fmu("reference")),
                 "--workers", "0", "--settle-time", "0.02", "--window-periods", "4",
                 "--no-progress", "-o", str(tmp_path)]) == 0
    assert ("through the FMU: the figures are those of the FMU's outputs at the recorded "
            "samples" in capsys.readouterr().out)
