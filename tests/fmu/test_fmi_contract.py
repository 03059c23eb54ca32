"""Issue 13: the FMU's contract with its hosts (FMI 2.0), point by point, through real hosts:
fmpy's FMU2Slave in this process (tests/helpers/fmu_host.py, logging on), `fmpy.simulate_fmu`
and the
`fmpy simulate` command line and libcosimpy in child processes, so that a crash or an abort
fails a test instead of the suite.

How errors reach the user (README, "Errors in each host"): a host that enabled logging gets the
message in its log and fmi2Discard; one that did not gets it on stderr and an fmi2Fatal, which
fmpy raises.
"""
import fnmatch
import io
import json
import math
import os
import pickle
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from helpers import FORCES, MODELS
from helpers.fmu_host import Instance

from herringbone.fmu import builder
from herringbone.integrate import first_start
from herringbone.model.parameters import INPUTS, PARAMETERS

WARNING, DISCARD, ERROR, FATAL = 1, 2, 3, 4  # fmi2Status
STEP = 1e-4
BIN = f"{sys.executable.rsplit('/', 1)[0]}"


@pytest.fixture(scope="module")
def fmu(scene_fmu):
    return scene_fmu("reference")


@pytest.fixture
def gear(fmu):
    instances = []

    def make(**arguments):
        instances.append(Instance(fmu, **arguments))
        return instances[-1]

    yield make
    for instance in instances:
        instance.free()


def errors(instance, *words):
    return [text for status, text in instance.messages
            if status == ERROR and all(word in text for word in words)]


def run_steps(instance, count, size=STEP):
    rows = []
    for _ in range(count):
        instance.step(size)
        rows.append(list(instance.get(list(FORCES)).values()))
    return np.array(rows)


# --- part 1: the contract -------------------------------------------------------------------

def test_a_run_from_a_start_time_is_the_run_from_zero_shifted(gear, fmu):
    from_zero = run_steps(gear(), 20)
    late = gear(start_time=1.0)
    from_one = run_steps(late, 20)
    assert late.messages == []
    # the same steps from another time origin: the times' rounding differs, nothing else
    assert np.abs(from_one - from_zero).max() < 1e-9 * np.abs(from_zero).max()
    result = fmpy.simulate_fmu(str(fmu), start_time=1.0, stop_time=1.002, output_interval=STEP)
    assert len(result) == 21 and result["time"][-1] == pytest.approx(1.002)
    assert np.abs(result["F_mesh"][1:] - from_zero[:, 0]).max() < 1e-9 * from_zero[0, 0]


@pytest.mark.parametrize("tolerance, start_values, used", [
    (1e-9, {}, 1e-9),  # the experiment's tolerance becomes solver_tolerance
    (1e-9, {"solver_tolerance": 1e-8}, 1e-8),  # unless the user set solver_tolerance
    (1.0, {}, 1e-2),  # clamped into solver_tolerance's range, with a warning
    (None, {}, 1e-7),  # no tolerance: the start value
])
def test_experiment_tolerance_maps_to_solver_tolerance(gear, tolerance, start_values, used):
    instance = gear(tolerance=tolerance, start_values=start_values)
    assert instance.get(["solver_tolerance"])["solver_tolerance"] == used
    warnings = [text for status, text in instance.messages if status == 1]  # fmi2Warning
    assert bool(warnings) == (tolerance == 1.0)
    assert all("tolerance 1" in text and "0.01" in text for text in warnings)


def test_a_fixed_parameter_set_after_initialization_is_refused(gear):
    untouched = run_steps(gear(), 5)
    instance = gear()
    instance.set(m_pinion=2.0)
    assert instance.get(["m_pinion"])["m_pinion"] == 0.929436
    (message,) = errors(instance, "m_pinion")
    assert "fixed parameter" in message and "before exitInitializationMode" in message
    assert np.array_equal(run_steps(instance, 5), untouched)  # it runs on, as it says


