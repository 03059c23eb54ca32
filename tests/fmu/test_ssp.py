"""The drive train as an SSP (herringbone.fmu.ssp, examples/cosimulate_drivetrain.py).

`drivetrain.ssp` is built once; libcosim (libcosimpy) and fmpy's SSP support run it, each in a
fresh interpreter (a host that aborts fails its test, not the session, and the gear FMU loads
the herringbone it carries, not this source tree's), and must bring the train to the
intersection of the motor's Kloss curve and the fan curve through the gear ratio, judged as in
tests/fmu/test_cosimulation.py (same step, stop time, windows and tolerances).  The example script
is run as a user runs it, and its printed numbers are checked.
"""
import json
import math
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
import test_cosimulation as cosim
from fmpy import read_model_description
from helpers import ROOT

from herringbone.fmu import ssp

EXAMPLES = ROOT / "examples"
sys.path.insert(0, str(EXAMPLES))
from drivetrain_operating_point import operating_point  # noqa: E402

EXAMPLE = EXAMPLES / "cosimulate_drivetrain.py"
FMU_ENTRIES = {name: f"resources/{file}" for name, file in ssp.FMU_FILES.items()}
SSD_NS = {"ssd": ssp.NAMESPACES["ssd"], "ssc": ssp.NAMESPACES["ssc"],
          "ssv": ssp.NAMESPACES["ssv"]}
# A heavier fan for the parameter-set test: it moves the operating point by far more than
# the tolerances (w_motor by 7e-3, M_motor by 25 %) and stays on the motor's stable branch.
HEAVY_FAN = 1.2


@pytest.fixture(scope="session")
def drivetrain(tmp_path_factory):
    """The SSP of the reference scene, and its three FMUs unpacked beside it."""
    folder = tmp_path_factory.mktemp("ssp")
    path = ssp.build_ssp(ROOT / "models" / "reference.toml", folder / "drivetrain.ssp")
    with zipfile.ZipFile(path) as archive:
        archive.extractall(folder / "unpacked")
    fmus = {name: folder / "unpacked" / entry for name, entry in FMU_ENTRIES.items()}
    return {"ssp": path, "fmus": fmus, "folder": folder}


def expected_point(fmus, **overrides):
    """The analytic operating point from the FMUs' start values (and `overrides`)."""
    motor, fan, gear = (cosim.start_values(fmus[name]) for name in ("motor", "fan", "gear"))
    values = {"M_breakdown": motor["M_breakdown"], "s_breakdown": motor["s_breakdown"],
              "w_sync": motor["w_sync"], "k_fan": fan["k_fan"], "z_pinion": gear["z_pinion"],
              "z_wheel": gear["z_wheel"], **overrides}
    return {**operating_point(**values), "w0_pinion": gear["w0_pinion"]}


def run_child(code, folder):
    """Run `code` in a fresh interpreter in `folder` (temporary files there too); the JSON it
    printed on its last line starting with RESULT."""
    run = subprocess.run([sys.executable, "-c", code], cwd=folder, capture_output=True,
                         text=True, timeout=600, env={**os.environ, "TMPDIR": str(folder)})
    assert run.returncode == 0, f"child exited with {run.returncode}:\n{run.stderr[-3000:]}"
    lines = [line for line in run.stdout.splitlines() if line.startswith("RESULT ")]
    assert lines, f"child printed no result:\n{run.stdout[-3000:]}\n{run.stderr[-3000:]}"
    return json.loads(lines[-1][len("RESULT "):])


