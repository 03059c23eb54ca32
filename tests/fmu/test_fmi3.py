"""Issue 18 part 1: the FMI 3.0 co-simulation FMU (pythonfmu3) of the same slave as the FMI 2.0
one (both adapters over herringbone/fmu/core.py): it validates, and driven by fmpy it gives the
FMI 2.0 FMU's outputs bit for bit, on the reference scene and on one with contact loss; its start
time, its message for a bad parameter, its FMU state.
"""
import math
import shutil
import xml.etree.ElementTree as ET
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from helpers import MODELS

import herringbone
from herringbone.fmu import builder, resource_path
from herringbone.fmu.pythonfmu_references import PYTHONFMU_LIBRARY_PREFIX
from herringbone.fmu.run import simulate_scene_fmu

SCENES = ("reference", "contact_loss")  # contact_loss: points lift off and re-engage
STOP_TIME = 0.01  # 100 communication steps of the scenes' 1e-4 s
ERROR = 3  # fmi3Error


@pytest.fixture(scope="session")
def fmus(tmp_path_factory):
    """{(scene, FMI version): FMU path}, built once."""
    folder = tmp_path_factory.mktemp("fmi3")
    return {(scene, version): builder.build_gear_fmu(MODELS / f"{scene}.toml",
                                                     folder / f"{scene}_{version}.fmu",
                                                     fmi_version=version)
            for scene in SCENES for version in (2, 3)}


def test_both_fmus_carry_the_linux_binary_only(fmus):
    """The FMU is built and tested on Linux x86-64 only (docs/hosts.md): pythonfmu's and
    pythonfmu3's Windows binaries are left out, so that a host elsewhere says the platform is
    missing instead of loading an untried library. The FMI 2.0 FMU's library is this package's,
    in front of pythonfmu's (fmu/resource_path.c), where a C compiler built it."""
    fmi2 = ["binaries/linux64/HerringboneGear.so"]
    if resource_path.c_compiler() is not None:
        fmi2.append(f"binaries/linux64/{PYTHONFMU_LIBRARY_PREFIX}HerringboneGear.so")
    for version, expected in ((2, fmi2), (3, ["binaries/x86_64-linux/HerringboneGear.so"])):
        names = zipfile.ZipFile(fmus["reference", version]).namelist()
        binaries = [name for name in names
                    if name.startswith("binaries/") and not name.endswith("/")]
        assert binaries == expected, (version, binaries)


def variables(fmu):
    return {v.name: v for v in read_model_description(str(fmu)).modelVariables}


@pytest.mark.parametrize("scene", SCENES)
def test_fmi3_fmu_validates_and_declares_what_the_fmi2_one_does(fmus, scene):
    fmu2, fmu3 = fmus[scene, 2], fmus[scene, 3]
    assert builder.validate(fmu3) == []
    description = read_model_description(str(fmu3))
    assert description.fmiVersion == "3.0" and description.coSimulation.canSerializeFMUstate
    two, three = variables(fmu2), variables(fmu3)
    assert three.pop("time").causality == "independent"  # FMI 3.0 wants it
    assert list(two) == list(three)  # the same names in the same order: the same references
    for name, v2 in two.items():
        v3 = three[name]
        assert (v3.valueReference, v3.causality, v3.variability, v3.description) \
            == (v2.valueReference, v2.causality, v2.variability, v2.description), name
        assert (v3.unit, v3.min, v3.max) == (v2.unit, v2.min, v2.max), name
        number = v2.type in ("Real", "Integer") and v2.start is not None
        # FMI 2.0: pythonfmu writes 16 digits; FMI 3.0: every bit (repr)
        assert (float(v3.start) == pytest.approx(float(v2.start), rel=1e-15, abs=0)) \
            if number else v3.start == v2.start, name
    with zipfile.ZipFile(fmu3) as zf:  # the FMU carries its compiled integrator
        assert any("numba_cache" in name for name in zf.namelist())
        root = ET.fromstring(zf.read("modelDescription.xml"))
    assert all(output.get("dependencies") == "" for output in root.iter("Output"))
    assert "generationDateAndTime" not in root.attrib