def test_outputs_wrong_types_and_unknown_references_are_answered_without_fatal(gear):
    instance = gear()
    refs = {name: v.valueReference for name, v in instance.variables.items()}
    instance.slave.setReal([refs["F_mesh"]], [5.0])
    assert errors(instance, "F_mesh is an output", "cannot be set")
    assert math.isnan(instance.slave.getReal([refs["n_contacts"]])[0])
    assert errors(instance, "n_contacts is an Integer", "fmi2GetInteger")
    assert instance.slave.getInteger([refs["F_mesh"]]) == [0]
    assert errors(instance, "F_mesh is a Real", "fmi2GetReal")
    assert math.isnan(instance.slave.getReal([100_000])[0])
    assert errors(instance, "value reference 100000")
    instance.slave.setReal([refs["internal_steps"]], [1.0])  # a local, through the wrong type
    assert errors(instance, "internal_steps is an Integer")
    assert not [text for status, text in instance.messages if status == FATAL]
    forces = run_steps(instance, 3)  # the instance lives on, unchanged
    assert np.array_equal(forces, run_steps(gear(), 3))


def test_an_input_discard_clears_once_the_input_is_valid_and_is_logged_once(gear):
    clean = run_steps(gear(), 6)
    instance = gear()  # the last one made: fmpy's logger proxy reports to it
    run_steps(instance, 2)
    instance.set(M_load=float("nan"))
    for _ in range(3):
        with pytest.raises(FMICallException) as error:
            instance.slave.doStep(instance.time, STEP)
        assert error.value.status == DISCARD
    assert len(errors(instance, "M_load", "finite")) == 1, instance.messages
    instance.set(M_load=1800.0)
    assert np.array_equal(run_steps(instance, 4), clean[2:])
    # a doStep from the wrong time is refused, once, and the right one goes on
    with pytest.raises(FMICallException):
        instance.slave.doStep(instance.time + 1.0, STEP)
    with pytest.raises(FMICallException):
        instance.slave.doStep(instance.time + 1.0, STEP)
    assert len(errors(instance, "FMU is at")) == 1
    instance.step(STEP)
    assert len(instance.messages) == 2


def test_a_torque_not_valid_at_initialization_holds_the_start_back_until_it_is(gear):
    """The start (the static deflection under M_motor) waits for a valid torque: a host that
    sets one after a refused doStep goes on from the start time as if it had set it first."""
    clean = run_steps(gear(), 4)
    instance = gear(start_values={"M_motor": float("nan")})
    assert np.isnan(list(instance.get(["F_mesh"]).values())).all()  # no start to show
    with pytest.raises(FMICallException) as error:
        instance.slave.doStep(instance.time, STEP)
    assert error.value.status == DISCARD
    (said,) = errors(instance, "input M_motor is nan; allowed: any finite number, in N.m")
    instance.set(M_motor=500.0)
    assert np.array_equal(run_steps(instance, 4), clean)
    assert len(instance.messages) == 1, instance.messages


@pytest.mark.parametrize("size", [math.nan, math.inf, -STEP, 0.0])
def test_a_step_size_that_is_not_finite_and_positive_is_refused_and_the_run_goes_on(gear, size):
    """As the Reference FMUs do: a doStep by a step size that is not > 0 is refused (FMI 2.0:
    Discard, pythonfmu has no Error) with one message naming it; the instance is unharmed."""
    clean = run_steps(gear(), 4)
    instance = gear()
    run_steps(instance, 2)
    for _ in range(2):
        with pytest.raises(FMICallException) as error:
            instance.slave.doStep(instance.time, size)
        assert error.value.status == DISCARD
    (message,) = [text for _, text in instance.messages]
    assert f"communicationStepSize is {size!r} s; allowed: finite and > 0 s" in message
    assert np.array_equal(run_steps(instance, 2), clean[2:])


@pytest.mark.parametrize("point", [math.nan, math.inf])
def test_a_communication_point_that_is_not_finite_is_refused_naming_it(gear, point):
    """A doStep from a currentCommunicationPoint that is not finite is refused with one
    message naming it (not the clock's resolution); the instance is unharmed."""
    clean = run_steps(gear(), 4)
    instance = gear()
    run_steps(instance, 2)
    with pytest.raises(FMICallException) as error:
        instance.slave.doStep(point, STEP)
    assert error.value.status == DISCARD
    (message,) = [text for _, text in instance.messages]
    assert f"currentCommunicationPoint is {point!r} s; allowed: finite" in message
    assert np.array_equal(run_steps(instance, 2), clean[2:])


