"""The gear FMU driven by fmpy against the reference integration (same model, same inputs)."""
import dataclasses
import math
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from helpers import FORCES, MODELS, force_error
from helpers.fmu_host import Instance, structured_inputs

import herringbone
from herringbone.fmu import builder

DEFAULT_BOUND = 1e-6  # of the static mesh force, at the FMU's default settings (issue 4)
TIGHT_BOUND = 1e-7  # at its tightest settings (solver_tolerance 1e-12)
STEP = 1e-4
DURATION = 0.02
DISCARD = 2  # fmi2Discard


def static_mesh_force(scene):
    radius = herringbone.model.assembly.GearTrainModel(scene).geometry.radius_pinion
    return scene.inputs.M_motor[0] / radius


def signal(kind, times):
    """Input torques at the communication points; the FMU holds each over its step."""
    motor = np.full_like(times, 500.0)
    load = np.full_like(times, 1800.0)
    if kind == "torque step":
        motor[times >= 0.008] = 800.0
    elif kind == "ramp":
        motor += 300.0 * np.clip((times - 0.004) / 0.012, 0.0, 1.0)
    elif kind == "ripple":
        motor += 50.0 * np.sin(2 * math.pi * 300.0 * times)
        load += 100.0 * np.sin(2 * math.pi * 70.0 * times + 1.0)
    return motor, load


def fmu_against_reference(fmu_path, scene_name, kind, start_values=None):
    scene = herringbone.load_scene(MODELS / f"{scene_name}.toml")
    times = np.arange(round(DURATION / STEP) + 1) * STEP
    motor, load = signal(kind, times)
    result = fmpy.simulate_fmu(str(fmu_path), stop_time=DURATION, output_interval=STEP,
                               input=structured_inputs(times, motor, load),
                               start_values=start_values or {})
    assert result["time"][-1] == pytest.approx(DURATION)
    reference = herringbone.reference_simulate(
        scene.with_inputs(table=[[t, m, ld] for t, m, ld in zip(times, motor, load)]),
        stop_time=DURATION, output_interval=STEP)
    assert result["time"] == pytest.approx(reference["time"], abs=1e-12)
    return force_error(result, reference, scene)


@pytest.mark.parametrize("scene_name, kind", [
    ("reference", "constant"), ("reference", "ripple"), ("torsional", "torque step"),
    ("staggered", "ramp"), ("lead_error", "ripple"),
])
def test_default_settings_agree_with_reference(built_fmus, scene_name, kind):
    assert fmu_against_reference(built_fmus[scene_name], scene_name, kind) < DEFAULT_BOUND


@pytest.mark.parametrize("scene_name, kind", [("reference", "torque step"),
                                              ("staggered", "ripple")])
def test_tightest_settings_agree_with_reference(built_fmus, scene_name, kind):
    error = fmu_against_reference(built_fmus[scene_name], scene_name, kind,
                                  start_values={"solver_tolerance": 1e-12})
    assert error < TIGHT_BOUND


def test_every_built_fmu_validates_and_declares_only_its_scene(built_fmus):
    for name in ("reference", "torsional", "staggered", "lead_error"):
        assert builder.validate(built_fmus[name]) == []
        description = fmpy.read_model_description(str(built_fmus[name]))
        variables = {v.name: v for v in description.modelVariables}
        scene = herringbone.load_scene(MODELS / f"{name}.toml")
        assert float(description.defaultExperiment.stopTime) == scene.experiment.stop_time
        assert float(description.defaultExperiment.stepSize) == scene.experiment.output_interval
        for variable in variables.values():
            assert variable.description and not variable.description.endswith(("[]", "[1]"))
            if variable.type == "Real":
                assert variable.unit, variable.name
        for parameter, value in scene.parameters.items():
            start = variables[parameter].start
            if isinstance(value, bool):
                assert start == str(value).lower()
            else:
                assert float(start) == pytest.approx(float(value), rel=1e-15)
        # the inertias a scene works out say that they follow the masses (docs/hosts.md)
        if "J_pinion" in variables:
            assert "follows the masses" in variables["J_pinion"].description
    torsional = {v.name for v in fmpy.read_model_description(
        str(built_fmus["torsional"])).modelVariables}
    assert not any("brg" in name or name in ("m_pinion", "J_wheel", "a_left") for name in torsional)
    assert {"M_motor", "M_load", "F_mesh", "w_motor", "T_shaft_out"} <= torsional