@pytest.mark.parametrize("scene", SCENES)
def test_fmi3_outputs_are_the_fmi2_outputs_bit_for_bit(fmus, scene):
    loaded = herringbone.load_scene(MODELS / f"{scene}.toml")
    two = simulate_scene_fmu(fmus[scene, 2], loaded, stop_time=STOP_TIME)
    three = simulate_scene_fmu(fmus[scene, 3], loaded, stop_time=STOP_TIME)
    assert list(two) == list(three) and len(two["time"]) == round(STOP_TIME / 1e-4) + 1
    for name in two:
        assert np.array_equal(two[name], three[name]), name  # bit for bit, NaN nowhere
    if scene == "contact_loss":  # the run does lose contact: fewer points carry load
        assert two["n_contacts"].min() < two["n_contacts"].max()


def test_fmi3_start_time_is_the_first_steps_time(fmus):
    """pythonfmu3 does not pass enterInitializationMode's startTime on: the run starts where
    the first doStep starts it, which gives the FMI 2.0 FMU's run from the same start time."""
    runs = [fmpy.simulate_fmu(str(fmus["reference", version]), start_time=1.0,
                              stop_time=1.002, output_interval=1e-4) for version in (2, 3)]
    assert len(runs[1]) == 21 and runs[1]["time"][-1] == pytest.approx(1.002)
    for name in ("F_mesh", "F_brg_pinion_left", "w_pinion"):
        assert np.array_equal(runs[0][name], runs[1][name]), name


def test_fmi3_bad_parameter_error_names_it(fmus, capfd):
    with pytest.raises(FMICallException, match="fmi3DoStep failed with status 3"):
        fmpy.simulate_fmu(str(fmus["reference", 3]), stop_time=1e-3,
                          start_values={"m_pinion": -1.0})
    printed = capfd.readouterr().out  # fmpy prints every message pythonfmu3 passes on
    assert "[ERROR] " in printed
    assert "parameter m_pinion is -1.0 kg; allowed: [1e-09, 1e+07] kg" in printed


@pytest.fixture
def instance(fmus):
    fmu = fmus["reference", 3]
    unzipped = extract(str(fmu))
    description = read_model_description(unzipped)
    messages = []
    slave = FMU3Slave(guid=description.guid, unzipDirectory=unzipped,
                      modelIdentifier=description.coSimulation.modelIdentifier,
                      instanceName="gear")
    slave.instantiate(loggingOn=False,
                      logMessage=lambda env, status, category, message:
                      messages.append((status, message.decode())))
    slave.enterInitializationMode(startTime=0.0)
    slave.exitInitializationMode()
    slave.messages = messages
    slave.refs = {v.name: v.valueReference for v in description.modelVariables}
    yield slave
    slave.terminate()
    slave.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)


def steps(slave, start, count, size=1e-4):
    rows = []
    for k in range(count):
        slave.doStep(currentCommunicationPoint=start + k * size, communicationStepSize=size)
        rows.append(slave.getFloat64([slave.refs["F_mesh"], slave.refs["w_pinion"]]))
    return np.array(rows)


def test_fmi3_state_round_trip_and_serialization(instance):
    steps(instance, 0.0, 5)
    state = instance.getFMUState()
    serialized = instance.serializeFMUState(state)
    first = steps(instance, 5e-4, 10)
    instance.setFMUState(state)
    assert np.array_equal(steps(instance, 5e-4, 10), first)
    restored = instance.deserializeFMUState(serialized)
    instance.setFMUState(restored)
    assert np.array_equal(steps(instance, 5e-4, 10), first)
    instance.freeFMUState(state)
    instance.freeFMUState(restored)
    assert instance.messages == []