def test_a_step_past_what_the_clock_resolves_is_refused_and_the_run_goes_on(gear):
    """A doStep of 1e300 s (it ran for ever) and an experiment started at 1e9 s (its times
    resolve 1.2e-7 s, a hundredth of the fastest mode's time scale) are refused with one
    message naming the time and the limit (5.4e7 s on the reference scene)."""
    clean = run_steps(gear(), 4)
    instance = gear()
    run_steps(instance, 2)
    with pytest.raises(FMICallException) as error:
        instance.slave.doStep(instance.time, 1e300)
    assert error.value.status == DISCARD
    (message,) = [text for _, text in instance.messages]
    assert "doStep to t = 1e+300 s" in message and "within 5.37e+07 s of t = 0" in message
    assert np.array_equal(run_steps(instance, 2), clean[2:])
    late = gear(start_time=1e9)
    with pytest.raises(FMICallException):
        late.step(STEP)
    assert errors(late, "doStep to t = 1e+09 s", "resolves 1.2e-07 s")


def test_a_max_step_whose_rounding_outweighs_its_steps_is_logged_as_a_warning(gear):
    instance = gear(start_values={"max_step": 1e-9})
    (said,) = [text for status, text in instance.messages if status == WARNING]
    assert said.startswith("gear: max_step 1e-09 s takes at least 1e+09 steps a simulated "
                           "second, and below 1e-07 s their rounding adds more error")
    run_steps(instance, 1, size=1e-6)  # it runs


def test_a_max_step_makes_its_steps_and_no_runaway(gear):
    """max_step = 1e-7 s forces 1e5 internal steps into a doStep of 1e-2 s, over the runaway
    bound of the train alone: they are allowed for, and the run agrees with the one without
    (the step bound only makes it more accurate). inf is no limit, as 0 is."""
    free, bounded = gear(), gear(start_values={"max_step": 1e-7})
    free.step(1e-2)
    bounded.step(1e-2)
    assert not bounded.messages, bounded.messages
    assert bounded.get(["internal_steps"])["internal_steps"] >= 1e5
    np.testing.assert_allclose(list(bounded.get(list(FORCES)).values()),
                               list(free.get(list(FORCES)).values()), rtol=1e-5)
    unbounded = gear(start_values={"max_step": math.inf})
    unbounded.step(1e-2)
    assert unbounded.get(list(FORCES)) == free.get(list(FORCES))


