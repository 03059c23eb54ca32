"""Defects users found in the command line after its first hour (test_cli_friction.py has
that hour's): one test each, in-process (`main([...])`, capsys) where possible. The bad values
among them have rows in tests/test_bad_input.py's table as well."""
import os
import re
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from helpers import MODELS, one_error_line

import herringbone
from herringbone.cli import main

REFERENCE = str(MODELS / "reference.toml")


def summary_line(printed: str, start: str) -> str:
    return next(line for line in printed.splitlines() if line.startswith(start))


# --- run -----------------------------------------------------------------------------------------

def test_run_takes_the_method_of_the_compiled_integrator(tmp_path, capsys):
    """`--set solver_method=dop853` was refused and there was no other way: --method runs
    herringbone.simulate's method, to the CSV's 12 digits, and the summary names it (and
    that auto picked it, by default); with --reference it is refused."""
    scene = herringbone.load_scene("reference")
    csv = tmp_path / "run.csv"
    for method in ("dop853", "radau"):
        assert main(["run", "reference", "--stop-time", "2e-3", "--method", method,
                     "--no-progress", "-o", str(csv)]) == 0
        simulated = summary_line(capsys.readouterr().out, "simulated ")
        assert f"on the compiled integrator ({method}) in " in simulated
        table = np.genfromtxt(csv, delimiter=",", names=True)
        expected = herringbone.simulate(scene, stop_time=2e-3, method=method)
        assert np.allclose(table["F_mesh_N"], expected["F_mesh"], rtol=1e-11, atol=0.0)
    assert main(["run", "reference", "--stop-time", "2e-3", "--no-progress", "-o",
                 str(csv)]) == 0
    assert ", picked by --method auto) in " in summary_line(capsys.readouterr().out,
                                                             "simulated ")
    assert main(["run", "reference", "--reference", "--method", "dop853"]) == 2
    assert "--method dop853 with --reference" in one_error_line(capsys, "run")


def test_run_says_when_its_samples_miss_the_fastest_mode(tmp_path, capsys):
    """At the reference scene's 1e-4 s the samples give its 13.2 kHz mode 0.76 a period, and
    the table's least F_mesh sample read 21 275 N where the steady state dips to 15 844 N
    (`sweep` reads K_v 1.508): a line after the table says what the samples miss and what
    to do; at 5e-6 s (15 a period) no line."""
    from herringbone.analysis.sweep_point import fastest_ringing
    from herringbone.model.assembly import GearTrainModel

    fastest = fastest_ringing(GearTrainModel(herringbone.load_scene("reference")))
    assert main(["run", "reference", "--stop-time", "4e-3", "--no-progress", "-o",
                 str(tmp_path / "run.csv")]) == 0
    printed = capsys.readouterr().out
    note = summary_line(printed, "The samples, every 100 µs")
    assert printed.index("n_contacts") < printed.index(note)  # after the table
    assert (f"fastest mode, ringing at {fastest:.0f} Hz with its damping (`herringbone info` "
            f"lists it undamped), {1e4 / fastest:.2g} a period") in note
    assert "the min and max of samples can miss its swings" in note
    assert (f"--output-interval {int(1e7 / (8 * fastest)) / 10:g}e-06 or shorter follows the "
            "ringing, but the force's jumps at contact switches fall between samples at any "
            "interval") in note
    assert "`herringbone sweep reference --speeds FROM TO COUNT`" in note
    assert main(["run", "reference", "--stop-time", "4e-3", "--output-interval", "5e-6",
                 "--no-progress", "-o", str(tmp_path / "run.csv")]) == 0
    assert "The samples" not in capsys.readouterr().out