def test_variable_steps_tiny_large_and_varying(built_fmus, reference_scene):
    """Steps of 1e-5 to 5e-3 s in any order land exactly where the reference is."""
    grid = 1e-5
    reference = herringbone.reference_simulate(reference_scene, stop_time=0.02,
                                               output_interval=grid)
    gear = Instance(built_fmus["reference"])
    units = [1, 1, 7, 500, 3, 1, 250, 40, 1, 2, 100, 95, 998, 1]
    index, worst = 0, 0.0
    try:
        for size in units:
            gear.step(size * grid)
            index += size
            out = gear.get(list(FORCES))
            worst = max(worst, force_error(out, {n: reference[n][index] for n in FORCES},
                                           reference_scene))
    finally:
        gear.free()
    assert index * grid == pytest.approx(0.02)
    assert worst < DEFAULT_BOUND


def test_rollback_restores_everything(built_fmus):
    gear = Instance(built_fmus["reference"])
    names = [*FORCES, "n_contacts", "w_pinion", "dte"]
    try:
        for _ in range(13):
            gear.step(3e-4)
        saved = gear.slave.getFMUstate()
        saved_time = gear.time
        first = []
        for size in (1e-4, 7e-4, 2e-4):
            gear.step(size)
            first.append(gear.get(names))
        for _ in range(2):  # the same state restored twice re-steps identically
            gear.slave.setFMUstate(saved)
            gear.time = saved_time
            again = []
            for size in (1e-4, 7e-4, 2e-4):
                gear.step(size)
                again.append(gear.get(names))
            assert again == first
        gear.slave.freeFMUstate(saved)
    finally:
        gear.free()


def test_instances_in_one_process_are_independent(built_fmus):
    names = [*FORCES, "w_pinion"]
    alone = Instance(built_fmus["reference"], {"M_motor": 700.0, "M_load": 2520.0}, "alone")
    for _ in range(20):
        alone.step(5e-4)
    expected = alone.get(names)
    alone.free()
    first = Instance(built_fmus["reference"], {"M_motor": 700.0, "M_load": 2520.0}, "first")
    second = Instance(built_fmus["reference"], {"M_motor": 300.0, "M_load": 1080.0,
                                                "c_point": 3e8}, "second")
    for _ in range(20):
        first.step(5e-4)
        second.step(5e-4)
    assert first.get(names) == expected
    assert second.get(["F_mesh"])["F_mesh"] != expected["F_mesh"]
    first.free()
    second.free()


def test_reading_many_reals_at_once_gives_what_reading_each_gives(built_fmus):
    # the slave reads its outputs in one pass; parameters and inputs go through their getters
    gear = Instance(built_fmus["reference"], {"M_motor": 600.0, "M_load": 2160.0})
    try:
        for _ in range(7):
            gear.step(3e-4)
        outputs = [v for v in gear.description.modelVariables
                   if v.causality == "output" and v.type == "Real"]
        mixed = outputs[:3] + [gear.variables["c_point"], gear.variables["M_motor"]] + outputs[3:]
        for variables in (outputs, mixed, outputs[::-1]):
            at_once = gear.slave.getReal([v.valueReference for v in variables])
            one_by_one = gear.get([v.name for v in variables])
            assert at_once == [one_by_one[v.name] for v in variables]
        # the same list read after every step, as a master reads it: the new values each time
        references, names = [v.valueReference for v in outputs], [v.name for v in outputs]
        for _ in range(2):
            before = gear.slave.getReal(references)
            gear.step(3e-4)
            after, one_by_one = gear.slave.getReal(references), gear.get(names)
            assert after != before and after == [one_by_one[name] for name in names]
        assert gear.get(["M_motor"])["M_motor"] == 600.0
        assert gear.get(["F_mesh"])["F_mesh"] > 0.9 * static_mesh_force(
            herringbone.load_scene(MODELS / "reference.toml").with_inputs(
                M_motor=600.0, M_load=2160.0))
    finally:
        gear.free()