def test_calls_out_of_their_order_are_refused_with_a_message_and_harm_nothing(gear):
    """Each call where the Reference FMUs allow it, as the FMI 2.0 state machine has it: a
    doStep before initialization or after terminate is refused (Discard) with a message;
    exitInitializationMode without enter, enter, exit and setupExperiment again after
    initialization, a second terminate and a set after terminate are refused with a message
    (pythonfmu has no fmi2Error: answered OK), and the run goes on as if they had not been
    made, not started again, moved or changed."""
    clean = run_steps(gear(), 4)
    instance = gear(initialize=False)
    with pytest.raises(FMICallException) as error:
        instance.slave.doStep(instance.time, STEP)
    assert error.value.status == DISCARD
    instance.slave.exitInitializationMode()
    instance.slave.enterInitializationMode()
    with pytest.raises(FMICallException):
        instance.slave.doStep(instance.time, STEP)
    instance.slave.exitInitializationMode()
    run_steps(instance, 2)
    instance.slave.enterInitializationMode()
    instance.slave.exitInitializationMode()
    instance.slave.setupExperiment(startTime=5.0, tolerance=1e-3)
    assert np.array_equal(run_steps(instance, 2), clean[2:])
    instance.slave.terminate()
    instance.slave.terminate()
    instance.set(M_motor=600.0)
    with pytest.raises(FMICallException) as error:
        instance.step(STEP)
    assert error.value.status == DISCARD
    assert np.array_equal(list(instance.get(list(FORCES)).values()), clean[3])
    said = [text.split(": ", 1)[1] for status, text in instance.messages if status == ERROR]
    assert said == [
        "fmi2DoStep before fmi2EnterInitializationMode: refused; allowed: doStep once "
        "fmi2EnterInitializationMode and fmi2ExitInitializationMode have initialized the FMU, "
        "until fmi2Terminate",
        "fmi2ExitInitializationMode before fmi2EnterInitializationMode: refused; allowed: "
        "once, after fmi2EnterInitializationMode",
        "fmi2DoStep in initialization mode: refused; allowed: doStep once "
        "fmi2EnterInitializationMode and fmi2ExitInitializationMode have initialized the FMU, "
        "until fmi2Terminate",
        "fmi2EnterInitializationMode after the FMU was initialized: refused, the run goes on; "
        "allowed: once, before the first doStep (fmi2Reset starts again)",
        "fmi2ExitInitializationMode after the FMU was initialized: refused, the run goes on; "
        "allowed: once, after fmi2EnterInitializationMode",
        "fmi2SetupExperiment after the FMU was initialized: refused, the run goes on; "
        "allowed: once, before fmi2EnterInitializationMode",
        "fmi2Terminate after fmi2Terminate: refused; allowed: once, after "
        "fmi2ExitInitializationMode",
        "fmi2SetReal after fmi2Terminate: refused; allowed: before fmi2Terminate",
        "fmi2DoStep after fmi2Terminate: refused; allowed: doStep once "
        "fmi2EnterInitializationMode and fmi2ExitInitializationMode have initialized the FMU, "
        "until fmi2Terminate"]


def test_a_step_past_the_experiments_stop_time_is_refused(gear):
    """fmi2SetupExperiment's stop time: a doStep that would end past it is refused (Discard,
    where the Reference FMUs answer Error) with a message, one that ends on it to a master's
    rounding is taken."""
    instance = gear(stop_time=3 * STEP)
    run_steps(instance, 2)
    with pytest.raises(FMICallException) as error:
        instance.step(2 * STEP)
    assert error.value.status == DISCARD
    assert errors(instance, "ends past the experiment's stop time 0.0003 s "
                  "(fmi2SetupExperiment); allowed: doSteps that end by it")
    instance.slave.doStep(instance.time, STEP * (1 + 1e-9))


def test_outputs_read_in_initialization_mode_follow_what_the_host_set(gear):
    """The outputs are calculated initial unknowns: read in initialization mode they are
    those of the values set there (the train's start, docs/model.md section 6), as they read
    after exitInitializationMode, not those of the scene's start values."""
    instance = gear(initialize=False)
    assert list(instance.get(["F_mesh", "w_pinion"]).values()) == pytest.approx(
        [23036.42, 157.08], abs=0.01)
    instance.slave.enterInitializationMode()
    instance.set(M_motor=1000.0, M_load=3600.0, w0_pinion=100.0)
    during = instance.get(["F_mesh", "w_pinion", "w_load"])
    assert list(during.values()) == pytest.approx([2 * 23036.42, 100.0, 100.0 / 3.6], abs=0.01)
    instance.slave.exitInitializationMode()
    assert instance.get(["F_mesh", "w_pinion", "w_load"]) == during
    instance.step(STEP)
    assert np.isfinite(list(instance.get(list(FORCES)).values())).all()


