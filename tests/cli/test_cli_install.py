"""What a user who installs the package meets: the examples run as modules of the
installed package, the FMU's runtime needs stay numpy, scipy, numba (and the FMI tools), the
analysis and co-simulation packages come as extras, and a missing one is named with the extra
that brings it."""
import inspect
import subprocess
import sys
import tomllib

import numpy as np
import pytest
from helpers import MODELS

import herringbone

ROOT = MODELS.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
ANALYSIS = ("matplotlib", "dask", "pandas", "tqdm")


def _names(requirements) -> set[str]:
    return {requirement.split("[")[0].split(">")[0].split("<")[0].split("=")[0].strip()
            for requirement in requirements}


def test_the_runtime_needs_only_what_an_fmu_runs():
    base = _names(PYPROJECT["project"]["dependencies"])
    assert base == {"numpy", "scipy", "numba", "pythonfmu", "pythonfmu3", "fmpy"}
    extras = PYPROJECT["project"]["optional-dependencies"]
    assert _names(extras["analysis"]) == set(ANALYSIS)
    assert _names(extras["cosim"]) == {"libcosimpy"}
    assert "herringbone[analysis,cosim]" in extras["all"]
    assert "herringbone[all]" in extras["test"]  # the tests, and what the README installs


def test_building_and_simulating_imports_no_analysis_package():
    """The modules an FMU build and a run go through (the builder, the slave's core, the
    compiled integrator, the reference) import none of matplotlib, dask, pandas, tqdm."""
    program = ("import sys, herringbone, herringbone.fmu.builder, herringbone.fmu.core, "
               "herringbone.fmu.ssp, herringbone.integrate.compiled_stepper, "
               "herringbone.integrate.reference, herringbone.analysis.stability\n"
               f"heavy = sorted(m for m in sys.modules if m.split('.')[0] in {ANALYSIS!r})\n"
               "assert not heavy, heavy")
    run = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr


def test_a_missing_analysis_package_is_named_with_its_extra(monkeypatch, capsys, tmp_path):
    from herringbone.cli import main

    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas now fails
    with pytest.raises(herringbone.MissingDependency,
                       match=r"pip install pandas \(or every dependency of the 'analysis'"):
        herringbone.sweep(herringbone.load_scene("reference"), speeds=[100.0, 200.0],
                          workers=0, progress=False)
    assert main(["sweep", "reference", "--speeds", "100", "200", "2", "-o",
                 str(tmp_path)]) == 2
    error = capsys.readouterr().err
    assert error.startswith("herringbone sweep: ") and error.count("\n") == 1
    assert "pip install pandas (or every dependency of the 'analysis' extra" in error


