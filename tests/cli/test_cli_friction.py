"""The command line as a newcomer meets it: every friction point a first hour with it showed,
one test each. In-process (`main([...])`, capsys) where possible: a process start costs a second
or two of imports."""
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import MODELS, one_error_line

import herringbone
from herringbone.cli import main

REFERENCE = str(MODELS / "reference.toml")
# the summary's line of a compiled run's internal steps: (steps, per simulated second)
STEPS_LINE = re.compile(r"^(\d+) internal steps \(([\d.e+-]+) per simulated second\)$",
                        re.MULTILINE)


def reference_variant(folder, name: str, *replacements: tuple[str, str]):
    """models/reference.toml written to folder/NAME.toml with each (old, new) replaced."""
    text = (MODELS / "reference.toml").read_text()
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new)
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path


@pytest.fixture
def no_work(monkeypatch):
    """Any run, chart or sweep beginning fails the test: the check must come first."""
    import importlib

    def refuse(*args, **kwargs):
        raise AssertionError("the work began before the arguments were checked")

    for module, name in (("analysis.sweep", "run_checked_points"), ("analysis.stability",
                                                           "stability_chart"),
                         ("analysis.run_progress", "simulate_with_progress"),
                         ("cli.run", "compiled_run"), ("analysis.campbell", "plot_campbell"),
                         ("fmu.builder", "build_gear_fmu"), ("cli.build_fmu", "compile_first")):
        monkeypatch.setattr(importlib.import_module(f"herringbone.{module}"), name, refuse)


def test_sweep_onto_a_file_fails_at_once_in_one_line(tmp_path, capsys, no_work):
    afile = tmp_path / "afile"
    afile.write_text("keep me\n")
    assert main(["sweep", REFERENCE, "--speeds", "100", "200", "2", "-o", str(afile)]) == 2
    error = one_error_line(capsys, "sweep")
    assert "--output" in error and "is a file" in error and "folder" in error
    assert afile.read_text() == "keep me\n"