@pytest.mark.parametrize("categories, heard_in", [
    (["logAll"], "logAll"),
    (["logStatusError"], "logStatusError"),
    (["logStatusWarning", "logAll"], "logAll"),
    ([], "logStatusError"),
    (["logStatusWarning", "logStatusDiscard"], None),
])
def test_a_host_that_names_log_categories_hears_a_problem_or_gets_it_on_stderr(
        gear, capfd, categories, heard_in):
    """fmi2SetDebugLogging with categories: pythonfmu passes a message only in a category the
    host named. One that names logAll (declared as every message) or logStatusError hears an
    input problem and gets fmi2Discard; one that names neither does not hear it, and gets it
    on stderr and an fmi2Fatal, as a host with logging off (the message was lost before)."""
    instance = gear(categories=categories)
    run_steps(instance, 1)
    instance.set(M_motor=math.nan)
    with pytest.raises(FMICallException) as error:
        instance.step(STEP)
    said = "gear: input M_motor is nan; allowed: any finite number"
    heard = [category for (status, text), category
             in zip(instance.messages, instance.categories) if said in text]
    if heard_in is None:
        assert error.value.status == FATAL and heard == []
        assert f"gear: error: {said[len('gear: '):]}" in capfd.readouterr().err
    else:
        assert error.value.status == DISCARD and heard == [heard_in]
        assert "M_motor" not in capfd.readouterr().err


def _serialize(instance):
    state = instance.slave.getFMUstate()
    data = instance.slave.serializeFMUstate(state)
    instance.slave.freeFMUstate(state)
    return bytes(data)


def _restore(instance, data):
    state = instance.slave.deSerializeFMUstate(data)
    instance.slave.setFMUstate(state)
    instance.slave.freeFMUstate(state)


def test_serialized_state_restores_every_bit_also_in_a_new_instance(gear, fmu):
    assert fmpy.read_model_description(str(fmu)).coSimulation.canSerializeFMUstate
    instance = gear()
    run_steps(instance, 30)
    saved_time, data = instance.time, _serialize(instance)
    assert _serialize(instance) == data  # a stable format: the same state, the same bytes
    after = run_steps(instance, 30)
    steps = instance.get(["internal_steps"])["internal_steps"]
    assert steps > 0
    for target in (instance, gear()):
        _restore(target, data)
        target.time = saved_time
        assert np.array_equal(run_steps(target, 30), after)
        assert target.get(["internal_steps"])["internal_steps"] == steps


@pytest.mark.parametrize("change", ["values", "run", "run.cycle"])
def test_a_state_not_of_this_fmus_layout_is_refused_with_a_message_not_a_fatal(gear, change):
    """A serialized state with the format's name but a part missing (or, inside the run, a
    contact set that is not one) is refused or fails with a message, not a Python exception
    (which pythonfmu makes Fatal); where it was refused, the instance goes on unharmed."""
    clean = run_steps(gear(), 4)
    instance = gear()
    run_steps(instance, 2)
    state = json.loads(_serialize(instance))
    if change == "run.cycle":
        state["run"]["cycle"] = "no such cycle"
    else:
        del state[change]
    _restore(instance, json.dumps(state).encode())
    (message,) = [text for status, text in instance.messages]
    assert "fmi2SetFMUstate" in message
    if change == "run.cycle":  # the values were taken: the instance stops with the message
        with pytest.raises(FMICallException):
            instance.step(STEP)
    else:
        assert "not one of this FMU" in message
        assert np.array_equal(run_steps(instance, 2), clean[2:])


def test_internal_steps_stays_at_the_most_an_integer_holds(gear):
    """A count past 2^31 − 1 (a long stiff run) reads that, not a negative wrapped one."""
    instance = gear()
    run_steps(instance, 1)
    state = json.loads(_serialize(instance))
    for count, read in ((2**31 - 10, 2**31 - 10), (2**31 + 5, 2**31 - 1), (2**32 + 5, 2**31 - 1)):
        state["run"]["internal_steps"] = count
        _restore(instance, json.dumps(state).encode())
        assert instance.get(["internal_steps"])["internal_steps"] == read


FOREIGN_STATE = b'{"not": "a state of this FMU"}'