def test_fmi3_start_time_stays_once_the_first_step_set_it(instance):
    """The first doStep sets the start time pythonfmu3 does not pass on; a state taken before
    that step and set again does not let a later doStep start the run anew elsewhere."""
    before = instance.getFMUState()
    first = steps(instance, 0.0, 3)
    instance.setFMUState(before)
    with pytest.raises(FMICallException, match="status 3"):
        instance.doStep(currentCommunicationPoint=0.5, communicationStepSize=1e-4)
    ((status, text),) = instance.messages
    assert status == ERROR and "doStep from t = 0.5 s, but the FMU is at t = 0" in text
    assert np.array_equal(steps(instance, 0.0, 3), first)
    instance.freeFMUState(before)


def test_fmi3_errors_are_fmi3error_and_the_instance_lives(instance):
    steps(instance, 0.0, 2)
    with pytest.raises(FMICallException, match="status 3"):  # a skipped step
        instance.doStep(currentCommunicationPoint=1.0, communicationStepSize=1e-4)
    ((status, text),) = instance.messages
    assert status == ERROR and "doStep from t = 1.0 s" in text and "fmi3SetFMUState" in text
    # refusals answer fmi3OK, with a message: an output set, a fixed parameter after init
    instance.setFloat64([instance.refs["F_mesh"]], [1.0])
    instance.setFloat64([instance.refs["m_pinion"]], [2.0])
    assert "F_mesh is an output" in instance.messages[1][1]
    assert "m_pinion is a fixed parameter" in instance.messages[2][1]
    assert instance.getFloat64([instance.refs["m_pinion"]]) == [0.929436]
    steps(instance, 2e-4, 2)  # the input problem has cleared: the run goes on
    assert len(instance.messages) == 3


def test_fmi3_a_bad_step_size_and_calls_out_of_order_are_errors_and_the_instance_lives(
        instance):
    """As the Reference FMUs answer: a step size that is not finite and > 0 is fmi3Error with
    one message (twice in a row: the instance lives, where a Python exception made it Fatal);
    enter and exit initialization again answer OK with a message, and the run goes on."""
    steps(instance, 0.0, 2)
    for size in (math.nan, math.nan, -1e-4):
        with pytest.raises(FMICallException, match="status 3"):
            instance.doStep(currentCommunicationPoint=2e-4, communicationStepSize=size)
    assert [text for _, text in instance.messages] == [
        "gear: communicationStepSize is nan s; allowed: finite and > 0 s",
        "gear: communicationStepSize is -0.0001 s; allowed: finite and > 0 s"]
    instance.enterInitializationMode(startTime=0.0)
    instance.exitInitializationMode()
    assert all("after the FMU was initialized: refused, the run goes on" in text
               for _, text in instance.messages[2:]) and len(instance.messages) == 4
    steps(instance, 2e-4, 2)
    instance.terminate()
    with pytest.raises(FMICallException, match="status 3"):
        instance.doStep(currentCommunicationPoint=4e-4, communicationStepSize=1e-4)
    assert instance.messages[-1][1].startswith(
        "gear: fmi3DoStep after fmi3Terminate: refused; allowed: doStep once "
        "fmi3EnterInitializationMode and fmi3ExitInitializationMode have initialized the FMU")


def _si_exponents(unit: str) -> dict:
    """The SI base exponents of a unit written as the FMUs write them ("N.m.s/rad",
    "N.m.s2/rad2"): factors joined by '.', one '/', a power as trailing digits; N = kg·m/s²."""
    import re

    exponents: dict = {}
    numerator, _, denominator = unit.partition("/")
    for sign, part in ((1, numerator), (-1, denominator)):
        for factor in filter(None, part.split(".")):
            name, power = re.fullmatch(r"([a-zA-Z]+)(\d*)", factor).groups()
            power = sign * int(power or 1)
            base = {"N": {"kg": 1, "m": 1, "s": -2}}.get(name, {name: 1})
            for dimension, value in base.items():
                exponents[dimension] = exponents.get(dimension, 0) + power * value
    return {dimension: value for dimension, value in exponents.items() if value}