def test_run_times_the_csv_apart_from_the_run(tmp_path, capsys, monkeypatch):
    """high_speed over 20 s: the summary said 4.6 s, the command took 44 s, most of it writing
    486 MB of CSV after the summary's clock had stopped. The summary is printed before the
    CSV is written, and a line gives the CSV's own time beside the run's."""
    from herringbone.analysis import run_report

    written = run_report.write_csv
    printed_before = []

    def write_csv(results, path):
        printed_before.append(capsys.readouterr().out)
        written(results, path)

    monkeypatch.setattr(run_report, "write_csv", write_csv)
    csv = tmp_path / "run.csv"
    assert main(["run", "reference", "--stop-time", "2e-3", "--no-progress", "-o",
                 str(csv)]) == 0
    assert "static mesh force" in printed_before[0]  # the summary came first
    line = summary_line(capsys.readouterr().out, "outputs written to")
    found = re.fullmatch(rf"outputs written to {re.escape(str(csv))} \(21 rows, ([\d.e+-]+) "
                         r"MB\) in ([\d.]+) s of wall time, which the run's ([\d.]+) s above "
                         "leaves out", line)
    assert found, line
    assert float(found[1]) == pytest.approx(csv.stat().st_size / 1e6, rel=1e-2)
    run_time = re.search(r"in ([\d.]+) s of wall time", summary_line(printed_before[0],
                                                                     "simulated "))[1]
    assert found[3] == run_time


def test_the_undamped_run_says_where_it_leaves_what_the_model_describes(tmp_path, capsys):
    """`run undamped --stop-time 5` reported dte down to -67 mm and F_mesh peaks of 2.8 MN
    without a word: its growth swings the transmission error past a tooth pitch (13.6 mm),
    where the pinion has slipped a tooth, which the model (one engaged pair, no back flank,
    no re-engagement) does not describe. The slip comes at 1.9 s sampled every 1 ms (2.8 s
    every 0.1 ms: the sampled run's steps end at the samples, and the growth amplifies the
    difference), so 4 s leaves a margin; the reference scene says nothing of it."""
    assert main(["run", "undamped", "--stop-time", "4", "--output-interval", "1e-3",
                 "--no-progress", "-o", str(tmp_path / "run.csv")]) == 0
    line = summary_line(capsys.readouterr().out, "From t = ")
    found = re.fullmatch(r"From t = ([\d.]+) s the transmission error has swung over ([\d.]+) "
                         r"mm, more than a tooth pitch \(13.6 mm on the pitch circle, "
                         r"π·m_n/cos β\): the pinion has slipped a tooth or more against the "
                         r"wheel; the model \(one engaged tooth pair, no back flank, no "
                         r"re-engagement at the next tooth\) does not describe that, and the "
                         r"outputs from there on are not the gear's", line)
    assert found, line
    assert 1.0 < float(found[1]) < 4.0 and float(found[2]) > 13.6
    assert main(["run", "reference", "--stop-time", "0.02", "--no-progress", "-o",
                 str(tmp_path / "run.csv")]) == 0
    assert "From t = " not in capsys.readouterr().out


def test_a_run_that_loses_contact_to_its_end_says_so():
    """No tooth in contact from some time to the end, longer than a period of the slowest
    mode (113 Hz: 8.9 ms), is a line; a shorter flight (a bounce) is none."""
    from herringbone.cli.run import slip_notes

    scene = herringbone.load_scene("reference")
    times = np.linspace(0.0, 0.1, 1001)
    for lost_from, said in ((0.05, True), (0.095, False)):
        results = {"time": times, "dte": np.full_like(times, 6e-5),
                   "n_contacts": np.where(times < lost_from, 6, 0)}
        lines = slip_notes(scene, results)
        assert bool(lines) == said, lines
        if said:
            assert lines[0].startswith(f"From t = {lost_from:g} s to the end (")
            assert "no tooth is in contact" in lines[0]


def test_the_reference_help_gives_its_cost_as_measured():
    """Measured: 18 CPU s per simulated second of the reference scene (the help said 40-50 s
    of wall time)."""
    from herringbone.cli import parser

    _, commands = parser()
    help_text = " ".join(commands["run"].format_help().split())
    assert "about 20 s of CPU per simulated second of the reference scene" in help_text


# --- build-fmu ---------------------------------------------------------------------------------

def test_the_builders_compile_progress_goes_to_stderr(capsys, monkeypatch, tmp_path):
    """The builder printed the compile's notes and progress to stdout, among the results."""
    from herringbone.fmu import builder
    from herringbone.integrate import first_start

    def compile_for_scene(scene, say, progress_every=10.0):
        say("compiling the integrator for this machine")
        say("  ... 10 s of about 90 s")
        raise RuntimeError("no build in this test")

    monkeypatch.setattr(first_start, "compile_for_scene", compile_for_scene)
    with pytest.raises(RuntimeError, match="no build in this test"):
        builder.carry_compiled_integrator(MODELS / "reference.toml", tmp_path)
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "compiling the integrator" in captured.err and "... 10 s of" in captured.err