def test_sweep_default_folder_a_file_fails_before_work(tmp_path, capsys, no_work, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results").write_text("a file\n")
    assert main(["sweep", REFERENCE, "--speeds", "100", "200", "2"]) == 2
    assert "results" in one_error_line(capsys, "sweep")


@pytest.mark.parametrize("command, output, words", [
    ("stability", "chart.csv", ("not a .png",)),
    ("stability", "/proc/nope/x.png", ("/proc/nope",)),
    ("campbell", "diagram.csv", ("not a .png",)),
    ("run", "out.png", ("not a .csv",)),
])
def test_an_output_of_the_wrong_kind_or_place_is_refused_before_work(
        command, output, words, tmp_path, capsys, no_work, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([command, REFERENCE, "-o", output]) == 2
    error = one_error_line(capsys, command)
    assert "--output" in error and all(word in error for word in words), error
    assert list(tmp_path.iterdir()) == []


def test_every_output_option_says_file_or_folder():
    from herringbone.cli import parser

    _, commands = parser()
    for name, command in commands.items():
        for action in command._actions:
            if "--output" in action.option_strings:
                assert "-o" in action.option_strings, name
                assert re.search(r"\b(file|folder)\b", action.help), (name, action.help)


def test_speeds_take_the_same_form_everywhere(capsys, no_work):
    """FROM TO COUNT, COUNT >= 2, in stability, sweep and campbell alike."""
    from herringbone.cli import parser

    _, commands = parser()
    for name in ("stability", "sweep", "campbell"):
        speeds = next(a for a in commands[name]._actions if "--speeds" in a.option_strings)
        assert speeds.metavar == ("FROM", "TO", "COUNT") and speeds.nargs == 3, name
        assert main([name, REFERENCE, "--speeds", "100", "200", "1"]) == 2
        error = one_error_line(capsys, name)
        assert "COUNT 1" in error and "COUNT >= 2" in error


@pytest.mark.parametrize("argv, command, suggestion", [
    (["run", "refrence"], "run", "'reference'"),
    (["run", REFERENCE, "--stoptime", "1"], "run", "'--stop-time'"),
    (["sweep", REFERENCE, "--param", "z_pinon", "10", "12", "2"], "sweep", "'z_pinion'"),
    (["sweep", REFERENCE, "--param", "zeta", "0.02", "0.05", "2"], "sweep", "'zeta_mesh'"),
    # in other case: difflib ranked h_shaft_in, one letter off, above it
    (["sweep", REFERENCE, "--param", "c_shaft_in", "1e4", "2e4", "2"], "sweep",
     "'C_shaft_in'"),
    (["stability", REFERENCE, "--speed", "1", "2", "3", "--outptu", "x.png"], "stability",
     "'--output'"),
])
def test_a_typo_gets_did_you_mean(argv, command, suggestion, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    error = one_error_line(capsys, command)
    assert f"did you mean {suggestion}?" in error


def test_a_misspelt_command_and_parameter_get_did_you_mean(capsys, tmp_path):
    assert main(["stabilty", REFERENCE]) == 2
    assert "did you mean 'stability'?" in capsys.readouterr().err
    scene = tmp_path / "typo.toml"
    scene.write_text("[parameters]\nz_pinon = 12\n")
    assert main(["info", str(scene)]) == 2
    assert "did you mean 'z_pinion'?" in one_error_line(capsys, "info")


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"herringbone {herringbone.__version__}"


def test_errors_of_run_name_the_command(capsys, tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text("[parameters]\nbeta = 22.86\n")
    assert main(["run", str(scene)]) == 2
    error = one_error_line(capsys, "run")
    # the unit, named as radians: the value was meant in degrees
    assert "beta is 22.86 rad; allowed: [0.01, 1.4] rad, an angle in radians" in error


def test_build_fmu_names_its_fmu_by_scene_and_fmi_version(capsys):
    from herringbone.cli.build_fmu import declare
    from herringbone.fmu.builder import default_fmu_name

    assert default_fmu_name("torsional", 2) != default_fmu_name("reference", 2)
    assert default_fmu_name("reference", 3) != default_fmu_name("reference", 2)
    assert default_fmu_name("reference", 2) == "reference-fmi2.fmu"
    parser = herringbone.arguments.OneLineParser(prog="x")
    declare(parser)
    help_text = parser.format_help()
    assert "<scene>-fmi<N>.fmu" in " ".join(help_text.split())


def test_build_fmu_of_another_scene_leaves_the_reference_fmu(tmp_path, monkeypatch, capsys):
    """Building torsional (FMI 2.0), then reference with --fmi 3, in a folder that already
    holds the reference FMI 2.0 FMU: each lands in its own file, the first untouched."""
    from herringbone.cli import build_fmu
    from herringbone.fmu import builder

    built = []

    def build(scene, output, fmi_version=2):
        built.append((Path(scene).name, Path(output), fmi_version))
        Path(output).write_text(f"{scene} {fmi_version}")
        return Path(output)

    monkeypatch.setattr(builder, "build_gear_fmu", build)
    monkeypatch.setattr(build_fmu, "compile_first", lambda scene, progress: None)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "dist").mkdir()
    reference = tmp_path / "dist" / "reference-fmi2.fmu"
    reference.write_text("the reference FMU")
    assert main(["build-fmu", "torsional"]) == 0
    assert main(["build-fmu", "reference", "--fmi", "3"]) == 0
    assert reference.read_text() == "the reference FMU"
    assert [(name, output.as_posix(), version) for name, output, version in built] == [
        ("torsional", "dist/torsional-fmi2.fmu", 2), ("reference", "dist/reference-fmi3.fmu", 3)]
    assert "built dist/torsional-fmi2.fmu" in capsys.readouterr().out


def test_build_fmu_refuses_an_output_that_is_no_fmu(tmp_path, capsys, no_work):
    assert main(["build-fmu", "reference", "-o", str(tmp_path / "x.zip")]) == 2
    assert "not a .fmu file" in one_error_line(capsys, "build-fmu")


def test_run_defaults_to_the_compiled_integrator_and_its_numbers(tmp_path, capsys):
    """`run` gives herringbone.simulate's numbers to the CSV's 12 digits, with units in the
    header and the summary; --reference gives reference_simulate's."""
    scene = herringbone.load_scene("reference")
    span = dict(stop_time=2e-3, output_interval=1e-4)
    csv = tmp_path / "run.csv"
    assert main(["run", "reference", "--stop-time", "2e-3", "--output-interval", "1e-4",
                 "--no-progress", "-o", str(csv)]) == 0
    printed = capsys.readouterr().out
    assert "on the compiled integrator" in printed
    assert re.search(r"^dte\s+µm\s", printed, re.MULTILINE)  # dte shown in µm, with its unit
    assert re.search(r"^F_mesh\s+N\s", printed, re.MULTILINE)
    header = csv.read_text().splitlines()[0].split(",")
    assert header[:2] == ["time [s]", "k_mesh [N/m]"] and "dte [m]" in header
    assert "n_contacts" in header
    table = np.loadtxt(csv, delimiter=",", skiprows=1)
    expected = herringbone.simulate(scene, **span)
    assert np.allclose(table[:, header.index("F_mesh [N]")], expected["F_mesh"], rtol=1e-11)
    assert main(["run", "reference", "--reference", "--stop-time", "2e-3",
                 "--output-interval", "1e-4", "--no-progress", "-o", str(csv)]) == 0
    assert "on the scipy reference" in capsys.readouterr().out
    table = np.loadtxt(csv, delimiter=",", skiprows=1)
    expected = herringbone.reference_simulate(scene, **span)
    assert np.allclose(table[:, header.index("F_mesh [N]")], expected["F_mesh"], rtol=1e-11)


def test_run_tolerance_is_checked_against_the_integrator_chosen(capsys, no_work, tmp_path):
    with pytest.raises(AssertionError, match="the work began"):  # the compiled one allows it
        main(["run", REFERENCE, "--tolerance", "1e-3", "-o", str(tmp_path / "x.csv")])
    assert main(["run", REFERENCE, "--reference", "--tolerance", "1e-3"]) == 2
    assert "[1e-12, 1e-05]" in one_error_line(capsys, "run")


def test_a_run_too_large_for_the_memory_is_refused_before_work(capsys, no_work, monkeypatch):
    """--stop-time 1e5 --output-interval 1e-7 ended in numpy's "Unable to allocate 7.28 TiB"
    and a traceback: one line naming both options, the size and what is allowed instead (the
    machine's memory taken as 1 GiB, whatever this one has)."""
    from herringbone import arguments

    monkeypatch.setattr(arguments, "physical_memory", lambda: 2 ** 30, raising=False)
    assert main(["run", REFERENCE, "--stop-time", "1e5", "--output-interval", "1e-7"]) == 2
    error = one_error_line(capsys, "run")
    assert "--stop-time 100000 s with --output-interval 1e-07 s is 1e+12 samples" in error
    assert "138 TiB; allowed: at most 3.53e+06 samples" in error and "1 GiB" in error


def test_a_benchmark_of_a_scene_that_is_not_there_is_one_line_and_exit_2(capsys):
    """`benchmark --scenes nosuch` said "benchmark: no scene file …" with exit code 1."""
    for scenes, words in ((["nosuch"], "no scene file"), (["refrence"], "'reference'?"),
                          (["nosuch*.toml"], "no scene file matches it")):
        assert main(["benchmark", "--quick", "--scenes", *scenes]) == 2
        error = one_error_line(capsys, "benchmark error-vs-runtime")
        assert f"--scenes {scenes[0]}: " in error and words in error
        assert "allowed: scene names (models/NAME.toml), scene files or globs" in error


def test_the_compiled_run_shows_progress_and_keeps_its_numbers(capsys):
    """With the bar, and with the compiled loop loaded first for on_ready (a run of a
    nanosecond), the numbers are herringbone.simulate's to the bit."""
    from herringbone.analysis.run_progress import simulate_with_progress

    scene = herringbone.load_scene("reference")
    plain = herringbone.simulate(scene, stop_time=2e-3, output_interval=1e-4)
    ready = []
    watched = simulate_with_progress(scene, stop_time=2e-3, output_interval=1e-4)
    loaded_first = simulate_with_progress(scene, stop_time=2e-3, output_interval=1e-4,
                                          on_ready=lambda *said: ready.append(said))
    for name in plain:
        assert np.array_equal(plain[name], watched[name]), name
        assert np.array_equal(plain[name], loaded_first[name]), name
    assert ready == [("exponential", "")]  # the method auto takes for the scene, as named
    assert "s simulated" in capsys.readouterr().err


def test_the_run_with_its_bar_samples_into_an_array_as_simulate_does(monkeypatch, capsys):
    """simulate_with_progress takes herringbone.simulate's way, the samples written into an
    array by the compiled calls, not handed one by one to a callback as dicts (3.3 µs a
    sample more: a simulated second of the reference scene took 0.047 s that way, 0.014 s
    this way): with CompiledStepper.advance, the callback's way, refused, it still runs,
    and its bar reaches the end."""
    from herringbone.analysis.run_progress import simulate_with_progress
    from herringbone.integrate.compiled_stepper import CompiledStepper

    def refused(*arguments, **keywords):
        raise AssertionError("the samples went the callback's way")

    monkeypatch.setattr(CompiledStepper, "advance", refused)
    scene = herringbone.load_scene("reference")
    result = simulate_with_progress(scene, stop_time=2e-3, output_interval=1e-4)
    assert len(result["time"]) == 21
    assert "0.002/0.002 s simulated" in capsys.readouterr().err


def test_run_tells_its_start_from_its_stepping(tmp_path, capsys):
    """A short run's wall time is mostly its start (the model's tables, the compiled code
    loaded: 0.2 s on the project's machine), which a rate over the whole would charge to the
    stepping (11 s per simulated second for 20 ms of the reference scene, whose stepping
    takes 0.07): `run` prints the start apart, and the rate of the stepping alone; the two
    add up to the wall time. Where the start is not known (the scipy reference's run) the
    rate says that it includes it."""
    from herringbone.analysis.run_report import summary

    assert main(["run", "reference", "--stop-time", "2e-3", "--output-interval", "1e-4",
                 "--no-progress", "-o", str(tmp_path / "run.csv")]) == 0
    line = next(text for text in capsys.readouterr().out.splitlines()
                if text.startswith("simulated "))
    found = re.search(r"in ([\d.]+) s of wall time: ([\d.]+) s to start \(.*\), ([\d.e+-]+) s "
                      r"stepping \(([\d.e+-]+) s per simulated second\)", line)
    assert found, line
    wall, start, stepping, rate = map(float, found.groups())
    assert start + stepping == pytest.approx(wall, abs=0.01)
    assert rate == pytest.approx(stepping / 2e-3, rel=1e-2)
    scene = herringbone.load_scene("reference")
    results = herringbone.simulate(scene, stop_time=2e-3, output_interval=1e-4)
    assert "0.50 s of wall time, start included (250.00 s per simulated second)" in summary(
        scene, results, 0.5, "its FMU")


@pytest.mark.parametrize("method", ["exponential", "dop853"])
def test_run_counts_its_internal_steps(tmp_path, capsys, method):
    """The summary gives the run's internal steps, what its cost grows with: those of the
    same run by CompiledStepper, not the warm-up's (the reference scene over 20 ms: about
    1.1e3 a simulated second by the exponential method, one a segment between contact
    switches; DOP853 far more, following the 10-13 kHz ringing)."""
    from herringbone.integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper
    from herringbone.integrate.contract import simulate_with
    from herringbone.model.assembly import GearTrainModel

    assert main(["run", "reference", "--stop-time", "0.02", "--method", method,
                 "--no-progress", "-o", str(tmp_path / "run.csv")]) == 0
    found = STEPS_LINE.search(capsys.readouterr().out)
    assert found
    steps, rate = int(found[1]), float(found[2])
    scene = herringbone.load_scene("reference")
    stepper = CompiledStepper(GearTrainModel(scene), DEFAULT_TOLERANCE, method)
    simulate_with(stepper, scene, 0.02)
    assert steps == stepper.accepted_steps
    assert rate == pytest.approx(steps / 0.02, rel=1e-2)
    assert (500 <= rate <= 3000) if method == "exponential" else rate >= 10_000


def test_build_fmu_simulate_tells_the_fmus_start_from_its_stepping(tmp_path, capsys,
                                                                     monkeypatch):
    """Through fmpy the start (the FMU unpacked, instantiated and set up) took 0.12 s of a
    0.19 s run of 0.1 s, and a rate over the whole read 1.16 s per simulated second where the
    stepping's is a third of it: the start is apart, ending at the first step's end."""
    monkeypatch.chdir(tmp_path)
    assert main(["build-fmu", "reference", "--simulate", "--no-progress"]) == 0
    out = capsys.readouterr().out
    line = next(text for text in out.splitlines() if text.startswith("simulated "))
    found = re.search(r"in ([\d.]+) s of wall time: ([\d.]+) s to start \(the FMU unpacked, "
                      r"instantiated and set up, its first step\), ([\d.e+-]+) s stepping "
                      r"\(([\d.e+-]+) s per simulated second\)", line)
    assert found, line
    wall, start, stepping, rate = map(float, found.groups())
    assert start + stepping == pytest.approx(wall, abs=0.01)
    assert rate == pytest.approx(stepping / 0.1, rel=1e-2)  # the scene's stop time
    fmu_steps(out)


def fmu_steps(out: str) -> None:
    """The FMU's internal steps in build-fmu's summary are its integrator's, one call of
    run_to a communication step as the FMU makes them (the reference scene: about 1.1e4 a
    simulated second, a call's end ending a step besides each switch), not the outputs' rows
    (1e4 a second) nor the steps of one call over the run (about 1.1e3); not in the table."""
    from herringbone.integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper
    from herringbone.integrate.contract import output_times, start_position
    from herringbone.model.assembly import GearTrainModel

    found = STEPS_LINE.search(out)
    assert found and "internal_steps" not in out, out
    scene = herringbone.load_scene("reference")
    stepper = CompiledStepper(GearTrainModel(scene), DEFAULT_TOLERANCE)
    run = stepper.start(start_position(stepper.model, scene.inputs.at(0.0)[0]))
    times = output_times(scene.experiment.stop_time, scene.experiment.output_interval)
    for end in times[1:]:
        stepper.run_to(run, end, scene.inputs.at(0.0))
    assert int(found[1]) == stepper.accepted_steps > len(times)


def test_the_console_script_runs_the_package(tmp_path):
    """`herringbone` as installed (pyproject's herringbone.cli:main) from another folder."""
    run = subprocess.run([str(Path(sys.executable).parent / "herringbone"), "--version"],
                         capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert run.returncode == 0 and run.stdout.startswith("herringbone ")


def test_the_stability_chart_reports_progress_and_keeps_its_numbers():
    """The chart in batches (for `stability`'s bar) is the chart in one go, to the bit."""
    from herringbone.analysis.stability import stability_chart

    scene = herringbone.load_scene("reference")
    speeds = np.linspace(100.0, 3000.0, 12)
    done = []
    batched = stability_chart(scene, speeds, on_progress=done.append)
    whole = stability_chart(scene, speeds)
    assert sum(done) == len(speeds) and len(done) > 1
    assert np.array_equal(batched.largest_modulus, whole.largest_modulus)
    assert batched.unstable_bands == whole.unstable_bands


@pytest.mark.parametrize("arguments, culprit", [
    (["--param", "stagger", "0", "0.5", "3", "--param", "eps_q", "0.5", "0.6", "2",
      "--method", "shooting"], "--method shooting"),
    (["--param", "stagger", "0", "0.5", "3", "--time-sweeps"], "--time-sweeps"),
    (["--speeds", "100", "200", "3", "--method", "time", "--time-sweeps"], "--time-sweeps"),
])
def test_a_sweep_method_that_cannot_run_is_refused_before_any_work(arguments, culprit, capsys,
                                                                    monkeypatch, no_work):
    import herringbone.analysis.sweep as sweep_module

    monkeypatch.setattr(sweep_module, "shooting_sweep", no_work_at_all)
    assert main(["sweep", REFERENCE, *arguments, "--no-progress"]) == 2
    error = one_error_line(capsys, "sweep")
    assert culprit in error and "allowed:" in error


def no_work_at_all(*args, **kwargs):
    raise AssertionError("the work began before the arguments were checked")


def test_a_speed_sweep_finds_the_periodic_branch_and_draws_no_waterfall(tmp_path, capsys):
    assert main(["sweep", REFERENCE, "--speeds", "500", "600", "3", "--no-progress",
                 "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "periodic steady state by shooting and continuation: " in out
    written = sorted(path.name for path in tmp_path.iterdir())
    assert written == ["reference_sweep_w0_pinion.csv", "reference_sweep_w0_pinion_resonance.png"]
    header = (tmp_path / "reference_sweep_w0_pinion.csv").read_text().splitlines()[0]
    assert "stability" in header and "w0_pinion [rad/s]" in header


@pytest.mark.parametrize("command", [[], ["run"], ["sweep"], ["info"], ["stability"],
                                     ["campbell"], ["build-fmu"], ["benchmark"]])
def test_help_answers_without_loading_the_integrators(command):
    """Asking a command for its help (or a bad option) loads neither numba nor scipy: the
    command line names its defaults from arguments.py, and each command imports its work
    where it runs it."""
    code = ("import sys\nfrom herringbone.cli import main\ntry:\n"
            f"    main({command + ['--help']!r})\nexcept SystemExit:\n    pass\n"
            "print(sorted({'numba', 'scipy', 'matplotlib'} & set(sys.modules)))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True).stdout.strip().splitlines()[-1]
    assert loaded == "[]", f"herringbone {' '.join(command)} --help loaded {loaded}"


def interrupted(arguments, folder, ready: str, group: bool = False, sent=None,
                delay: float = 1.0):
    """`herringbone ARGUMENTS` run in `folder` and sent SIGINT (or the signal `sent`) once its
    stderr shows `ready` and `delay` s more have passed: to the process alone, or to its whole
    process group (Dask's workers too) where `group`, as Ctrl-C at a terminal does. Returns
    (exit code, stderr)."""
    import os
    import signal
    import time

    sent = signal.SIGINT if sent is None else sent

    def default_interrupt():  # a job started in the background, as CI's may be, inherits
        signal.signal(signal.SIGINT, signal.SIG_DFL)  # SIGINT ignored, as a shell sets it

    process = subprocess.Popen([str(Path(sys.executable).parent / "herringbone"), *arguments],
                               cwd=folder, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               start_new_session=True, preexec_fn=default_interrupt)
    assert process.stderr is not None
    seen, deadline = b"", time.monotonic() + 120
    while ready.encode() not in seen and time.monotonic() < deadline:
        chunk = os.read(process.stderr.fileno(), 4096)
        if not chunk:  # the command ended before it showed `ready`
            break
        seen += chunk
    time.sleep(delay)
    if group:
        os.killpg(process.pid, sent)
    else:
        process.send_signal(sent)
    rest = process.communicate(timeout=120)[1]
    return process.returncode, (seen + rest).decode()


def assert_stopped_in_one_line(code, stderr, folder, expected: int, stop: str):
    """The run stopped with exit code `expected` and one last line saying `stop`, no
    traceback, and the folder's out.csv as it was, nothing beside it."""
    assert code == expected, stderr
    assert stderr.splitlines()[-1] == (f"herringbone run: {stop}; files not finished are "
                                       "left as they were")
    assert "Traceback" not in stderr
    assert (folder / "out.csv").read_text() == "the last run's table\n"
    assert sorted(p.name for p in folder.iterdir()) == ["out.csv"]


def test_ctrl_c_stops_a_run_in_one_line_and_leaves_the_file_it_would_replace(tmp_path):
    (tmp_path / "out.csv").write_text("the last run's table\n")
    code, stderr = interrupted(["run", "reference", "--reference", "--stop-time", "1", "-o",
                                "out.csv"], tmp_path, "run reference:")
    assert_stopped_in_one_line(code, stderr, tmp_path, 130, "interrupted")


def test_sigterm_while_the_table_is_written_stops_in_one_line_and_leaves_no_half_file(
        tmp_path):
    """`timeout`, a batch scheduler and CI end a command by SIGTERM, whose default action
    left the 200 001 rows' staging file behind (half a table, 48 MB here)."""
    import signal

    (tmp_path / "out.csv").write_text("the last run's table\n")
    code, stderr = interrupted(["run", "reference", "--stop-time", "2", "--output-interval",
                                "1e-5", "-o", "out.csv"], tmp_path, "writing 200001 rows",
                               sent=signal.SIGTERM, delay=0.3)
    assert_stopped_in_one_line(code, stderr, tmp_path, 143, "terminated")


def test_ctrl_c_stops_a_sweep_on_workers_in_one_line_not_a_traceback_from_each(tmp_path):
    code, stderr = interrupted(["sweep", "reference", "--speeds", "100", "1000", "400",
                                "--method", "time", "--workers", "2", "-o", "sweep"],
                               tmp_path, "sweep:", group=True)
    assert code == 130, stderr
    lines = [line for line in stderr.replace("\r", "\n").splitlines() if line.strip()]
    assert lines[-1].startswith("herringbone sweep: interrupted")
    # nothing but the bar before it: no traceback, no worker's warning that its running
    # points were cancelled
    assert [line for line in lines[:-1] if not line.startswith("sweep:")] == [], stderr
    assert not list(tmp_path.rglob("*.csv"))


def _raised_inside_a_compiled_call():
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as interrupt:  # numba's dispatcher hands it on so
        raise SystemError("CPUDispatcher(...) returned a result with an exception set") \
            from interrupt


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt, _raised_inside_a_compiled_call],
                         ids=["plain", "inside-a-compiled-call"])
def test_an_interrupt_wherever_it_lands_is_one_line_and_exit_130(interrupt, monkeypatch,
                                                                  capsys):
    from herringbone.cli import run

    def execute(args, parser):
        if interrupt is KeyboardInterrupt:
            raise KeyboardInterrupt
        interrupt()

    monkeypatch.setattr(run, "execute", execute)
    assert main(["run", "reference"]) == 130
    assert one_error_line(capsys, "run").startswith("herringbone run: interrupted")


def test_an_unexpected_error_is_not_taken_for_an_interrupt(monkeypatch):
    from herringbone.cli import run

    def execute(args, parser):
        raise ZeroDivisionError("a fault of the program")

    monkeypatch.setattr(run, "execute", execute)
    with pytest.raises(ZeroDivisionError):
        main(["run", "reference"])


def test_info_gives_a_backward_speed_with_its_sign(tmp_path, capsys):
    """w0_pinion < 0 turns the train backwards (docs/model.md): `info` gives the speed as the
    scene does, and the mesh frequency, which has no sign, as at the forward speed."""
    scene = tmp_path / "backwards.toml"
    scene.write_text((MODELS / "reference.toml").read_text().replace(
        "w0_pinion = 157.08", "w0_pinion = -157.08"))
    assert main(["info", str(scene)]) == 0
    assert "Mesh frequency at w0_pinion = -157.08 rad/s (-1500 rpm): 250.00 Hz" in \
        capsys.readouterr().out


def test_scenes_lists_every_shipped_scene_by_name_with_a_whole_sentence(capsys):
    """One line a scene, in the order of their names, each the first sentence of its header
    (not a "Run:" line, not cut mid-sentence; a long one cut at a word with "…")."""
    from herringbone.shipped import HEADLINE_WIDTH, scene_files

    assert main(["scenes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    names = [line.split()[0] for line in lines]
    assert names == sorted(scene_files()) and "parametric_resonance" in names
    for line in lines:
        said = line.split(None, 1)[1]
        assert said.endswith((".", " …")) and len(said) <= HEADLINE_WIDTH + 1, line
        assert not said.startswith("Run:"), line


def test_a_run_whose_torques_load_the_back_flanks_says_so(tmp_path, capsys):
    """M_motor < 0 presses the back flanks together, on which the model has no contact: the
    run goes on as the model says (the teeth separate, F_mesh 0), and its summary says why
    beside the negative static mesh force, which it printed bare."""
    scene = reference_variant(tmp_path, "backwards_torque", ("M_motor = 500.0", "M_motor = -500.0"),
                              ("M_load = 1800.0", "M_load = -1800.0"))
    assert main(["run", str(scene), "--stop-time", "2e-3", "--output-interval", "1e-4",
                 "--no-progress", "-o", str(tmp_path / "run.csv")]) == 0
    (line,) = [text for text in capsys.readouterr().out.splitlines()
               if text.startswith("static mesh force")]
    assert line == ("static mesh force M_motor/Rp = -23036.4 N (negative: M_motor < 0 loads "
                    "the back flanks, on which the model has no contact: the teeth separate)")
    mesh_force = np.loadtxt(tmp_path / "run.csv", delimiter=",", skiprows=1, usecols=4)
    assert len(mesh_force) == 21 and (mesh_force == 0.0).all()  # F_mesh [N]: no contact


def test_a_run_of_a_torque_table_says_whose_static_force_it_prints(tmp_path, capsys):
    """torque_step's torques step tenfold at 5 ms: the static mesh force printed is the first
    row's (500 N·m / Rp), and the line names the force the tolerance is relative to, the
    largest torque's, ten times it."""
    assert main(["run", "torque_step", "--stop-time", "1e-3", "--no-progress",
                 "-o", str(tmp_path / "run.csv")]) == 0
    (line,) = [text for text in capsys.readouterr().out.splitlines()
               if text.startswith("static mesh force")]
    assert line == ("static mesh force M_motor/Rp = 23036.4 N at t = 0 (M_motor = 500 N·m, the "
                    "torque table's first row; the tolerance is relative to the largest "
                    "torque's, 230364.2 N)")


def test_a_run_whose_face_leaves_the_pair_without_contact_says_so(tmp_path, capsys):
    """A face of 0.1 mm (ε_β = 0.003 a half) has no point on it for 99.4 % of each mesh period:
    the run goes on as the model says (F_mesh 0 most of the time), and its summary says why
    beside the static mesh force, which it printed as if the pair carried it."""
    scene = reference_variant(tmp_path, "narrow_face", ("b_left = 0.035", "b_left = 0.0001"),
                              ("b_right = 0.035", "b_right = 0.0001"))
    assert main(["run", str(scene), "--stop-time", "2e-3", "--output-interval", "1e-4",
                 "--no-progress", "-o", str(tmp_path / "run.csv")]) == 0
    lines = capsys.readouterr().out.splitlines()
    at = next(i for i, text in enumerate(lines) if text.startswith("static mesh force"))
    assert lines[at + 1] == ("No point is on the face for 99.4 % of each mesh period: the pair "
                             "transmits no torque then, and the teeth meet again by impact (a "
                             "wider face keeps a point on it)")
    mesh_force = np.loadtxt(tmp_path / "run.csv", delimiter=",", skiprows=1, usecols=4)
    assert (mesh_force == 0.0).mean() > 0.5  # F_mesh [N]


def test_a_run_of_a_shipped_scene_has_no_word_on_contact_gaps(tmp_path, capsys):
    assert main(["run", "reference", "--stop-time", "1e-3", "--no-progress",
                 "-o", str(tmp_path / "run.csv")]) == 0
    assert "no point is on the face" not in capsys.readouterr().out.lower()


def test_a_run_that_starts_with_points_in_tension_says_why_f_mesh_starts_high(tmp_path, capsys):
    """contact_loss: the start's static equilibrium (every point loaded, docs/model.md section
    6) leaves three of its six points in tension, which start unloaded: F_mesh starts at
    4165 N against the static 2304 N, and the summary says why beside it."""
    assert main(["run", "contact_loss", "--stop-time", "1e-3", "--no-progress",
                 "-o", str(tmp_path / "run.csv")]) == 0
    (line,) = [text for text in capsys.readouterr().out.splitlines()
               if text.startswith("static mesh force")]
    assert line == ("static mesh force M_motor/Rp = 2303.6 N; F_mesh starts at 4165.4 N: the "
                    "start's static equilibrium (every point loaded) leaves points in tension, "
                    "which start unloaded, and the run starts with a transient")


@pytest.mark.parametrize("scene_text, said, balanced", [
    # M_motor alone keeps the reference's M_load = 1800 N·m, which no longer balances it: the
    # pinion from 157 to 380 rad/s in 20 ms without a word before
    ("[parameters]\nz_pinion = 14\n[inputs]\nM_motor = 2000.0\n",
     "M_load = 1800 N·m does not balance M_motor = 2000 N·m (u = 2.57143): the train "
     "accelerates (steady running needs M_load = u·M_motor = 5142.86 N·m)", "reference"),
    # docs/scenes.md's example: M_motor stepped alone at 0.05 s, the pinion from 157 to 425
    # rad/s; torque_step, whose rows all balance, says nothing
    ("[inputs]\ntable = [[0.0, 500.0, 1800.0], [0.05, 1000.0, 1800.0]]\n",
     "from t = 0.05 s M_load = 1800 N·m does not balance M_motor = 1000 N·m (u = 3.6): the "
     "train accelerates while they hold (steady running needs M_load = u·M_motor)",
     "torque_step"),
], ids=["constant", "table"])
def test_torques_that_do_not_balance_are_said_by_info_and_run(tmp_path, capsys, scene_text,
                                                               said, balanced):
    """Torques that do not balance accelerate the train: info and the run's summary say so,
    of constant torques and of an input table's rows alike; a balanced scene says nothing."""
    scene = tmp_path / "unbalanced.toml"
    scene.write_text(scene_text)
    assert main(["info", str(scene)]) == 0
    assert said in capsys.readouterr().out.splitlines()
    assert main(["run", str(scene), "--stop-time", "1e-3", "--no-progress",
                 "-o", str(tmp_path / "run.csv")]) == 0
    assert said in capsys.readouterr().out.splitlines()
    assert main(["info", balanced]) == 0
    assert "does not balance" not in capsys.readouterr().out


def test_a_run_whose_static_deflection_is_not_small_says_so(tmp_path, capsys):
    """Bearings of 1e4 N/m deflect 1.15 m under the reference's mesh force: the run's dte
    starts at 2.3 m, 576 times the module, and the summary says the model does not hold
    there (it said nothing); the reference scene's 92 µm (2.3 % of the module) is small."""
    scene = reference_variant(tmp_path, "soft_bearings", *(
        (f"c_brg_{side} = 5e8", f"c_brg_{side} = 1e4")
        for side in ("pinion_left", "pinion_right", "wheel_left", "wheel_right")))
    for path, said in ((str(scene), True), ("reference", False)):
        assert main(["run", path, "--stop-time", "1e-3", "--no-progress",
                     "-o", str(tmp_path / "run.csv")]) == 0
        lines = capsys.readouterr().out.splitlines()
        assert any(line.startswith("The static deflection is not small: dte 2.304e+06 µm at "
                                   "the start, 576 times the normal module m_n = 4 mm")
                   for line in lines) is said


def test_a_chatter_where_no_point_is_on_the_face_says_so(tmp_path, capsys):
    """A face of 1 µm (K_ε = 0) chatters at 7.1 ms: the teeth meet again by impact at every
    entry, which the message now says beside the chatter's usual causes (it named low speed
    and a light pinion alone, and told to give an edge ramp)."""
    scene = reference_variant(tmp_path, "micron_face", ("b_left = 0.035", "b_left = 1e-6"),
                              ("b_right = 0.035", "b_right = 1e-6"))
    assert main(["run", str(scene), "--stop-time", "0.01", "--no-progress",
                 "-o", str(tmp_path / "run.csv")]) == 2
    error = one_error_line(capsys, "run")
    assert "the pinion chatters on a contact switch" in error
    assert error.rstrip().endswith(
        "Here no point is on the face for 100 % of each mesh period (K_eps = 0): the teeth meet "
        "again by impact at every entry, and a wider face keeps a point on it")


def test_a_command_whose_reader_has_gone_ends_quietly():
    """`herringbone scenes | head -2`: the reader closes the pipe before the list is written;
    the command ended with "herringbone scenes: [Errno 32] Broken pipe" and exit 2. It now
    ends quietly, as a Unix tool does, with 141 (128 + SIGPIPE, as a shell reports it)."""
    import subprocess
    import sys

    command = subprocess.Popen([sys.executable, "-m", "herringbone", "scenes"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    command.stdout.close()
    error = command.stderr.read()
    assert command.wait(timeout=60) == 141 and error == b""


def test_every_command_that_takes_a_scene_takes_no_progress(capsys):
    """A script passing --no-progress to each command got exit 2 from `info` and `campbell`,
    which show no bar: every command that takes a SCENE accepts it."""
    from herringbone.cli import parser

    _, commands = parser()
    taking = [name for name, command in commands.items()
              if any(action.dest == "scene" for action in command._actions)]
    assert {"run", "info", "stability", "sweep", "campbell", "build-fmu"} <= set(taking)
    for name in taking:
        assert "--no-progress" in commands[name]._option_string_actions, name
    assert main(["info", "reference", "--no-progress"]) == 0
    assert capsys.readouterr().out.startswith("Scene reference")


def test_a_changed_scenes_files_are_named_by_its_changes(tmp_path, monkeypatch, capsys):
    """`run reference --set w0_pinion=450` wrote results/reference.csv, replacing the scene's
    own run that a user meant to compare it with: its files carry its changes in their
    names, as build-fmu's FMUs do, and the scene's own are left as they were."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "reference.csv").write_text("the scene's own run\n")
    assert main(["run", "reference", "--set", "w0_pinion=450", "--stop-time", "0.002",
                 "--no-progress"]) == 0
    # a number in the short form that means it, as it was typed: 1e9, not 1000000000.0
    assert main(["campbell", "reference", "--set", "c_brg_pinion_left=1e9", "--speeds", "100",
                 "500", "5"]) == 0
    # and the scipy reference's run beside the compiled one's, which it is compared with
    assert main(["run", "reference", "--reference", "--stop-time", "0.002",
                 "--no-progress"]) == 0
    capsys.readouterr()
    assert (tmp_path / "results" / "reference.csv").read_text() == "the scene's own run\n"
    assert sorted(p.name for p in (tmp_path / "results").iterdir()) == [
        "reference+c_brg_pinion_left=1e9_campbell.png", "reference+w0_pinion=450.csv",
        "reference.csv", "reference_scipy.csv"]


def test_set_changes_a_parameter_or_torque_for_one_command(tmp_path, capsys, built_fmus):
    """--set NAME=VALUE runs the scene with a parameter or input torque changed, says so, and
    is checked as a scene file's value is (one line, exit 2, the setting named)."""
    csv = tmp_path / "at450.csv"
    assert main(["run", REFERENCE, "--set", "w0_pinion=450", "--set", "M_motor=250",
                 "--set", "M_load=900.0", "--stop-time", "0.002", "-o", str(csv),
                 "--no-progress"]) == 0
    said = capsys.readouterr().out
    assert said.startswith("scene reference with w0_pinion = 450 rad/s, M_motor = 250 N.m, "
                           "M_load = 900.0 N.m (--set)\n")
    import pandas as pd

    first = pd.read_csv(csv).iloc[0]
    assert first["w_pinion [rad/s]"] == pytest.approx(450.0, rel=1e-9)
    # the static mesh force follows the torque set: M_motor / Rp
    assert first["F_mesh [N]"] == pytest.approx(250.0 / 0.021705, rel=1e-3)
    for setting, expected in (
            ("zeta=1", "--set zeta=1: unknown parameter 'zeta'; did you mean 'zeta_mesh'?"),
            ("beta=5", "--set beta=5: beta is 5 rad; allowed: [0.01, 1.4] rad"),
            ("beta=abc", "--set 'beta=abc': the value 'abc' is not a number, true or false"),
            ("beta", "--set 'beta': allowed: NAME=VALUE"),
            ("bearings=false", "--set bearings=false: bearings is a component, not a "
                               "parameter; allowed: a scene file's [components] sets it")):
        assert main(["info", REFERENCE, "--set", setting]) == 2
        assert expected in one_error_line(capsys, "info")
    assert main(["build-fmu", REFERENCE, "--set", "max_step=1e-6"]) == 2
    assert ("--set max_step=1e-6: max_step is a solver setting of the FMU, not a parameter; "
            "allowed: a host sets it on the FMU") in one_error_line(capsys, "build-fmu")
    assert main(["run", REFERENCE, "--set", "solver_method=radau"]) == 2
    assert ("--set solver_method=radau: solver_method is a solver setting of the FMU, not a "
            "parameter; allowed: a host sets it on the FMU (`herringbone run` takes --tolerance "
            "and --method)") in one_error_line(capsys, "run")
    assert main(["run", REFERENCE, "--set", "tolerance=1e-9"]) == 2
    assert ("--set tolerance=1e-9: tolerance is the integrator's, not a parameter; allowed: "
            "--tolerance where the command takes it") in one_error_line(capsys, "run")
    assert main(["info", REFERENCE, "--set", "method=radau"]) == 2
    assert "--set method=radau: method is the integrator's" in one_error_line(capsys, "info")
    assert main(["run", REFERENCE, "--set", "stop_time=0.01"]) == 2
    assert ("--set stop_time: stop_time is of the scene's [experiment], not a parameter; "
            "allowed: --stop-time") in one_error_line(capsys, "run")
    assert main(["info", REFERENCE, "--set", 'M_motor="500"']) == 2
    assert '--set M_motor="500": M_motor must be a number' in one_error_line(capsys, "info")
    assert main(["sweep", REFERENCE, "--speeds", "100", "200", "2", "--method", "time",
                 "--through-fmu", str(built_fmus["reference"]), "--set", "zeta_mesh=0.2"]) == 2
    assert "--set with --through-fmu: the FMU runs the values it was built with" in \
        one_error_line(capsys, "sweep")
    assert main(["info", REFERENCE, "--set", "w0_pinion=450", "--set", "w0_pinion=300"]) == 2
    assert "--set w0_pinion is given 2 times; allowed: each name once" in \
        one_error_line(capsys, "info")
    assert main(["run", str(MODELS / "torque_step.toml"), "--set", "M_motor=100"]) == 2
    assert "the scene's torques are a table of 2 rows" in one_error_line(capsys, "run")


def test_stability_takes_set_as_the_other_commands_do(tmp_path, capsys):
    """`stability --set` charts the changed scene: the undamped mesh (zeta_mesh = 0) of the
    reference has bands the damped one has not."""
    chart = str(tmp_path / "chart.png")
    arguments = ["stability", REFERENCE, "--speeds", "100", "3000", "60", "-o", chart,
                 "--no-progress"]
    assert main(arguments) == 0
    damped = capsys.readouterr().out
    assert main(arguments + ["--set", "zeta_mesh=0", "--set", "h_shaft_in=0",
                             "--set", "h_shaft_out=0"]) == 0
    undamped = capsys.readouterr().out
    assert undamped.startswith("scene reference with zeta_mesh = 0, h_shaft_in = 0 N.m.s/rad, "
                               "h_shaft_out = 0 N.m.s/rad (--set)\n")
    assert "no unstable band" in damped and "unstable:" in undamped


def test_a_compiles_end_is_said_before_the_commands_last_line(monkeypatch, capsys):
    """A compile announced, done less than a second before the command stopped (the
    reference's small kernels, then Ctrl-C as the bar starts), had its end said at exit,
    after 'interrupted': the command says it first, and its own line stays last."""
    from herringbone.compiling import announce

    monkeypatch.setattr(announce, "finish", lambda: print("compiled", file=sys.stderr))
    assert main(["run", "no_such_scene"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "compiled" and lines[-1].startswith("herringbone run: ")


def test_a_scenes_torque_table_goes_beside_its_fmu_for_a_host(tmp_path, capsys, monkeypatch):
    """The FMU's inputs are the host's: torque_step's table, which --simulate plays, is not in
    the FMU, so build-fmu writes it as fmpy's input file and says so; fmpy's command line plays
    it as the API does with herringbone.scene_inputs. Built here without a C compiler, whose
    warning is one line."""
    from herringbone.fmu.run import simulate_scene_fmu

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    assert main(["build-fmu", "torque_step", "--no-progress"]) == 0
    said = capsys.readouterr().err.splitlines()
    assert [line for line in said if line.startswith(
        "herringbone build-fmu: warning: no C compiler ($CC or cc): the FMI 2.0 FMU keeps")]
    assert not [line for line in said if "Warning" in line or "warnings.warn" in line]
    fmu, table = Path("dist/torque_step-fmi2.fmu"), Path("dist/torque_step-fmi2-inputs.csv")
    assert (f"note: the scene's torque table is not part of the FMU, whose inputs start at its "
            f"first row (M_motor 500 N.m, M_load 1800 N.m) and hold where a host sets nothing; "
            f"{table} holds the table for a host: fmpy simulate {fmu} --input-file {table}"
            in said)
    assert np.loadtxt(table, delimiter=",", skiprows=1).tolist() == [
        [0.0, 500.0, 1800.0], [0.005, 500.0, 1800.0], [0.005, 5000.0, 18000.0],
        [0.02, 5000.0, 18000.0]]
    fmpy_command = Path(sys.executable).parent / "fmpy"
    subprocess.run([str(fmpy_command), "simulate", str(fmu), "--input-file", str(table),
                    "--output-file", "played.csv"], check=True, capture_output=True, timeout=300)
    played = np.genfromtxt("played.csv", delimiter=",", names=True)
    expected = simulate_scene_fmu(fmu, herringbone.load_scene("torque_step"))
    assert np.array_equal(played["time"], expected["time"])
    assert np.allclose(played["F_mesh"], expected["F_mesh"], rtol=1e-12, atol=0)
    assert played["F_mesh"].max() > 10 * played["F_mesh"][0]  # the step, ten times the torque