def test_archive_holds_the_ssd_and_the_three_fmus(drivetrain):
    """The zip: SystemStructure.ssd and the FMUs it names; the SSD passes the SSP 1.0 schema
    (fmpy), connects speed and torque both ways, gives every connector its FMU's unit, and
    binds the motor's and fan's parameters at their FMUs' start values."""
    from fmpy.ssp.ssd import read_ssd

    with zipfile.ZipFile(drivetrain["ssp"]) as archive:
        assert sorted(archive.namelist()) == sorted(["SystemStructure.ssd",
                                                     *FMU_ENTRIES.values()])
        root = ET.fromstring(archive.read("SystemStructure.ssd"))
    read_ssd(str(drivetrain["ssp"]))  # raises with the schema's complaint if invalid
    connections = {(c.get("startElement"), c.get("startConnector"), c.get("endElement"),
                    c.get("endConnector")) for c in root.iterfind(".//ssd:Connection", SSD_NS)}
    assert connections == {("gear", "w_motor", "motor", "w_motor"),
                           ("motor", "M_motor", "gear", "M_motor"),
                           ("gear", "w_load", "fan", "w_load"),
                           ("fan", "M_load", "gear", "M_load")}
    for component in root.iterfind(".//ssd:Component", SSD_NS):
        name = component.get("name")
        assert component.get("source") == FMU_ENTRIES[name]
        variables = {v.name: v for v in
                     read_model_description(str(drivetrain["fmus"][name])).modelVariables}
        for connector in component.iterfind(".//ssd:Connector", SSD_NS):
            variable = variables[connector.get("name")]
            assert connector.get("kind") == variable.causality, connector.get("name")
            assert connector.find("ssc:Real", SSD_NS).get("unit") == (variable.unit or "1")
        bound = {p.get("name"): float(p.find("ssv:Real", SSD_NS).get("value"))
                 for p in component.iterfind(".//ssv:Parameter", SSD_NS)}
        assert bound == {p: float(variables[p].start)
                         for p in ssp.DEFAULT_PARAMETERS.get(name, ())}, name
    units = {u.get("name") for u in root.iterfind("ssd:Units/ssc:Unit", SSD_NS)}
    assert units == {"rad/s", "N.m", "1", "N.m.s2/rad2"}


def test_same_fmus_and_values_give_the_same_bytes(drivetrain, tmp_path):
    again = ssp.write_ssp(drivetrain["fmus"], tmp_path / "again.ssp")
    assert again.read_bytes() == drivetrain["ssp"].read_bytes()
    other = ssp.write_ssp(drivetrain["fmus"], tmp_path / "other.ssp",
                          parameters={"motor": {"w_sync": 161.0}})
    assert other.read_bytes() != drivetrain["ssp"].read_bytes()


def test_unknown_parameter_is_refused_by_name(drivetrain, tmp_path):
    with pytest.raises(ValueError, match=r"^fan\.k_fun is not a parameter of FanLoad\.fmu; "
                                         r"allowed: k_fan$"):
        ssp.write_ssp(drivetrain["fmus"], tmp_path / "bad.ssp", parameters={"fan": {"k_fun": 1}})
    assert not (tmp_path / "bad.ssp").exists()


@pytest.mark.parametrize("parameters, message", [
    pytest.param({"fan": {"k_fan": -1.0}},
                 "fan.k_fan is -1.0 N.m.s2/rad2; allowed: >= 0 N.m.s2/rad2 and finite",
                 id="fan-negative"),
    pytest.param({"fan": {"k_fan": math.nan}},
                 "fan.k_fan is nan; allowed: >= 0 N.m.s2/rad2 and finite", id="fan-nan"),
    pytest.param({"fan": {"k_fan": math.inf}},
                 "fan.k_fan is inf; allowed: >= 0 N.m.s2/rad2 and finite", id="fan-inf"),
    pytest.param({"motor": {"s_breakdown": 0.0}}, "motor.s_breakdown is 0.0; allowed: (0, 1]",
                 id="motor-exclusive-bound"),
    pytest.param({"motor": {"w_sync": "abc"}},
                 "motor.w_sync must be a number, got str 'abc'; allowed: > 0 rad/s and finite",
                 id="motor-not-a-number"),
    pytest.param({"gear": {"solver_tolerance": 5.0}},
                 "gear.solver_tolerance is 5.0; allowed: [1e-12, 0.01] (error per step relative "
                 "to the static mesh force)", id="gear-declared-max"),
    pytest.param({"gear": {"eps_q": 1.0}},
                 "gear.eps_q is 1.0; allowed: [0, 1) (a fraction of the axial pitch p_x)",
                 id="gear-exclusive-bound"),
    pytest.param({"gear": {"m_pinion": 0.0}}, "gear.m_pinion is 0.0 kg; allowed: [1e-09, 1e+07] "
                 "kg", id="gear-declared-min"),
    pytest.param({"gear": {"max_step": math.inf}},
                 "gear.max_step is inf; allowed: >= 0 s and finite", id="gear-inf"),
    pytest.param({"gear": {"z_pinion": 12.5}},
                 "gear.z_pinion is 12.5; allowed: a whole number [1, 1000]", id="gear-integer"),
    pytest.param({"gear": {"contact_loss": 1}},
                 "gear.contact_loss must be true or false, got int 1", id="gear-boolean"),
    pytest.param({"gear": {"solver_method": "rk4"}},
                 "gear.solver_method is 'rk4'; allowed: 'auto', 'dop853', 'radau', "
                 "'exponential' (the compiled integrator's methods)", id="gear-string"),
    # each allowed alone, not together: what the gear FMU's own scene then refuses
    pytest.param({"gear": {"edge_ramp": 1.0}},
                 "gear.edge_ramp is 1.0 m, over half the narrower face width (0.035 m); "
                 "allowed: <= 0.0175 m, the contact ellipse's half-length in metres (1 mm is "
                 "0.001)", id="gear-relation"),
])
def test_a_value_its_fmu_does_not_allow_is_refused_by_name(drivetrain, tmp_path, parameters,
                                                           message):
    """A value the component's FMU would refuse (the range its model description declares,
    an exclusive bound as fmi_units marks it, the gear's own ranges) or that is no value of
    its type: one ValueError naming component.parameter and what is allowed, nothing written."""
    with pytest.raises(ValueError) as raised:
        ssp.write_ssp(drivetrain["fmus"], tmp_path / "bad.ssp", parameters=parameters)
    assert str(raised.value) == message
    assert not (tmp_path / "bad.ssp").exists()