@pytest.fixture
def builds(monkeypatch):
    """build-fmu's builds and compiles recorded, not made: [(what, scene as loaded, output or
    progress)]; a build writes a placeholder at its output."""
    from herringbone.cli import build_fmu
    from herringbone.fmu import builder

    made = []

    def build(scene, output, fmi_version=2):
        made.append(("build", herringbone.load_scene(scene), Path(output)))
        Path(output).parent.mkdir(parents=True, exist_ok=True)
        Path(output).write_text("an FMU")
        return Path(output)

    monkeypatch.setattr(builder, "build_gear_fmu", build)
    monkeypatch.setattr(build_fmu, "compile_first", lambda scene, progress: made.append(
        ("compile", herringbone.load_scene(scene), progress)))
    return made


def test_build_fmu_takes_set_and_no_progress(tmp_path, monkeypatch, capsys, builds):
    """`build-fmu --set` suggested "did you mean '--ssp'?" and it had no --no-progress: the FMU
    is built from the changed scene, named by the change (the scene's own FMU left as it
    is), and --no-progress leaves out the compile's progress lines."""
    monkeypatch.chdir(tmp_path)
    assert main(["build-fmu", "reference", "--set", "w0_pinion=450", "--set", "M_motor=250",
                 "--no-progress"]) == 0
    (_, compiled, progress), (_, built, output) = builds
    assert progress is False
    expected = herringbone.load_scene("reference").with_parameters(w0_pinion=450) \
        .with_inputs(M_motor=250.0)
    for scene in (compiled, built):
        assert scene.name == "reference"
        assert scene.parameters == expected.parameters
        assert (scene.inputs, scene.experiment, scene.components) == \
            (expected.inputs, expected.experiment, expected.components)
    assert output.as_posix() == "dist/reference+w0_pinion=450+M_motor=250-fmi2.fmu"
    out = capsys.readouterr().out
    assert out.startswith("scene reference with w0_pinion = 450 rad/s, M_motor = 250 N.m")
    builds.clear()
    assert main(["build-fmu", "reference"]) == 0
    assert builds[0][2] is True and builds[1][2].as_posix() == "dist/reference-fmi2.fmu"


def test_a_changed_scene_is_written_to_every_digit(tmp_path):
    """build-fmu --set's scene file gives back the scene: a torque table, components left
    out, values that need every digit."""
    from herringbone.cli.build_fmu import scene_text

    scene = herringbone.load_scene("torque_step").with_parameters(zeta_mesh=0.1 + 0.2,
                                                                  c_point=1.0e9 / 3)
    path = tmp_path / "torque_step.toml"
    path.write_text(scene_text(scene, [("zeta_mesh", 0.1 + 0.2)]))
    again = herringbone.load_scene(path)
    assert again.parameters == scene.parameters and again.given == scene.given
    assert (again.inputs, again.experiment, again.components) == \
        (scene.inputs, scene.experiment, scene.components)
    torsional = herringbone.load_scene("torsional")  # bearings = false
    path.write_text(scene_text(torsional, []))
    assert herringbone.load_scene(path).components == torsional.components


def test_build_fmu_without_progress_compiles_without_progress_lines(monkeypatch):
    """compile_first hands the compile its progress interval: 10 s, or never."""
    from herringbone.cli.build_fmu import compile_first
    from herringbone.integrate import first_start

    given = []
    monkeypatch.setattr(first_start, "compile_for_scene",
                        lambda scene, say, progress_every: given.append(progress_every))
    compile_first(MODELS / "reference.toml", True)
    compile_first(MODELS / "reference.toml", False)
    assert given == [10.0, threading.TIMEOUT_MAX]


# --- paths, speeds, options ---------------------------------------------------------------------