def test_a_foreign_state_raises_where_the_host_hears_no_log(fmu, tmp_path):
    """fmpy's FMU2Slave without logging: a refused state is an exception (fmi2Fatal), not an
    fmi2OK a master would take for a rollback; the instance keeps its own and goes on."""
    program = f"""
import sys, fmpy
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
d = fmpy.read_model_description(sys.argv[1])
s = FMU2Slave(guid=d.guid, unzipDirectory=fmpy.extract(sys.argv[1]),
              modelIdentifier=d.coSimulation.modelIdentifier, instanceName="gear")
s.instantiate(); s.setupExperiment(startTime=0.0); s.enterInitializationMode()
s.exitInitializationMode(); s.doStep(0.0, {STEP!r})
try:
    s.setFMUstate(s.deSerializeFMUstate({FOREIGN_STATE!r}))
    print("RESULT taken")
except FMICallException as error:
    print("RESULT raised", error.status)
s.doStep({STEP!r}, {STEP!r})
print("RESULT stepped")
"""
    run = _child([sys.executable, "-c", program, str(fmu)], tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    results = [line for line in run.stdout.splitlines() if line.startswith("RESULT ")]
    assert results == ["RESULT raised 4", "RESULT stepped"], run.stdout
    assert "fmi2SetFMUstate: the state is not one of this FMU" in run.stderr


def test_a_state_restores_every_bit_in_an_instance_started_with_other_torques(gear):
    # the stepper's tolerances and modal forms are taken in the static scales of the torques
    # it was built with: the restoring instance builds it again with the saved run's
    instance = gear(start_values={"M_motor": 600.0, "M_load": 2160.0})
    run_steps(instance, 30)
    saved_time, data = instance.time, _serialize(instance)
    after = run_steps(instance, 30)
    for target in (gear(), gear(start_values={"M_motor": 600.0, "M_load": 2160.0})):
        _restore(target, data)
        target.time = saved_time
        assert np.array_equal(run_steps(target, 30), after)


@pytest.mark.parametrize("values", [{"phase0": 0.3}, {"M_motor": 800.0, "M_load": 2880.0},
                                    {"stagger": 0.5}])
def test_a_state_taken_in_initialization_mode_keeps_the_values_set_before_it(gear, values):
    """A state taken in initialization mode right after a set (no output read between) goes
    back to those values and their run: after a step and the restore, the run is the one
    without the round trip, to the bit (the state had kept the run of the values before the
    set, and a staggered mesh, with more streams of points, failed to restore)."""
    plain = gear(start_values=values)
    expected = run_steps(plain, 3)
    instance = gear(initialize=False)
    instance.slave.enterInitializationMode()
    instance.set(**values)
    state = instance.slave.getFMUstate()
    instance.slave.exitInitializationMode()
    run_steps(instance, 1)
    instance.slave.setFMUstate(state)
    instance.slave.freeFMUstate(state)
    instance.time = 0.0
    instance.slave.exitInitializationMode()
    assert np.array_equal(run_steps(instance, 3), expected)
    assert errors(instance) == []


def test_model_description_ranges_and_dependencies(fmu):
    root = ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))
    declared = {v.get("name"): v[0] for v in root.iter("ScalarVariable")}
    for name, parameter in {**PARAMETERS, **INPUTS}.items():
        if name not in declared or parameter.kind is bool:
            continue
        for attribute, bound in (("min", parameter.allowed.low), ("max", parameter.allowed.high)):
            text = declared[name].get(attribute)
            assert (text is None) == (bound is None), (name, attribute)
            if bound is not None:
                assert float(text) == bound, (name, attribute)
    assert declared["solver_tolerance"].get("min") == "1e-12"
    outputs = root.find("ModelStructure/Outputs")
    assert len(outputs) > 10 and all(u.get("dependencies") == "" for u in outputs)


CARRIED_CACHE = f"resources/{first_start.CARRIED_FOLDER}/"