def test_the_example_runs_as_a_module_of_the_package(tmp_path):
    """`python -m herringbone.examples.cosimulate_drivetrain` from another folder: its imports
    are the package's (it failed on `No module named 'drivetrain_operating_point'`)."""
    run = subprocess.run([sys.executable, "-m", "herringbone.examples.cosimulate_drivetrain",
                          "--help"], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "--stop-time" in run.stdout
    from herringbone.examples import drivetrain_operating_point

    assert callable(drivetrain_operating_point.operating_point)


def test_python_dash_m_herringbone_is_the_command(tmp_path):
    """`python -m herringbone` (where the environment's scripts folder is not on PATH) is the
    `herringbone` command: its name in the messages, its exit codes."""
    def command(*arguments):
        return subprocess.run([sys.executable, "-m", "herringbone", *arguments],
                              capture_output=True, text=True, cwd=tmp_path, timeout=120)

    scenes, missing = command("scenes"), command("run", "no_such_scene")
    assert scenes.returncode == 0 and "reference" in scenes.stdout.split()
    assert missing.returncode == 2 and missing.stdout == ""
    assert missing.stderr.startswith("herringbone run: no_such_scene: no such scene file")


def test_the_public_api_exports_what_a_run_raises_and_gives():
    for name in ("Result", "IntegrationError", "StepBudgetExceeded", "SceneError",
                 "MissingDependency", "scene_inputs", "Protocol"):
        assert name in herringbone.__all__ and getattr(herringbone, name) is not None
    # sweep's signature names Protocol: a user finds it where sweep is
    assert isinstance(inspect.signature(herringbone.sweep).parameters["protocol"].default,
                      herringbone.Protocol)
    assert issubclass(herringbone.StepBudgetExceeded, herringbone.IntegrationError)
    from herringbone.integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper
    from herringbone.integrate.contract import simulate_with
    from herringbone.model.assembly import GearTrainModel

    scene = herringbone.load_scene("reference")
    result = herringbone.simulate(scene, stop_time=4e-4, output_interval=1e-4)
    assert isinstance(result, herringbone.Result)
    assert np.array_equal(result.time, result["time"]) and len(result.time) == 5
    assert result.units["F_mesh"] == "N" and result.units["time"] == "s"
    assert result.units["dte"] == "m" and result.units["w_pinion"] == "rad/s"
    # its steps are those of its stepper over the run; the reference's are not counted
    stepper = CompiledStepper(GearTrainModel(scene), DEFAULT_TOLERANCE)
    simulate_with(stepper, scene, 4e-4, 1e-4)
    assert result.steps == stepper.accepted_steps >= 1
    assert herringbone.reference_simulate(scene, stop_time=4e-4).steps is None


def test_scene_inputs_hold_each_row_in_fmpy():
    """fmpy's Input interpolates a Real input between rows; scene_inputs' rows make it hold
    each row of the scene's table until the next, as herringbone.simulate does (checked with
    fmpy's own interpolation, the one its co-simulation loop applies)."""
    from fmpy.simulation import Input

    scene = herringbone.scene_from_dict({"inputs": {"table": [[0.0, 500.0, 1800.0],
                                                              [0.01, 800.0, 2000.0]]}})
    table = herringbone.scene_inputs(scene, stop_time=0.02)
    values = np.stack([table["M_motor"], table["M_load"]])
    for time in (0.0, 0.004, 0.0099999, 0.01, 0.015, 0.02, 0.03):
        held = scene.inputs.at(time)
        given, _ = Input.interpolate(time=time, t=table["time"], table=values,
                                     after_event=True)
        assert tuple(given) == pytest.approx(held, rel=1e-12), time
    ramp = np.array([[500.0, 800.0], [1800.0, 2000.0]])  # the table as given: a ramp
    between, _ = Input.interpolate(time=0.005, t=np.array([0.0, 0.01]), table=ramp,
                                   after_event=True)
    assert between[0] == pytest.approx(650.0)


def test_help_names_the_fmu_scheme_and_outputs(capsys):
    from herringbone.cli import main

    assert main(["build-fmu", "--help"]) == 0
    assert "dist/<scene>-fmi<N>.fmu" in " ".join(capsys.readouterr().out.split())
    assert main(["run", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "--reference" in text and "a .csv file to write" in text


@pytest.mark.parametrize("bar", [True, False], ids=["bar", "no-progress"])
def test_a_run_without_tqdm_runs_without_a_bar(monkeypatch, capsys, tmp_path, bar):
    """The base install (no `analysis` extra) runs the main job: without tqdm the run goes on
    without a bar, one line on stderr saying why where a bar was wanted, and writes its table."""
    from herringbone.cli import main

    monkeypatch.setitem(sys.modules, "tqdm", None)  # import tqdm now fails
    output = tmp_path / "run.csv"
    argv = ["run", "reference", "--stop-time", "1e-3", "-o", str(output)]
    assert main(argv + ([] if bar else ["--no-progress"])) == 0
    notes = [line for line in capsys.readouterr().err.splitlines()
             if line.startswith("no progress bar")]
    assert len(notes) == (1 if bar else 0)
    # one sentence: it read "... (or every dependency of the 'analysis' extra: ...) (or give
    # --no-progress)"
    assert all("(or every dependency of the 'analysis' extra" in note and note.count("(") == 1
               for note in notes)
    assert output.read_text().count("\n") == 12  # the header and 11 samples, 0 to 1e-3 s


@pytest.mark.parametrize("name", [[], ["extreme-scenes"]], ids=["default", "named"])
def test_benchmark_without_the_repository_still_helps(monkeypatch, capsys, name):
    """Installed without its repository (no benchmarks/ folder beside the package),
    `herringbone benchmark --help` prints the help (it ended with exit 2 and a site-packages
    path), and running one says in one line where the benchmarks are and what to do."""
    from herringbone.cli import benchmark, main

    monkeypatch.setattr(benchmark, "benchmarks_folder", lambda: None)
    assert main(["benchmark", *name, "--help"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("usage: herringbone benchmark ") and err == ""
    assert all(script in out for script in benchmark.SCRIPTS)
    assert main(["benchmark", *name, "--quick"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("herringbone benchmark: ") and err.count("\n") == 1
    assert "site-packages" not in err and "python3" not in err
    assert "clone the repository" in err and "benchmarks/ folder" in err


def test_benchmark_help_from_the_checkout_lists_the_script_options(capsys):
    from herringbone.cli import benchmark, main

    assert benchmark.benchmarks_folder() is not None  # the tests run from the checkout
    assert main(["benchmark", "extreme-scenes", "--help"]) == 0
    assert "--periods" in capsys.readouterr().out


def test_the_command_runs_blas_on_one_thread_unless_told_otherwise():
    """The command sets one BLAS thread before numpy loads (the model's matrices are small and
    a BLAS's threads fight over a busy machine's cores); a count the user set is kept."""
    import os

    show = ("import herringbone.cli, numpy, os; "
            "print(os.environ['OPENBLAS_NUM_THREADS'], os.environ['OMP_NUM_THREADS'])")
    clean = {k: v for k, v in os.environ.items()
             if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    for given, expected in (({}, "1 1"), ({"OPENBLAS_NUM_THREADS": "4"}, "4 1")):
        run = subprocess.run([sys.executable, "-c", show], env={**clean, **given},
                             capture_output=True, text=True, timeout=120)
        assert run.stdout.split("\n")[0] == expected, run.stderr[-2000:]