def test_every_unit_declares_its_si_base_units(fmus):
    """Each <Unit> of both FMUs carries a <BaseUnit> with the SI exponents of its name (worked
    out here from the name, apart from the builder's table), so that a host can check and
    convert the units of what it connects; "1" has none."""
    for version in (2, 3):
        root = ET.fromstring(zipfile.ZipFile(fmus["reference", version])
                             .read("modelDescription.xml"))
        units = root.findall("UnitDefinitions/Unit")
        assert len(units) >= 10
        for unit in units:
            base = unit.find("BaseUnit")
            assert base is not None, (version, unit.get("name"))
            declared = {dimension: int(power) for dimension, power in base.attrib.items()}
            name = unit.get("name")
            assert declared == ({} if name == "1" else _si_exponents(name)), (version, name)


# A C host that gives no log callback (FMI 3.0 allows logMessage = NULL), in a process of its
# own: pythonfmu3 0.3.4 called the NULL pointer with the first message (a segmentation fault)
NO_LOGGER_HOST = r'''
import sys
from ctypes import POINTER, byref, c_bool, c_char_p, c_double, c_int, c_size_t, c_uint32, \
    c_void_p
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave
unzipped = extract(sys.argv[1])
description = read_model_description(unzipped)
refs = {v.name: v.valueReference for v in description.modelVariables}
dll = FMU3Slave(guid=description.guid, unzipDirectory=unzipped,
                modelIdentifier="HerringboneGear", instanceName="g").dll
def call(name, argtypes, *args):
    function = getattr(dll, name)
    function.argtypes, function.restype = argtypes, c_int
    return function(*args)
instantiate = dll.fmi3InstantiateCoSimulation
instantiate.restype = c_void_p
instantiate.argtypes = [c_char_p, c_char_p, c_char_p] + [c_bool] * 4 + [c_void_p, c_size_t] \
    + [c_void_p] * 3
resources = f"file://{unzipped}/resources/".encode()
def run(problem):
    instance = instantiate(b"g", description.guid.encode(), resources, False, False, False,
                           False, None, 0, None, None, None)
    one = lambda name, value: call("fmi3SetFloat64", [c_void_p, POINTER(c_uint32), c_size_t,
                                   POINTER(c_double), c_size_t], instance,
                                   (c_uint32 * 1)(refs[name]), 1, (c_double * 1)(value), 1)
    statuses = [call("fmi3EnterInitializationMode", [c_void_p, c_bool, c_double, c_double,
                     c_bool, c_double], instance, False, 0.0, 0.0, False, 0.0)]
    if problem == "parameter":
        one("m_pinion", -1.0)
    statuses.append(call("fmi3ExitInitializationMode", [c_void_p], instance))
    step = lambda at: call("fmi3DoStep", [c_void_p, c_double, c_double, c_bool] + [c_void_p] * 4,
                           instance, at, 1e-4, True, byref(c_bool()), byref(c_bool()),
                           byref(c_bool()), byref(c_double()))
    if problem != "parameter":
        statuses.append(step(0.0))
        if problem == "input":
            one("M_motor", float("nan"))
        statuses.append(step(0.5 if problem == "time" else 1e-4))
    if problem == "reset":  # a new slave over the same instance: the same again
        statuses.append(call("fmi3Reset", [c_void_p], instance))
        statuses.append(call("fmi3EnterInitializationMode", [c_void_p, c_bool, c_double,
                             c_double, c_bool, c_double], instance, False, 0.0, 0.0, False, 0.0))
        one("m_pinion", -1.0)
        statuses.append(call("fmi3ExitInitializationMode", [c_void_p], instance))
    print(problem, *statuses, flush=True)
for problem in sys.argv[2:]:
    run(problem)
'''