BAD_VALUES = [
    ({"m_pinion": -1.0}, "m_pinion", "[1e-09, 1e+07]"),
    ({"beta": 1.6}, "beta", "[0.01, 1.4]"),
    ({"eps_q": 1.0}, "eps_q", "[0, 1)"),
    ({"b_right": 0.0}, "b_right", "[1e-06, 10]"),
    ({"c_brg_wheel_left": -5e8}, "c_brg_wheel_left", "[1000, 1e+13]"),
    ({"z_pinion": 0}, "z_pinion", "a whole number [1, 1000]"),
    ({"zeta_mesh": float("nan")}, "zeta_mesh", "[0, 10]"),
    ({"solver_tolerance": 0.5}, "solver_tolerance", "[1e-12, 0.01]"),
    ({"max_step": -1.0}, "max_step", "0, >= 1e-12 or inf"),
    ({"max_step": 1e-300}, "max_step", "0, >= 1e-12 or inf"),
    ({"M_motor": float("inf")}, "M_motor", "finite"),
]


@pytest.mark.parametrize("values, culprit, allowed", BAD_VALUES)
def test_bad_parameter_is_discarded_with_a_message(built_fmus, values, culprit, allowed):
    """pythonfmu turns any exception into fmi2Fatal (which aborts a libcosim host), so the slave
    logs at error status and refuses the next doStep with fmi2Discard; the host lives on."""
    gear = Instance(built_fmus["reference"], values)
    try:
        with pytest.raises(FMICallException) as error:
            gear.step(1e-4)
        assert error.value.status == DISCARD
        errors = [text for status, text in gear.messages if status == 3]  # fmi2Error
        assert errors and culprit in errors[0] and allowed in errors[0]
    finally:
        gear.free()


def test_nan_input_mid_run_is_discarded_and_the_state_kept(built_fmus):
    gear = Instance(built_fmus["reference"])
    try:
        gear.step(1e-3)
        before = gear.get(list(FORCES))
        gear.set(M_load=float("nan"))
        with pytest.raises(FMICallException) as error:
            gear.step(1e-3)
        assert error.value.status == DISCARD
        assert any("M_load" in text and "finite" in text for _, text in gear.messages)
        assert gear.get(list(FORCES)) == before
    finally:
        gear.free()


def test_solver_failure_is_discarded_with_a_message(built_fmus):
    gear = Instance(built_fmus["torsional"])
    try:
        gear.set(M_motor=1e300)  # finite, but drives the state to overflow
        with pytest.raises(FMICallException) as error:
            for _ in range(5):
                gear.step(1e-3)
        assert error.value.status == DISCARD
        assert any("failed" in text for status, text in gear.messages if status == 3)
    finally:
        gear.free()


def test_messages_reach_simulate_fmu_logger(built_fmus):
    received = []
    result = fmpy.simulate_fmu(str(built_fmus["reference"]), stop_time=1e-3, output_interval=1e-4,
                               start_values={"beta": 2.0}, debug_logging=True,
                               logger=lambda *args: received.append(args[-1].decode()))
    assert result["time"][-1] < 1e-3  # the run ends at the first (discarded) step
    assert any("beta" in message and "[0.01, 1.4]" in message for message in received)


def test_scene_input_table_reaches_the_fmu_held_like_the_reference(built_fmus, torsional_scene):
    from herringbone.fmu.run import simulate_scene_fmu

    scene = torsional_scene.with_inputs(table=[[0.0, 500.0, 1800.0], [0.0035, 900.0, 1800.0],
                                               [0.011, 900.0, 3240.0]])
    result = simulate_scene_fmu(built_fmus["torsional"], scene, stop_time=0.015,
                                output_interval=5e-4)
    reference = herringbone.reference_simulate(scene, stop_time=0.015, output_interval=5e-4)
    assert force_error(result, reference, scene) < DEFAULT_BOUND
    # after the first step the motor torque has changed the shaft torque by hundreds of N·m
    assert np.ptp(reference["T_shaft_in"]) > 100.0


