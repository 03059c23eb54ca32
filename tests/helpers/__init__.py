"""What the tests share: where things are, and how two runs are compared.

The modules beside this one are the shared tools of the test suite: `fmu_host` (an fmpy host of
one instance), `independent_model` (the model written anew from docs/model.md),
`property_checks` (the invariants every run must keep), `scene_distribution` and
`random_scenes` (random scenes, plain and through hypothesis).
"""
from pathlib import Path

import numpy as np

TESTS = Path(__file__).resolve().parent.parent
ROOT = TESTS.parent
MODELS = ROOT / "models"
REGRESSION = TESTS / "regression"

# The forces every comparison of two runs is judged on: the mesh force and the bearing forces
# (a scene without bearings has F_mesh alone).
FORCES = ("F_mesh", "F_brg_pinion_left", "F_brg_pinion_right", "F_brg_wheel_left",
          "F_brg_wheel_right")


def regression_scene(name: str):
    """The scene tests/regression/<name>.toml."""
    import herringbone

    return herringbone.load_scene(REGRESSION / f"{name}.toml")


def _names(run) -> set[str]:
    """The outputs a run has: a dict's keys, or a structured array's fields (fmpy's result)."""
    names = getattr(getattr(run, "dtype", None), "names", None)
    return set(names if names is not None else run)


def force_errors(a, b, scene) -> dict[str, float]:
    """For each of FORCES that both runs have ({name: samples} as simulate gives them, or
    fmpy's structured array): max |a − b| over the samples, as a fraction of
    GearTrainModel.force_scale() (the static mesh force of the largest input torque).
    `scene`: a Scene or a GearTrainModel."""
    from herringbone.model.assembly import GearTrainModel

    model = scene if isinstance(scene, GearTrainModel) else GearTrainModel(scene)
    scale = model.force_scale()
    present = _names(a) & _names(b)
    return {name: float(np.abs(np.asarray(a[name]) - np.asarray(b[name])).max()) / scale
            for name in FORCES if name in present}


def force_error(a, b, scene) -> float:
    """The standard measure of two runs' disagreement: the largest of `force_errors`."""
    return max(force_errors(a, b, scene).values())


def momentum_terms(scene, outputs) -> list[np.ndarray]:
    """Each body's share of the train's angular momentum referred to the pinion (kg·m²/s) at
    every sample of `outputs`: I_p·ω_p, I_w·ω_w/u, and where the scene has them I_m·ω_m and
    I_l·ω_l/u. The mesh force turns the pinion by −F·Rp and the wheel by F·Rw = u·F·Rp, so
    their sum changes by the torques alone, M_motor − M_load/u."""
    p = scene.parameters
    ratio = p["z_wheel"] / p["z_pinion"]
    terms = [p["I_pinion"] * np.asarray(outputs["w_pinion"]),
             p["I_wheel"] * np.asarray(outputs["w_wheel"]) / ratio]
    if scene.has("motor"):
        terms.append(p["I_motor"] * np.asarray(outputs["w_motor"]))
    if scene.has("load"):
        terms.append(p["I_load"] * np.asarray(outputs["w_load"]) / ratio)
    return terms


def compiled_run(scene, tolerance, method):
    """herringbone.simulate's outputs of `scene` by the compiled `method` at `tolerance`
    ({name: samples}); DOP853 at 1e-11 is the converged run the methods are checked against."""
    from herringbone.integrate.compiled_stepper import CompiledStepper
    from herringbone.integrate.contract import simulate_with
    from herringbone.model.assembly import GearTrainModel

    return simulate_with(CompiledStepper(GearTrainModel(scene), tolerance, method), scene)


def communication_run(stepper, stop_time, communication_step, torques=(500.0, 1800.0)):
    """A stepper's outputs at every communication point from the start position of the motor
    torque, as a co-simulation master would see them ({output name: samples})."""
    from herringbone.integrate.contract import start_position

    model = stepper.model
    position = start_position(model, torques[0])
    samples = []
    for k in range(1, int(round(stop_time / communication_step)) + 1):
        position = stepper.advance(position, k * communication_step, torques)
        samples.append(model.outputs(position.state, position.segment.contact_set,
                                     position.segment.loaded))
    return {name: np.array([s[name] for s in samples]) for name in samples[0]}


def shipped_run(name, method, stop_time, communication_step=None):
    """The compiled Run of the shipped scene `name` by `method` at the default tolerance to
    stop_time (s), for its tallies (Run.trial_steps, Run.events, Run.rejected_steps): in one
    call with the starting torques held, or with a `communication_step` (s) as the FMU
    drives it, run_to every step with the scene's torques at the step's start."""
    return shipped_drive(name, method, stop_time, communication_step)[3]


def shipped_drive(name, method, stop_time, communication_step=None, tolerance=None):
    """shipped_run's drive, with what it drove: (model, scene, CompiledStepper, Run); at
    `tolerance` (None: the default one)."""
    import herringbone
    from herringbone.integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper
    from herringbone.integrate.contract import start_position
    from herringbone.model.assembly import GearTrainModel

    scene = herringbone.load_scene(MODELS / f"{name}.toml")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, DEFAULT_TOLERANCE if tolerance is None else tolerance,
                              method)
    run = stepper.start(start_position(model, scene.inputs.at(0.0)[0]))
    step = communication_step or stop_time
    for k in range(round(stop_time / step)):
        stepper.run_to(run, (k + 1) * step, scene.inputs.at(k * step))
    return model, scene, stepper, run


def benchmark_module(name):
    """benchmarks/<name>.py loaded as a module (the benchmarks are scripts, not a package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def one_error_line(capsys, command: str) -> str:
    """The one line on stderr, checked to start with `herringbone COMMAND: `; nothing on
    stdout."""
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1, captured.err
    assert captured.err.startswith(f"herringbone {command}: "), captured.err
    assert "Traceback" not in captured.err
    return captured.err