def settable_start_values(fmu):
    """Every parameter of `fmu` at its start value, as the Python value of its FMI type."""
    convert = {"Real": float, "Integer": int, "Boolean": lambda text: text == "true",
               "String": str}
    return {v.name: convert[v.type](v.start) for v in read_model_description(str(fmu))
            .modelVariables if v.causality == "parameter"}


def test_every_parameter_of_the_gear_can_be_set_in_its_unit(drivetrain, tmp_path):
    """Any parameter of the gear FMU goes into the parameter set (Integer, Boolean and String
    ones as ssv:Integer, ssv:Boolean, ssv:String), each Real in its unit, whose SI exponents
    are those of the FMU's <UnitDefinitions>; the SSD still passes the SSP 1.0 schema, and
    the parameters the message of an unknown one lists are exactly these."""
    from fmpy.ssp.ssd import read_ssd

    gear = drivetrain["fmus"]["gear"]
    values = settable_start_values(gear)
    path = ssp.write_ssp(drivetrain["fmus"], tmp_path / "all.ssp", parameters={"gear": values})
    read_ssd(str(path), validate=True)
    with zipfile.ZipFile(path) as archive:
        root = ET.fromstring(archive.read("SystemStructure.ssd"))
    description = read_model_description(str(gear))
    variables = {v.name: v for v in description.modelVariables}
    written = {}
    for parameter in root.iterfind(".//ssd:Component[@name='gear']//ssv:Parameter", SSD_NS):
        (node,) = list(parameter)
        kind = node.tag.rpartition("}")[2]
        name = parameter.get("name")
        assert kind == variables[name].type, name
        assert node.get("unit") == variables[name].unit, name
        written[name] = node.get("value")
    assert written == {n: str(v).lower() if isinstance(v, bool) else repr(v)
                       if isinstance(v, float) else str(v) for n, v in values.items()}
    declared = {u.name: {k: str(getattr(u.baseUnit, k)) for k in ("kg", "m", "s", "rad")
                         if getattr(u.baseUnit, k)} for u in description.unitDefinitions}
    for unit in root.iterfind("ssd:Units/ssc:Unit", SSD_NS):
        if unit.get("name") in declared:
            assert unit.find("ssc:BaseUnit", SSD_NS).attrib == declared[unit.get("name")]
    with pytest.raises(ValueError) as raised:
        ssp.write_ssp(drivetrain["fmus"], tmp_path / "bad.ssp", parameters={"gear": {"x": 1}})
    assert str(raised.value).partition("allowed: ")[2].split(", ") == sorted(values)