def test_step_from_a_time_the_fmu_is_not_at_is_discarded(built_fmus):
    gear = Instance(built_fmus["reference"])
    try:
        gear.step(1e-3)
        gear.time = 5e-3  # a master that skipped ahead without stepping
        with pytest.raises(FMICallException) as error:
            gear.step(1e-3)
        assert error.value.status == DISCARD
        assert any("FMU is at" in text for status, text in gear.messages if status == 3)
    finally:
        gear.free()


@pytest.mark.parametrize("stop_time", [-1.0, 0.0, float("nan")])
def test_scene_inputs_refuses_a_stop_time_that_is_not_finite_and_positive(stop_time):
    """A table for fmpy up to a stop time of -1 s would end before it starts: refused with
    the stop time's one message, as simulate refuses it."""
    with pytest.raises(ValueError, match=r"stop_time is .*; allowed: > 0 and finite"):
        herringbone.scene_inputs(herringbone.load_scene("torque_step"), stop_time)


def test_a_transverse_inertia_left_to_the_scene_follows_the_mass_the_host_sets(built_fmus):
    """J_pinion and J_wheel, which a scene works out from mass and geometry where it does not
    give them, follow the masses a host sets, as Scene.with_parameters's do: with a lead error
    the tilt is driven and J acts (a J left at the build's values put the bearing reactions
    21 N and 43 N off within 0.01 s). One the host sets itself is kept."""
    changed = {"m_pinion": 2.0, "m_wheel": 30.0}
    scene = herringbone.load_scene(MODELS / "lead_error.toml").with_parameters(**changed)
    for given in ({}, {"J_pinion": 1e-3}):
        result = fmpy.simulate_fmu(str(built_fmus["lead_error"]), stop_time=0.01,
                                   output_interval=STEP, start_values={**changed, **given})
        expected = herringbone.simulate(scene.with_parameters(**given), stop_time=0.01,
                                        output_interval=STEP)
        assert force_error(result, expected, scene) < 1e-9
    instance = Instance(built_fmus["lead_error"], start_values=changed)
    taken = instance.get(["J_pinion", "J_wheel"])
    instance.free()
    assert taken == {name: pytest.approx(scene.parameters[name], rel=1e-15)
                     for name in ("J_pinion", "J_wheel")}


def test_a_scene_object_is_built_as_its_file_would_be(tmp_path):
    """build_gear_fmu takes a Scene as the Python API hands it (changed by with_parameters and
    with_inputs): the FMU declares the changed values and runs as herringbone.simulate does."""
    scene = herringbone.load_scene("reference").with_parameters(zeta_mesh=0.08).with_inputs(
        M_motor=600.0, M_load=2160.0)
    # named as scene_from_dict names a scene, and as the FMU names the scene file it carries
    scene = dataclasses.replace(scene, name="scene")
    fmu = builder.build_gear_fmu(scene, tmp_path / "changed.fmu")
    starts = {v.name: v.start for v in fmpy.read_model_description(str(fmu)).modelVariables}
    assert (float(starts["zeta_mesh"]), float(starts["M_motor"])) == (0.08, 600.0)
    through_fmu = fmpy.simulate_fmu(str(fmu), stop_time=2e-3, output_interval=1e-4)
    direct = herringbone.simulate(scene, stop_time=2e-3, output_interval=1e-4)
    assert force_error(through_fmu, direct, scene) < 1e-9


def test_the_fmu_carries_its_documentation_where_the_standard_puts_it(built_fmus, tmp_path):
    """documentation/ with the entry page FMI names (2.0: _main.html, 3.0: index.html): the
    scene, the model's page shown, and the pages a host needs beside it."""
    fmi3 = builder.build_gear_fmu("torsional", tmp_path / "torsional3.fmu", fmi_version=3)
    for fmu, entry in ((built_fmus["torsional"], "_main.html"), (fmi3, "index.html")):
        with zipfile.ZipFile(fmu) as archive:
            names = set(archive.namelist())
            page = archive.read(f"documentation/{entry}").decode("utf-8")
        assert {f"documentation/{name}" for name in builder.FMU_DOCUMENTS} < names
        assert "<h1>HerringboneGear: the scene torsional</h1>" in page
        assert "The reference gear on rigid bearings" in page  # the scene's own header
        assert "# The model" in page and "</pre>" in page
        assert "documentation/model.md in the FMU" in \
            fmpy.read_model_description(str(fmu)).description