def test_an_output_name_too_long_is_one_line(tmp_path, capsys, monkeypatch):
    """`run -o <300 characters>.csv` ended in an OSError traceback (Path.is_dir raised
    "File name too long")."""
    monkeypatch.chdir(tmp_path)
    long_name = "a" * 300
    for argv, command in ((["run", REFERENCE, "-o", f"{long_name}.csv"], "run"),
                          (["sweep", REFERENCE, "--speeds", "100", "200", "2", "-o", long_name],
                           "sweep"),
                          (["sweep", REFERENCE, "--speeds", "100", "200", "2", "--through-fmu",
                            f"{long_name}.fmu"], "sweep"),
                          (["build-fmu", REFERENCE, "--ssp", f"{long_name}.ssp"], "build-fmu")):
        assert main(argv) == 2
        assert "File name too long" in one_error_line(capsys, command)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kind", ["device", "pipe", "dangling-link"])
def test_a_scene_that_is_no_regular_file_says_what_it_is(kind, tmp_path, capsys):
    """A scene that is a link to /dev/zero was "no such scene file", though it is there (the
    command line asks shipped.unreadable before it loads the scene: load_scene itself still
    says "no such scene file")."""
    path = tmp_path / "scene.toml"
    words = {"device": "not a regular file: a character device (a symbolic link to /dev/zero)",
             "pipe": "not a regular file: a named pipe (FIFO)",
             "dangling-link": f"a symbolic link to {tmp_path / 'gone.toml'}, which does not "
                              "exist"}[kind]
    if kind == "device":
        path.symlink_to("/dev/zero")
    elif kind == "pipe":
        os.mkfifo(path)
    else:
        path.symlink_to(tmp_path / "gone.toml")
    for command in (["run", str(path), "-o", str(tmp_path / "run.csv")], ["info", str(path)],
                    ["build-fmu", str(path), "-o", str(tmp_path / "x.fmu")]):
        assert main(command) == 2
        assert f"{path}: {words}; allowed: a scene file (TOML)" in one_error_line(capsys,
                                                                                 command[0])


def test_speeds_are_bounded_alike_in_every_command(capsys):
    """`stability --speeds 10 1e5 99999999999` ended in numpy's "Unable to allocate 745 GiB";
    `campbell --speeds 10 1e300 5` was taken, where the scene takes speeds to 1e5 rad/s."""
    for command in ("stability", "sweep", "campbell"):
        assert main([command, REFERENCE, "--speeds", "10", "1e5", "99999999999"]) == 2
        assert "COUNT 1e+11 is more than 100000 speeds" in one_error_line(capsys, command)
        for speeds, unit in ((["10", "1e300", "5"], "rad/s"), (["10", "1e6", "5", "--rpm"],
                                                               "rpm")):
            assert main([command, REFERENCE, "--speeds", *speeds]) == 2
            error = one_error_line(capsys, command)
            assert f"TO {float(speeds[1]):g} {unit} is faster than any pinion speed" in error
            assert "allowed: 0 < FROM < TO <= 100000 rad/s (954930 rpm with --rpm)" in error


def test_every_value_is_named_by_what_it_is(capsys):
    """Metavars were argparse's upper-cased option names (STOP_TIME, WORKERS) beside the
    project's own (W, FILE): each option that takes a value names it, or lists its choices;
    --speeds' help gives its unit once; a flag given a value says it takes none."""
    from herringbone.cli import parser

    _, commands = parser()
    for name, command in commands.items():
        for action in command._actions:
            if action.option_strings and action.nargs != 0 and action.choices is None \
                    and "--help" not in action.option_strings:
                assert action.metavar is not None, (name, action.option_strings)
    speeds = next(a for a in commands["stability"]._actions if "--speeds" in a.option_strings)
    assert speeds.help.count("rad/s") == 1, speeds.help
    assert main(["run", REFERENCE, "--plot=yes"]) == 2
    assert "--plot=yes: takes no value; allowed: --plot alone" in one_error_line(capsys, "run")


def test_the_no_tqdm_note_is_one_sentence(monkeypatch, capsys, tmp_path):
    """It read "... (or every dependency of the 'analysis' extra: ...) (or give
    --no-progress)": two brackets in a row."""
    monkeypatch.setitem(sys.modules, "tqdm", None)  # import tqdm now fails
    assert main(["stability", REFERENCE, "--speeds", "100", "200", "3", "-o",
                 str(tmp_path / "chart.png")]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines()
             if line.startswith("no progress bar")]
    assert len(notes) == 1 and notes[0].count("(") == 1, notes
    assert "--no-progress leaves out this line" in notes[0]