def test_gear_parameters_of_every_type_reach_the_fmu_in_libcosim(drivetrain, tmp_path):
    """libcosim applies the gear's parameter set, whatever the type: after a few steps the FMU
    holds the Real, Integer, Boolean and String values the SSP set (none its start value)."""
    given = {"m_pinion": 2.0, "J_wheel": 0.03, "z_wheel": 30, "contact_loss": False,
             "solver_method": "dop853"}
    path = ssp.write_ssp(drivetrain["fmus"], tmp_path / "gear.ssp", parameters={"gear": given})
    code = ("import json\nfrom libcosimpy.CosimExecution import CosimExecution\n"
            "from libcosimpy.CosimObserver import CosimObserver\n"
            f"execution = CosimExecution.from_ssp_file({str(path)!r}, step_size=100_000)\n"
            "observer = CosimObserver.create_last_value()\n"
            "execution.add_observer(observer=observer)\n"
            "gear = {i.name.decode(): i.index for i in execution.slave_infos()}['gear']\n"
            "refs = {v.name.decode(): v.reference for v in execution.slave_variables(gear)}\n"
            "assert execution.simulate_until(target_time=1_000_000)\n"
            "read = {'Real': observer.last_real_values, 'Integer': observer.last_integer_values,"
            " 'Boolean': observer.last_boolean_values, 'String': observer.last_string_values}\n"
            f"kinds = {{'m_pinion': 'Real', 'J_wheel': 'Real', 'z_wheel': 'Integer', "
            "'contact_loss': 'Boolean', 'solver_method': 'String'}\n"
            "values = {n: read[k](gear, [refs[n]])[0] for n, k in kinds.items()}\n"
            "values['solver_method'] = values['solver_method'].decode()\n"
            "print('RESULT ' + json.dumps(values))\n")
    starts = settable_start_values(drivetrain["fmus"]["gear"])
    assert all(starts[name] != value for name, value in given.items())
    assert run_child(code, tmp_path) == given


def test_the_example_reads_an_integer_parameter_of_the_ssp(drivetrain, tmp_path):
    """z_wheel set in the SSP (ssv:Integer) is the ratio the example's analytic point uses."""
    import cosimulate_drivetrain as example

    path = ssp.write_ssp(drivetrain["fmus"], tmp_path / "ratio.ssp",
                         parameters={"gear": {"z_wheel": 30}})
    assert example.read_ssp(path)["parameters"]["gear"]["z_wheel"] == 30


def test_example_refuses_an_ssp_whose_parameters_have_no_operating_point(drivetrain, tmp_path):
    """An SSP made elsewhere with a fan that drives (k_fan = -1, which build_ssp refuses):
    exit 2 and one error line naming what is wrong, before libcosim runs, no traceback."""
    bad = tmp_path / "negative.ssp"
    with zipfile.ZipFile(drivetrain["ssp"]) as source, zipfile.ZipFile(bad, "w") as target:
        for info in source.infolist():
            data = source.read(info)
            if info.filename == "SystemStructure.ssd":
                root = ET.fromstring(data)
                node = root.find(".//ssv:Parameter[@name='k_fan']/ssv:Real", SSD_NS)
                node.set("value", "-1.0")
                data = ET.tostring(root)
            target.writestr(info, data)
    run = run_example_process(bad, tmp_path)
    assert run.returncode == 2, f"exit {run.returncode}:\n{run.stdout}\n{run.stderr[-3000:]}"
    errors = [line for line in run.stderr.splitlines() if ": error: " in line]
    assert len(errors) == 1 and "Traceback" not in run.stderr, run.stderr[-3000:]
    assert "k_fan = -1.0" in errors[0] and "allowed: k_fan >= 0" in errors[0], errors[0]


def test_libcosim_runs_the_ssp_to_the_operating_point(drivetrain, tmp_path):
    """libcosimpy loads the .ssp in one call and, at the SSD's own 1e-4 s step, settles at
    the curves' intersection (the checks of tests/fmu/test_cosimulation.py)."""
    code = (f"import json, sys; sys.path.insert(0, {str(EXAMPLES)!r})\n"
            "import cosimulate_drivetrain as example\n"
            f"done, end, samples, _ = example.cosimulate({str(drivetrain['ssp'])!r}, "
            f"{cosim.STOP_TIME!r}, {cosim.STEP!r})\n"
            "module = sys.modules.get('herringbone')\n"
            "print('RESULT ' + json.dumps({'completed': done, 'end_time': end, "
            "'samples': samples, 'herringbone': module and module.__file__}))\n")
    result = run_child(code, tmp_path)
    assert result["completed"]
    assert result["end_time"] == pytest.approx(cosim.STOP_TIME, rel=1e-12)
    cosim.assert_ran_packaged_copy(result)
    samples = {name: np.array(values) for name, values in result["samples"].items()}
    samples["time"] = cosim.STEP * np.arange(1, len(samples["w_motor"]) + 1)
    assert len(samples["time"]) == round(cosim.STOP_TIME / cosim.STEP)
    cosim.check_settles_at_operating_point(samples, expected_point(drivetrain["fmus"]),
                                           cosim.STEP)


def run_example_process(ssp_path, folder, *options):
    """Run the example as a user does, with `options`; the finished process."""
    return subprocess.run([sys.executable, str(EXAMPLE), str(ssp_path), *options], cwd=folder,
                          capture_output=True, text=True, timeout=600,
                          env={**os.environ, "TMPDIR": str(folder)})


