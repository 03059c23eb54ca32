"""Co-simulation of the gear FMU with the example drive-train FMUs (docs/model.md sections 1,
5, 7, 11).

The induction motor (examples/induction_motor.py, Kloss curve) drives the reference gear train
and the fan (examples/fan_load.py, M = k_fan·w·|w|) loads it: `w_motor` → motor → `M_motor`,
`w_load` → fan → `M_load`.  In steady running the gear is a lossless ratio u = z_wheel/z_pinion
(docs/model.md section 5: M_load = u·M_motor, w_load = w_motor/u), so the train settles where
the motor curve meets the fan curve seen through the gear:

    Kloss(w) = k_fan·(w/u)²/u.

Both hosts must bring the train there from its own start (w0_pinion = 157.08 rad/s with the
static deflection of M_motor = 500 N·m, 0.7 % and 1.5 % off the operating point): (i) a master
loop written on fmpy's FMU2Slave, (ii) libcosimpy (the Open Simulation Platform's libcosim).

Each host runs in a fresh interpreter.  The pytest process has imported `herringbone` (conftest),
and a module already in sys.modules wins over the FMU's packaged copy, so only a fresh process
tests the FMU as shipped; it also keeps a crash of a host (libcosim aborts on a slave's fatal
error) from taking pytest down.  The child imports this file for the host functions below; this
file itself must therefore never import herringbone.
"""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from helpers import ROOT

TESTS_DIR = Path(__file__).resolve().parent
SOURCE_PACKAGE = ROOT / "fmu_src" / "herringbone"
sys.path.insert(0, str(ROOT / "examples"))
from drivetrain_operating_point import operating_point  # noqa: E402  (scipy only)

# Communication step.  The coupling is explicit (the gear integrates with the motor torque held
# over a step), and near the operating point the Kloss curve acts on the motor inertia like a
# damper of slope |dM/dw| ≈ 2·M_k/(s_k·w_sync) ≈ 125 N·m·s/rad (115 exactly at the operating
# point).  Explicit (forward-Euler-like) handling of a damper c on an inertia I is stable only
# for h·c/I < 2: with I_motor = 0.05 kg·m², h = 1e-4 s gives 0.23.  (Measured with the fmpy
# loop: h = 5e-4 s, ratio 1.15, still settles; h = 1e-3 s, ratio 2.3, makes w_motor jump
# between 148 and 162 rad/s from step to step.)
STEP = 1e-4
STEP_NS = round(STEP * 1e9)  # libcosim counts time in integer nanoseconds
# The rigid-body transient (time constant ≈ I_reduced/slope ≈ 0.09/121 s < 1 ms) and the 113 Hz
# torsional mode it excites have died out to below 1e-5 of the speeds after about 0.05 s
# (measured); 0.1 s leaves two judging windows of settled running after that.
STOP_TIME = 0.1
# The mesh makes the speeds ripple at the mesh frequency z_pinion·w/2π ≈ 248 Hz (peak to peak
# 0.1 rad/s on w_motor, 0.016 rad/s on w_load, 11 N·m on M_motor, 1.3 N·m on M_load), so values
# are judged as means over whole mesh periods; five periods ≈ 20 ms.
WINDOW_MESH_PERIODS = 5

# Tolerances, relative to the intersection of the two curves.  What separates the window means
# from it: ripple left over because a window is whole samples, not exactly five periods (201
# samples for 201.45); the power the gear's dampers take from the mesh ripple (the lossless
# ratio holds exactly only for a rigid rotation); what is left of the transient; the coupling's
# hold of the inputs over a step.  Measured, both hosts: below 1e-6 (speeds) and 5e-6 (torques).
# Speeds: 1e-4 (0.016 rad/s on the motor), a hundred times that, yet a gear losing 1 % of the
# torque (M_load = 0.99·u·M_motor) would move the speeds by 2.6e-4, M_motor by 1 % and M_load
# by 5e-4 and fail every check.  Torques follow from the speeds through the curves, so their
# tolerances are the speed tolerance times the curve's elasticity d(ln M)/d(ln w) at the
# operating point: ≈ 36 for the steep Kloss curve near synchronous speed, 2 for the fan.
SPEED_TOLERANCE = 1e-4
MOTOR_TORQUE_TOLERANCE = 36 * SPEED_TOLERANCE
LOAD_TORQUE_TOLERANCE = 2 * SPEED_TOLERANCE
# Settled: the mean of the last window differs from the mean of the window before by a tenth of
# the accuracy tolerance at most (measured in settled running: at most a quarter of that, from
# a slow beat of the window means of about 2e-6 relative).
DRIFT_FRACTION = 0.1