def test_two_builds_of_a_scene_are_the_same_fmu(tmp_path):
    # this process has loaded other scenes' code (the stepper of another method) in between:
    # the FMU carries what a run of its scene loads, taken in a fresh process
    first = builder.build_gear_fmu(MODELS / "reference.toml", tmp_path / "first.fmu")
    other = builder.build_gear_fmu(MODELS / "staggered.toml", tmp_path / "other.fmu")
    again = builder.build_gear_fmu(MODELS / "reference.toml", tmp_path / "again.fmu")
    # the compile times recorded beside the code move when anything compiles meanwhile
    record = CARRIED_CACHE + "*/" + first_start.RECORD
    with zipfile.ZipFile(first) as a, zipfile.ZipFile(again) as b:
        entries = [{name: archive.read(name) for name in archive.namelist()
                    if not fnmatch.fnmatch(name, record)} for archive in (a, b)]
    assert entries[0] == entries[1]
    guid = fmpy.read_model_description(str(first)).guid
    assert guid == fmpy.read_model_description(str(again)).guid
    assert fmpy.read_model_description(str(other)).guid != guid


def carried_kernels(fmu):
    """{kernel: the data files its carried index names} of an FMU's carried compiled code,
    and the data files it carries."""
    entries = [name for name in zipfile.ZipFile(fmu).namelist() if name.startswith(CARRIED_CACHE)]
    kernels = {}
    with zipfile.ZipFile(fmu) as archive:
        for name in entries:
            if name.endswith(".nbi"):
                index = io.BytesIO(archive.read(name))
                pickle.load(index)  # numba's version
                stamp, overloads = pickle.loads(index.read())
                kernels[Path(name).name.split("-")[0]] = sorted(overloads.values())
    return kernels, sorted(Path(name).name for name in entries if name.endswith(".nbc"))


def test_an_fmu_carries_the_code_of_the_kernels_its_run_calls_and_no_more(built_fmus):
    """The loop's code holds what it calls (the events, the steps, the equations), so the FMU
    carries the kernels called from Python, one entry each: the loop for its scene's method
    (the exponential method's for the reference scene, DOP853's for staggered) and the
    equations the model reads its outputs and contact geometry with; none of the analysis'
    (variational), none of the loop's callees. Whether that is enough:
    test_first_start.test_a_built_fmu_starts_on_an_empty_cache_without_compiling."""
    loops = set()
    for scene in ("reference", "staggered"):
        kernels, data = carried_kernels(built_fmus[scene])
        assert set(kernels) == {"walk.advance", "equations.outputs", "equations.approaches",
                                "equations.point_geometry"}
        assert all(len(files) == 1 for files in kernels.values())
        assert sorted(file for files in kernels.values() for file in files) == data
        loops.add(kernels["walk.advance"][0])
    assert len(loops) == 2  # each scene's own method


def _guid_after(fmu, tmp_path, name, data):
    """The GUID fix_model_description gives a copy of `fmu` with entry `name` set to `data`."""
    copy = tmp_path / f"{len(list(tmp_path.iterdir()))}.fmu"
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(copy, "w") as target:
        for entry in source.namelist():
            if entry != name:
                target.writestr(entry, source.read(entry))
        target.writestr(name, data)
    builder.fix_model_description(copy, no_feedthrough=True)
    return fmpy.read_model_description(str(copy)).guid


def test_the_guid_follows_the_model_not_the_carried_compiled_code(fmu, tmp_path):
    guid = fmpy.read_model_description(str(fmu)).guid
    assert _guid_after(fmu, tmp_path, "resources/scene.toml",
                       zipfile.ZipFile(fmu).read("resources/scene.toml")) == guid
    assert _guid_after(fmu, tmp_path, CARRIED_CACHE + "kernels-0/other.kernel-1.py311.nbi",
                       b"another variant") == guid
    assert _guid_after(fmu, tmp_path, "resources/scene.toml", b"# another scene\n") != guid
    assert _guid_after(fmu, tmp_path, "resources/herringbone/extra.py", b"") != guid


def test_a_runaway_stops_quickly_with_a_message_naming_the_torques(gear):
    instance = gear(start_values={"M_motor": 1e12})
    started = time.perf_counter()
    with pytest.raises(FMICallException) as error:
        for _ in range(10):
            instance.step(STEP)
    assert error.value.status == DISCARD
    assert time.perf_counter() - started < 5.0
    (message,) = errors(instance, "runs away")
    assert "M_motor = 1e+12 N.m" in message and "M_load" in message and "internal steps" in message


# --- part 2: errors reach the user in every host with its defaults -----------------------------