def run_example(ssp_path, folder):
    """Run the example as a user does; its table as {signal: (last, before, analytic)}."""
    run = run_example_process(ssp_path, folder)
    assert run.returncode == 0, f"{EXAMPLE.name} exited {run.returncode}:\n{run.stderr[-3000:]}"
    table = {}
    for line in run.stdout.splitlines():
        match = re.match(r"(w_motor|w_load|M_motor|M_load)\s+\S+\s+(\S+)\s+(\S+)\s+(\S+)", line)
        if match:
            table[match[1]] = tuple(float(match[i]) for i in (2, 3, 4))
    assert set(table) == set(cosim.SIGNALS), f"no full table in:\n{run.stdout}"
    chatter = [line for line in run.stderr.splitlines()
               if re.search(r"\[(trace|debug|info)\]", line)]  # libcosim's level tags
    assert not chatter, f"libcosim logged below warning level: {chatter[:3]}"
    return table


def check_table(table, expected):
    for signal, (last, before, analytic) in table.items():
        tolerance = cosim.TOLERANCES[signal]
        # printed to 6 decimals: 5e-7 of absolute rounding, far below the tolerances
        assert analytic == pytest.approx(expected[signal], abs=1e-6), signal
        assert last == pytest.approx(expected[signal], rel=tolerance), signal
        assert last == pytest.approx(before, rel=cosim.DRIFT_FRACTION * tolerance), signal


def test_example_prints_the_operating_point(drivetrain, tmp_path):
    """`python examples/cosimulate_drivetrain.py drivetrain.ssp` prints window means at the
    analytic intersection, and that intersection itself."""
    check_table(run_example(drivetrain["ssp"], tmp_path), expected_point(drivetrain["fmus"]))


def test_example_follows_the_parameter_set(drivetrain, tmp_path):
    """With k_fan = 1.2 in the SSD's parameter set, libcosim applies it and the example's
    analytic point uses it: both move to the new intersection, far from the default one."""
    heavy = ssp.write_ssp(drivetrain["fmus"], tmp_path / "heavy.ssp",
                          parameters={"fan": {"k_fan": HEAVY_FAN}})
    expected = expected_point(drivetrain["fmus"], k_fan=HEAVY_FAN)
    default = expected_point(drivetrain["fmus"])
    for signal in cosim.SIGNALS:  # the check below could not pass with the default k_fan
        assert abs(expected[signal] / default[signal] - 1) > 20 * cosim.TOLERANCES[signal]
    check_table(run_example(heavy, tmp_path), expected)


@pytest.mark.parametrize("options, words", [
    pytest.param(("--step", "0.03", "--stop-time", "0.3"),
                 ("--step 0.03 s", "allowed: at most 0.02", "averaging window"),
                 id="step-longer-than-the-window"),
    pytest.param(("--step", "0.003", "--stop-time", "0.01"),
                 ("--stop-time 0.01 s", "allowed: a whole number of steps"),
                 id="stop-time-not-whole-steps"),
    pytest.param(("--stop-time", "0.03"),
                 ("--stop-time 0.03 s", "allowed: at least two averaging windows"),
                 id="stop-time-shorter-than-two-windows"),
    pytest.param(("--step=-1e-4",), ("--step -0.0001", "allowed: finite and > 0"),
                 id="step-negative"),
    pytest.param(("--scene", "torsional"), ("--scene torsional", "carries its own gear FMU",
                                            "allowed: --scene without SSP"),
                 id="scene-beside-an-ssp"),
])
def test_example_refuses_a_bad_argument_before_the_run(drivetrain, tmp_path, options, words):
    """A step or stop time that cannot give two averaging windows of whole steps: exit 2, one
    error line naming the option and what is allowed, before libcosim runs anything."""
    run = run_example_process(drivetrain["ssp"], tmp_path, *options)
    assert run.returncode == 2, f"exit {run.returncode}:\n{run.stdout}\n{run.stderr[-3000:]}"
    assert run.stdout == ""
    errors = [line for line in run.stderr.splitlines() if ": error: " in line]
    assert len(errors) == 1 and "Traceback" not in run.stderr, run.stderr[-3000:]
    assert all(word in errors[0] for word in words), errors[0]