SIGNALS = ("w_motor", "w_load", "M_motor", "M_load")
TOLERANCES = {"w_motor": SPEED_TOLERANCE, "w_load": SPEED_TOLERANCE,
              "M_motor": MOTOR_TORQUE_TOLERANCE, "M_load": LOAD_TORQUE_TOLERANCE}
# Which FMU produces each signal; the gear's outputs are read by the name in docs/model.md
# section 7.
SOURCE_OF_SIGNAL = {"w_motor": "gear", "w_load": "gear", "M_motor": "motor", "M_load": "fan"}
# The connections: (from FMU, output) → (to FMU, input).
CONNECTIONS = (
    (("gear", "w_motor"), ("motor", "w_motor")),
    (("gear", "w_load"), ("fan", "w_load")),
    (("motor", "M_motor"), ("gear", "M_motor")),
    (("fan", "M_load"), ("gear", "M_load")),
)


# --- the expected operating point -------------------------------------------------------------

def start_values(fmu_path):
    """The numeric start values of an FMU's variables, by name, as its model description says."""
    return {v.name: float(v.start) for v in read_model_description(str(fmu_path)).modelVariables
            if v.start is not None and v.type in ("Real", "Integer")}


def expected_operating_point(fmus):
    """Where Kloss(w) = M_fan(w/u)/u on the motor's stable branch, with the FMUs' defaults
    (examples/drivetrain_operating_point.py)."""
    motor = start_values(fmus["motor"])
    fan = start_values(fmus["fan"])
    gear = start_values(fmus["reference"])
    point = operating_point(motor["M_breakdown"], motor["s_breakdown"], motor["w_sync"],
                            fan["k_fan"], gear["z_pinion"], gear["z_wheel"])
    return {**point, "w0_pinion": gear["w0_pinion"]}


# --- the two hosts (run in a child interpreter, see the module docstring) ---------------------

def value_references(fmu_path):
    """The value reference of every variable of an FMU, by name."""
    return {v.name: v.valueReference for v in read_model_description(str(fmu_path)).modelVariables}


def packaged_herringbone():
    """Where the `herringbone` the gear FMU imported came from (None if not imported)."""
    module = sys.modules.get("herringbone")
    return None if module is None else str(Path(module.__file__).resolve())


def run_fmpy_master(fmu_paths, stop_time, step):
    """Co-simulate with a master loop on fmpy's FMU2Slave; every signal at every communication
    point t = 0, h, …, stop_time.

    At each point the gear's speeds go to the motor and the fan, whose torques (direct
    feedthrough of those speeds) go back to the gear; then all three step from t to t + h.
    """
    from fmpy.fmi2 import FMU2Slave

    refs = {name: value_references(path) for name, path in fmu_paths.items()}
    unzipped, slaves = [], {}
    try:
        for name, path in fmu_paths.items():
            description = read_model_description(path)
            unzipped.append(extract(path))
            slave = FMU2Slave(guid=description.guid, unzipDirectory=unzipped[-1],
                              modelIdentifier=description.coSimulation.modelIdentifier,
                              instanceName=name)
            slave.instantiate()
            slaves[name] = slave
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.exitInitializationMode()

        def read(fmu, variable):
            return slaves[fmu].getReal([refs[fmu][variable]])[0]

        samples = {"time": [], **{signal: [] for signal in SIGNALS}}
        n_steps = round(stop_time / step)
        for k in range(n_steps + 1):
            for (source, output), (target, input_) in CONNECTIONS:
                slaves[target].setReal([refs[target][input_]], [read(source, output)])
            samples["time"].append(k * step)
            for signal in SIGNALS:
                samples[signal].append(read(SOURCE_OF_SIGNAL[signal], signal))
            if k < n_steps:
                for slave in slaves.values():
                    slave.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
        return {"samples": samples, "herringbone": packaged_herringbone()}
    finally:
        for slave in slaves.values():
            slave.terminate()
            slave.freeInstance()
        for folder in unzipped:
            shutil.rmtree(folder, ignore_errors=True)