def test_fmi3_host_without_a_log_callback_gets_statuses_and_stderr(fmus, tmp_path):
    """A host that passes no log callback gets each problem's status (fmi3Fatal from
    exitInitializationMode for a bad parameter, fmi3Error from doStep for a NaN input and a
    doStep from the wrong time) and the message on stderr, and its process ends normally."""
    import subprocess
    import sys

    script = tmp_path / "host.py"
    script.write_text(NO_LOGGER_HOST)
    run = subprocess.run([sys.executable, str(script), str(fmus["reference", 3]), "parameter",
                          "input", "time", "reset"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.split("\n")[:4] == ["parameter 0 4", "input 0 0 0 3", "time 0 0 0 3",
                                          "reset 0 0 0 0 0 0 4"]
    # once for the parameter run, once for the reset's (a new slave over the same Logger)
    assert run.stderr.count(
        "g: error: parameter m_pinion is -1.0 kg; allowed: [1e-09, 1e+07] kg") == 2
    assert "g: error: input M_motor is nan; allowed: any finite number" in run.stderr
    assert "g: error: doStep from t = 0.5 s, but the FMU is at t = 0.0001 s" in run.stderr


# A host whose Python has the FMU's own FMI package and not the other one (pythonfmu3 without
# pythonfmu, as docs/fmi3.md's host; pythonfmu without pythonfmu3): it runs the FMU, a bad
# parameter's message included, and prints the FMI packages it imported
WITHOUT_THE_OTHER_PACKAGE = r'''
import sys

class NotInstalled:
    """The FMI package named in argv[2] is not installed: its import fails as such."""
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] == sys.argv[2]:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)

sys.meta_path.insert(0, NotInstalled())
import fmpy
from fmpy.fmi1 import FMICallException
result = fmpy.simulate_fmu(sys.argv[1], stop_time=0.002, output_interval=1e-3)
try:
    fmpy.simulate_fmu(sys.argv[1], stop_time=0.002, start_values={"m_pinion": -1.0})
except FMICallException:
    pass
print(len(result), " ".join(sorted({name.split(".")[0] for name in sys.modules
                                    if name.startswith("pythonfmu")})))
'''


@pytest.mark.parametrize(("version", "missing", "imported"),
                         [(3, "pythonfmu", "pythonfmu3"), (2, "pythonfmu3", "pythonfmu")])
def test_each_fmu_runs_in_a_host_without_the_other_versions_pythonfmu(fmus, tmp_path, version,
                                                                     missing, imported):
    """The FMI 3.0 FMU carries pythonfmu3 and needs no pythonfmu, the FMI 2.0 one the other
    way round: each instantiates, runs and reports a bad parameter in a host whose Python has
    the other package missing (its import fails), and imports only its own."""
    import subprocess
    import sys

    script = tmp_path / "host.py"
    script.write_text(WITHOUT_THE_OTHER_PACKAGE)
    run = subprocess.run([sys.executable, str(script), str(fmus["reference", version]), missing],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stdout.split("\n")[-2] == f"3 {imported}"  # 3 samples; no other FMI package
    assert "parameter m_pinion is -1.0 kg; allowed: " in run.stdout + run.stderr
    assert "ModuleNotFoundError" not in run.stdout + run.stderr


def test_the_host_line_speaks_to_an_fmi3_slave_without_pythonfmu(monkeypatch, capsys):
    """HostLine (what the integrator's first start says through, before a compile) takes an
    FMI 3.0 slave without importing pythonfmu: a WARNING reaches pythonfmu3's log as
    fmi3Warning in its own category, an INFO as fmi3OK, and both reach stderr."""
    import logging
    import sys

    from pythonfmu3 import Fmi3Slave
    from pythonfmu3.enums import Fmi3Status

    from herringbone.fmu.pythonfmu_logger import HostLine

    for name in {"pythonfmu", *[name for name in sys.modules if name.startswith("pythonfmu.")]}:
        monkeypatch.setitem(sys.modules, name, None)  # its import fails, submodules' too
    slave = Fmi3Slave(instance_name="gear")
    line = HostLine(slave, None)  # as the FMI 3.0 slave builds it (fmu/core.py, _setup)
    line.say("compiling the integrator", logging.INFO)
    line.say("cannot copy the compiled integrator", logging.WARNING)
    logged = [(message.status, message.category, message.msg) for message in slave.log_queue]
    assert logged == [(Fmi3Status.ok, "logAll", "gear: compiling the integrator"),
                      (Fmi3Status.warning, "logStatusWarning",
                       "gear: cannot copy the compiled integrator")]
    assert "herringbone FMU gear: cannot copy" in capsys.readouterr().err