def test_example_says_a_diverged_run_diverged(drivetrain, tmp_path):
    """At 0.01 s steps the explicit coupling of motor and gear is unstable (ssp.STEP): the
    speeds swing off to the wrong sign.  The example says so and exits 1, no table of means."""
    run = run_example_process(drivetrain["ssp"], tmp_path, "--step", "0.01")
    assert run.returncode == 1, f"exit {run.returncode}:\n{run.stdout}\n{run.stderr[-3000:]}"
    assert "the co-simulation diverged" in run.stderr, run.stderr[-3000:]
    assert "Traceback" not in run.stderr
    assert not re.search(r"^(w_motor|w_load|M_motor|M_load)\s", run.stdout, re.M), run.stdout


def test_scene_without_motor_and_load_is_refused_before_any_build(tmp_path, monkeypatch):
    """jump_resonance has neither motor nor load, whose speeds the SSP connects: one
    ValueError naming the scene and what is allowed, before an FMU is built."""
    from herringbone.fmu import builder

    def no_build(*args, **kwargs):
        raise AssertionError("an FMU was built before the scene was checked")

    monkeypatch.setattr(builder, "build_gear_fmu", no_build)
    monkeypatch.setattr(builder, "build_example_fmus", no_build)
    with pytest.raises(ValueError, match=r"^the SSP connects the motor and the load: scene "
                                         r"jump_resonance has neither \(its \[components\]\); "
                                         r"allowed: a scene with motor and load$"):
        ssp.build_ssp("jump_resonance", tmp_path / "x.ssp")
    assert not (tmp_path / "x.ssp").exists()


def test_parameters_of_an_unknown_component_are_refused_before_any_build(tmp_path,
                                                                        monkeypatch):
    """What needs no FMU is checked before the builds: a component the SSP does not have."""
    from herringbone.fmu import builder

    def no_build(*args, **kwargs):
        raise AssertionError("an FMU was built before the parameters were checked")

    monkeypatch.setattr(builder, "build_gear_fmu", no_build)
    monkeypatch.setattr(builder, "build_example_fmus", no_build)
    with pytest.raises(ValueError, match=r"^parameters for 'pump': allowed components: gear, "
                                         r"motor, fan$"):
        ssp.build_ssp("reference", tmp_path / "x.ssp", parameters={"pump": {"k_fan": 1.0}})
    assert not (tmp_path / "x.ssp").exists()


def test_build_fmu_help_says_ssp_packs_fmi_2(capsys):
    """`build-fmu --help` says, for --ssp, that it packs FMI 2.0 FMUs (not --fmi 3) and needs
    a scene with motor and load; --fmi 3 with --ssp is refused (tests/test_bad_input.py)."""
    from herringbone.cli import build_fmu

    assert build_fmu.main(["--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    ssp_help = text[text.index("--ssp FILE build the drive train"):]
    for words in ("FMI 2.0 FMUs", "libcosim, its host, reads FMI 2.0 only", "leave out --fmi 3",
                  "a motor and a load"):
        assert words in ssp_help, ssp_help


def test_fmpy_simulate_ssp_reaches_the_operating_point(drivetrain, tmp_path):
    """fmpy's own SSP support runs the same file (its loop steps every FMU, then passes the
    outputs on: a delay of a step, and it starts the torques at 0) to the same point.  It does
    not read the SSD's parameter bindings; here they equal the FMUs' start values."""
    code = ("import json\nfrom fmpy.ssp.simulation import simulate_ssp\n"
            f"rows = simulate_ssp({str(drivetrain['ssp'])!r}, stop_time={cosim.STOP_TIME!r}, "
            f"step_size={cosim.STEP!r})\n"
            "print('RESULT ' + json.dumps({name: rows[name].tolist() for name in "
            "('time', 'gear.w_motor', 'gear.w_load', 'motor.M_motor', 'fan.M_load')}))\n")
    rows = run_child(code, tmp_path)
    samples = {"time": np.array(rows["time"]),
               **{signal: np.array(rows[f"{cosim.SOURCE_OF_SIGNAL[signal]}.{signal}"])
                  for signal in cosim.SIGNALS}}
    assert len(samples["time"]) == round(cosim.STOP_TIME / cosim.STEP)
    expected = expected_point(drivetrain["fmus"])
    last, before = cosim.window_means(samples, expected, cosim.STEP)
    for signal in cosim.SIGNALS:
        tolerance = cosim.TOLERANCES[signal]
        assert last[signal] == pytest.approx(expected[signal], rel=tolerance), signal
        assert last[signal] == pytest.approx(before[signal],
                                             rel=cosim.DRIFT_FRACTION * tolerance), signal