FMPY_API = """
import sys, fmpy
try:
    fmpy.simulate_fmu(sys.argv[1], stop_time=1e-3, output_interval=1e-4,
                      start_values={sys.argv[2]: float(sys.argv[3])})
except fmpy.fmi1.FMICallException as error:
    print("RAISED", error)
"""

LIBCOSIM = """
import json, sys, fmpy
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
refs = {v.name: v.valueReference for v in fmpy.read_model_description(sys.argv[1]).modelVariables}
execution = CosimExecution.from_step_size(step_size=100_000)
gear = execution.add_local_slave(CosimLocalSlave(fmu_path=sys.argv[1], instance_name="gear"))
execution.real_initial_value(gear, refs[sys.argv[2]], float(sys.argv[3]))
last = CosimObserver.create_last_value()
execution.add_observer(observer=last)
completed = execution.simulate_until(target_time=1_000_000)
print("RESULT", json.dumps({"completed": completed, "time": execution.status().current_time}))
"""


def _child(arguments, tmp_path):
    return subprocess.run(arguments, capture_output=True, text=True, cwd=tmp_path, timeout=300,
                          env={**os.environ, "TMPDIR": str(tmp_path)})


def test_fmpy_api_with_defaults_raises_and_prints_the_message(fmu, tmp_path):
    run = _child([sys.executable, "-c", FMPY_API, str(fmu), "m_pinion", "-1"], tmp_path)
    assert run.returncode == 0, run.stderr
    assert "RAISED fmi2ExitInitializationMode failed with status 4" in run.stdout
    assert ("HerringboneGear: error: parameter m_pinion is -1.0 kg; allowed: [1e-09, 1e+07] kg"
            in run.stderr)


def test_fmpy_command_line_fails_with_the_message(fmu, tmp_path):
    run = _child([f"{BIN}/fmpy", "simulate", str(fmu), "--stop-time", "1e-3",
                  "--start-values", "m_pinion", "-1"], tmp_path)
    assert run.returncode == 1
    first_line = run.stderr.splitlines()[0]
    assert first_line == ("HerringboneGear: error: parameter m_pinion is -1.0 kg; allowed: "
                          "[1e-09, 1e+07] kg")


def test_fmpy_with_logging_on_gets_the_message_in_its_log_only(fmu, tmp_path):
    code = ("import sys, fmpy\nr = fmpy.simulate_fmu(sys.argv[1], stop_time=1e-3, "
            "output_interval=1e-4, start_values={'m_pinion': -1.0}, debug_logging=True, "
            "logger=lambda *a: print('LOG', a[-1].decode()))\n"
            "print('ROWS', len(r), r['F_mesh'][0])\n")
    run = _child([sys.executable, "-c", code, str(fmu)], tmp_path)
    assert run.returncode == 0 and "m_pinion" not in run.stderr
    assert ("LOG HerringboneGear: parameter m_pinion is -1.0 kg; allowed: [1e-09, 1e+07] kg"
            in run.stdout)
    assert "ROWS 2 nan" in run.stdout  # no plausible-looking outputs of a train never started


@pytest.mark.parametrize("variable, value, completed, words", [
    ("m_pinion", -1.0, False, ("m_pinion is -1.0 kg; allowed: [1e-09, 1e+07] kg",)),
    ("M_load", float("nan"), False, ("M_load is nan; allowed: any finite number, in N.m",)),
    ("F_mesh", 5.0, True, ("F_mesh is an output: it cannot be set",)),
])
def test_libcosim_shows_the_message_and_lives(fmu, tmp_path, variable, value, completed, words):
    run = _child([sys.executable, "-c", LIBCOSIM, str(fmu), variable, repr(value)], tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    (line,) = [line for line in run.stdout.splitlines() if line.startswith("RESULT ")]
    assert json.loads(line[len("RESULT "):])["completed"] is completed
    shown = [line for line in run.stderr.splitlines() + run.stdout.splitlines()
             if "[error]" in line and "gear:" in line]
    assert shown and all(word in shown[0] for word in words), shown