def run_libcosim(fmu_paths, stop_time, step_ns):
    """Co-simulate with libcosim's fixed-step algorithm; every signal after every step."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.WARNING)  # libcosim logs to stderr; stdout carries the JSON
    refs = {name: value_references(path) for name, path in fmu_paths.items()}
    execution = CosimExecution.from_step_size(step_size=step_ns)
    index = {name: execution.add_local_slave(CosimLocalSlave(fmu_path=str(path),
                                                             instance_name=name))
             for name, path in fmu_paths.items()}
    for (source, output), (target, input_) in CONNECTIONS:
        status = execution.connect_real_variables(index[source], refs[source][output],
                                                  index[target], refs[target][input_])
        assert status == 0, f"connecting {source}.{output} to {target}.{input_}: {status}"
    n_steps = round(stop_time * 1e9 / step_ns)
    series = CosimObserver.create_time_series(buffer_size=n_steps + 10)
    execution.add_observer(observer=series)
    last = CosimObserver.create_last_value()
    execution.add_observer(observer=last)
    for signal in SIGNALS:
        fmu = SOURCE_OF_SIGNAL[signal]
        series.start_time_series(index[fmu], refs[fmu][signal], CosimVariableType.REAL)

    completed = execution.simulate_until(target_time=n_steps * step_ns)
    samples, final = {}, {}
    for signal in SIGNALS:
        fmu = SOURCE_OF_SIGNAL[signal]
        # step numbers start at 1 after the initial sample; ask from step 1 for all n_steps
        times_ns, _, values = series.time_series_real_samples(
            index[fmu], refs[fmu][signal], from_step=1, sample_count=n_steps)
        samples["time"] = [t / 1e9 for t in times_ns]
        samples[signal] = values
        final[signal] = last.last_real_values(index[fmu], [refs[fmu][signal]])[0]
    return {"completed": completed, "end_time": execution.status().current_time / 1e9,
            "samples": samples, "final": final, "herringbone": packaged_herringbone()}


def assert_ran_packaged_copy(result):
    """The gear FMU imported the herringbone it carries (…/resources/herringbone), not the
    source tree."""
    assert result["herringbone"] is not None
    module_file = Path(result["herringbone"])
    assert module_file.parts[-3:] == ("resources", "herringbone", "__init__.py"), module_file
    assert not module_file.is_relative_to(SOURCE_PACKAGE)


def run_in_child(host, fmus, folder, **arguments):
    """Run `host` (a function name of this file) in a fresh interpreter working in `folder`;
    return its result."""
    fmu_paths = {name: str(fmus[name]) for name in ("reference", "motor", "fan")}
    fmu_paths["gear"] = fmu_paths.pop("reference")
    code = ("import json, sys\n"
            f"sys.path[:0] = [{str(TESTS_DIR)!r}, {str(TESTS_DIR.parent)!r}]\n"
            "import test_cosimulation as this\n"
            f"result = this.{host}(json.loads(sys.argv[1]), **json.loads(sys.argv[2]))\n"
            "print('\\nRESULT ' + json.dumps(result))\n")
    # TMPDIR: the hosts unpack the FMUs into temporary folders; in `folder` a crashed child
    # leaves nothing behind
    run = subprocess.run([sys.executable, "-c", code, json.dumps(fmu_paths),
                          json.dumps(arguments)], cwd=folder,
                         env={**os.environ, "TMPDIR": str(folder)}, capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, f"{host} exited with {run.returncode}:\n{run.stderr[-3000:]}"
    result_lines = [line for line in run.stdout.splitlines() if line.startswith("RESULT ")]
    assert result_lines, f"{host} printed no result:\n{run.stdout[-3000:]}\n{run.stderr[-3000:]}"
    result = json.loads(result_lines[-1][len("RESULT "):])
    result["samples"] = {name: np.array(values) for name, values in result["samples"].items()}
    return result


# --- judging a run ----------------------------------------------------------------------------

def window_means(samples, expected, step):
    """Means of every signal over the last whole mesh periods and over the ones before them."""
    size = round(WINDOW_MESH_PERIODS * expected["mesh_period"] / step)
    assert len(samples["time"]) >= 3 * size, "run too short for two judging windows"
    last = {s: samples[s][-size:].mean() for s in SIGNALS}
    before = {s: samples[s][-2 * size:-size].mean() for s in SIGNALS}
    return last, before


def check_settles_at_operating_point(samples, expected, step):
    """The run starts visibly off the operating point, ends on it, and no longer drifts."""
    # By itself: the gear starts at w0_pinion (the fmpy loop's first sample is exactly that,
    # libcosim's is one step later), 7e-3 off, far outside the tolerance.
    assert abs(samples["w_motor"][0] / expected["w_motor"] - 1) > 20 * SPEED_TOLERANCE
    last, before = window_means(samples, expected, step)
    for signal in SIGNALS:
        assert last[signal] == pytest.approx(expected[signal], rel=TOLERANCES[signal]), signal
        assert last[signal] == pytest.approx(before[signal],
                                             rel=DRIFT_FRACTION * TOLERANCES[signal]), signal


# --- tests ------------------------------------------------------------------------------------

def test_operating_point_is_the_intersection_of_the_curves(built_fmus):
    """The expected point: on the motor's stable branch, torques in gear ratio, and near the
    design point the examples document (500 N·m at about 155.9 rad/s)."""
    expected = expected_operating_point(built_fmus)
    ratio = expected["w_motor"] / expected["w_load"]
    assert ratio == pytest.approx(3.6, rel=1e-12)
    assert expected["M_load"] == pytest.approx(ratio * expected["M_motor"], rel=1e-10)
    slip = 1 - expected["w_motor"] / start_values(built_fmus["motor"])["w_sync"]
    assert 0 < slip < start_values(built_fmus["motor"])["s_breakdown"]
    assert expected["w_motor"] == pytest.approx(155.9, abs=0.1)
    assert expected["M_motor"] == pytest.approx(500.0, rel=0.02)


def test_fmpy_master_loop_settles_at_operating_point(built_fmus, tmp_path):
    """fmpy master loop, h = 1e-4 s, 0.1 s: the mesh-period means of w_motor, w_load, M_motor,
    M_load equal the intersection of the Kloss and fan curves through the gear ratio."""
    expected = expected_operating_point(built_fmus)
    result = run_in_child("run_fmpy_master", built_fmus, tmp_path, stop_time=STOP_TIME,
                          step=STEP)
    samples = result["samples"]
    assert samples["time"][-1] == pytest.approx(STOP_TIME, rel=1e-12)
    assert samples["w_motor"][0] == pytest.approx(expected["w0_pinion"], rel=1e-12)
    assert_ran_packaged_copy(result)
    check_settles_at_operating_point(samples, expected, STEP)


def test_libcosim_settles_at_operating_point(built_fmus, tmp_path):
    """libcosim (libcosimpy) fixed-step co-simulation, h = 1e-4 s, 0.1 s: same operating point
    as the fmpy loop, i.e. the intersection of the two curves through the gear ratio."""
    expected = expected_operating_point(built_fmus)
    result = run_in_child("run_libcosim", built_fmus, tmp_path, stop_time=STOP_TIME,
                          step_ns=STEP_NS)
    assert result["completed"]
    assert result["end_time"] == pytest.approx(STOP_TIME, rel=1e-12)
    samples = result["samples"]
    assert len(samples["time"]) == round(STOP_TIME / STEP)
    assert samples["time"][-1] == pytest.approx(STOP_TIME, rel=1e-12)
    for signal in SIGNALS:  # the last-value observer agrees with the series' last sample
        assert result["final"][signal] == samples[signal][-1]
    assert_ran_packaged_copy(result)
    check_settles_at_operating_point(samples, expected, STEP)


@pytest.mark.parametrize("example, value, said", [
    ("fan", {"k_fan": -1.0}, "fan: need k_fan >= 0; got -1.0"),
    ("motor", {"M_breakdown": -1.0}, "motor: need M_breakdown > 0, 0 < s_breakdown <= 1"),
])
def test_the_example_fmus_name_their_instance_in_their_messages(built_fmus, example, value,
                                                                said):
    """As the gear FMU does: a host with several instances of a model reads which one the
    message is about (they named their model, FanLoad, InductionMotor)."""
    from fmpy.fmi1 import FMICallException
    from helpers.fmu_host import Instance

    instance = Instance(built_fmus[example], name=example, start_values=value)
    try:
        with pytest.raises(FMICallException):
            instance.step(1e-3)
        assert any(text.startswith(said) for _, text in instance.messages), instance.messages
    finally:
        instance.free()
