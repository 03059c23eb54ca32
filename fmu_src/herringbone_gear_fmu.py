"""The gear train as an FMI 2.0 co-simulation slave: a thin adapter over herringbone's model.

The FMU carries its scene (resources/scene.toml) and declares exactly that scene's variables:
its parameters (start values from the scene), the two input torques, the outputs of MODEL.md
section 7, and the solver's settings. doStep advances the same model that reference_simulate
uses, stopping at every contact switch.

Errors never raise: a Python exception is fmi2Fatal, which aborts a libcosim host. A bad
parameter, a non-finite input or a solver failure is logged at error status and the next doStep
returns False (fmi2Discard), so the host keeps running and shows the message.
"""
import math
from pathlib import Path

import fmu_runtime  # first: a missing dependency is named before anything imports it

fmu_runtime.check_dependencies()
import numpy as np  # noqa: E402

from fmi_units import RealWithUnit
from pythonfmu import (DefaultExperiment, Fmi2Causality, Fmi2Slave, Fmi2Variability, Boolean,
                       Integer, String)
from pythonfmu.enums import Fmi2Status

import herringbone
from herringbone import first_start
from herringbone.model import GearTrainModel, output_names
from herringbone.parameters import INPUTS, OUTPUTS, Parameter, check_value, parameters_of
from herringbone.integrator import (DEFAULT_TOLERANCE, METHODS, STIFFNESS_RATIO,
                                    CompiledStepper, warm_up)
from herringbone.stepping import start_position

SCENE_FILE = "scene.toml"
TIGHTEST_TOLERANCE = 1e-12  # below this the error control works on rounding noise

# The solver's settings, declared next to their meaning like the model's parameters.
SOLVER_SETTINGS = {
    "solver_tolerance": Parameter(
        "solver_tolerance", DEFAULT_TOLERANCE, "1", "error allowed per internal step, "
        "relative to the static mesh force (tighter: more accurate, slower)"),
    "max_step": Parameter(
        "max_step", 0.0, "s", "largest internal step (0: no limit beyond accuracy)"),
    "solver_method": Parameter(
        "solver_method", "auto", "", "internal integrator: 'dop853' (explicit, order 8), "
        "'radau' (implicit, L-stable, order 5, for stiff scenes) or 'auto' (radau when the "
        f"fastest eigenvalue is over {STIFFNESS_RATIO:g} times the fastest oscillation: "
        "overdamped stiffness)", kind=str),
}


class HerringboneGear(Fmi2Slave):
    description = "Herringbone Novikov gear train: motor, pinion, wheel and load (MODEL.md)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmu_runtime.finalize_python_first(self.resources)  # C hosts: no crash at exit
        first_start.prepare(self, kwargs.get("logger"))  # before anything is compiled
        self.scene = herringbone.load_scene(Path(self.resources) / SCENE_FILE)
        experiment = self.scene.experiment
        type(self).default_experiment = DefaultExperiment(
            start_time=0.0, stop_time=experiment.stop_time,
            step_size=experiment.output_interval)
        self.values = dict(self.scene.parameters)
        self.values.update({name: p.default for name, p in SOLVER_SETTINGS.items()})
        motor_torque, load_torque = self.scene.inputs.at(0.0)
        self.values.update(M_motor=motor_torque, M_load=load_torque)
        # model.output_vector at the current position (zeros until a valid start): the
        # outputs' getters read it where the scene's layout puts them
        scene_model = GearTrainModel(self.scene)
        layout = dict(scene_model.output_layout)
        self.output_values = np.zeros(scene_model.output_layout_size)
        self.problem = None  # what stops the run, logged once and reported by every doStep
        self.run = None  # integrator.Run, advanced in place by every doStep
        self.stepper = None
        self.real_output_entries = {}  # value reference -> entry of output_values (get_real)

        for name, parameter in {**parameters_of(self.scene.components),
                                **SOLVER_SETTINGS}.items():
            self._declare(name, parameter, Fmi2Causality.parameter, Fmi2Variability.fixed)
        for name, parameter in INPUTS.items():
            self._declare(name, parameter, Fmi2Causality.input, Fmi2Variability.continuous)
        for name in output_names(self.scene):
            output = OUTPUTS[name]
            getter = (lambda i=layout[name]: int(self.output_values.item(i))) \
                if output.kind is int else (lambda i=layout[name]: self.output_values.item(i))
            if output.kind is int:
                self.register_variable(Integer(name, description=output.description,
                                               causality=Fmi2Causality.output,
                                               variability=Fmi2Variability.discrete,
                                               getter=getter))
            else:
                variable = RealWithUnit(name, unit=output.unit, description=output.description,
                                        causality=Fmi2Causality.output,
                                        variability=Fmi2Variability.continuous, getter=getter)
                self.register_variable(variable)
                self.real_output_entries[variable.value_reference] = layout[name]
        self.register_variable(Integer(
            "internal_steps", description="internal steps the integrator has taken since "
            "initialization (a diagnostic of its cost)", causality=Fmi2Causality.local,
            variability=Fmi2Variability.discrete,
            getter=lambda: self.stepper.accepted_steps if self.stepper else 0))
        self._start()  # outputs at t = 0 for the scene's own values

    def _declare(self, name, parameter, causality, variability):
        kind = {bool: Boolean, int: Integer, str: String}.get(parameter.kind)
        arguments = dict(description=f"{parameter.description} [{parameter.unit}]"
                         if kind else parameter.description, causality=causality,
                         variability=variability, getter=lambda: self.values[name],
                         setter=lambda value: self.values.__setitem__(name, value))
        self.register_variable(kind(name, **arguments) if kind else
                               RealWithUnit(name, unit=parameter.unit, **arguments))

    # --- FMI callbacks -----------------------------------------------------------------------

    def get_real(self, vrs):
        # A master reads the outputs after every doStep. pythonfmu's get_real calls one getter
        # per variable, 0.35 µs each; they all sit in output_values, read here in one pass.
        # Anything else (a parameter, a wrong reference) takes pythonfmu's way and its errors.
        entries = self.real_output_entries
        if all(vr in entries for vr in vrs):
            values = self.output_values
            return [values.item(entries[vr]) for vr in vrs]
        return super().get_real(vrs)

    def exit_initialization_mode(self):
        self._start()

    def do_step(self, current_time, step_size):
        if self.problem is None:
            torques = (self.values["M_motor"], self.values["M_load"])
            for name, value in zip(INPUTS, torques):
                if not math.isfinite(value):
                    self._fail(f"input {name} is {value}; allowed: any finite number")
            # masters add up their times in their own way: forgive rounding, not a skipped step
            drift = abs(current_time - self.run.time)
            if drift > 1e-6 * step_size + 1e-12 * abs(current_time):
                self._fail(f"doStep from t = {current_time!r} s, but the FMU is at "
                           f"t = {self.run.time!r} s (roll back with fmi2SetFMUstate)")
            if self.problem is None:
                try:
                    self.stepper.run_to(self.run, current_time + step_size, torques)
                except Exception as error:  # never let an exception reach the host
                    self._fail(f"doStep from t = {current_time:g} s by {step_size:g} s "
                               f"failed: {error}")
        if self.problem is not None:
            self._log_error(self.problem)
            return False
        return True

    def _get_fmu_state(self):
        # the run changes in place: a state holds an immutable snapshot of it (a Position)
        position = self.stepper.position(self.run) if self.run is not None else None
        return {"position": position, "values": dict(self.values), "problem": self.problem}

    def _set_fmu_state(self, state):
        position = state["position"]
        self.run = self.stepper.start(position) if position is not None else None
        self.output_values = (self.run.outputs if self.run is not None
                              else np.zeros_like(self.output_values))
        self.values = dict(state["values"])
        self.problem = state["problem"]

    # --- the model behind it -----------------------------------------------------------------

    def _start(self):
        """Validate the parameters and place the train in its initial state (MODEL.md 6)."""
        self.problem = None
        try:
            problems = [(name, check_value(p, self.values[name])) for name, p in INPUTS.items()]
            problems += [(name, self._check_solver_setting(name, self.values[name]))
                         for name in SOLVER_SETTINGS]
            for name, problem in problems:
                if problem:
                    return self._fail(f"{name} {problem}")
            given = {k: v for k, v in self.values.items() if k in self.scene.parameters}
            scene = self.scene.with_parameters(**given).with_inputs(
                M_motor=self.values["M_motor"], M_load=self.values["M_load"])
            model = GearTrainModel(scene)
            max_step = self.values["max_step"] or math.inf
            self.stepper = CompiledStepper(model, self.values["solver_tolerance"],
                                           method=self.values["solver_method"],
                                           max_step=max_step)
            position = start_position(model, self.values["M_motor"])
            warm_up(self.stepper, position)  # a compile says so itself (first_start)
            self.run = self.stepper.start(position)
            self.output_values = self.run.outputs  # updated in place by every doStep
        except herringbone.SceneError as error:
            # the scene's own message names the variable; drop its file prefix
            self._fail(str(error).split(": ", 1)[-1].replace("[parameters] ", "parameter "))
        except Exception as error:
            self._fail(f"initialization failed: {error}")

    @staticmethod
    def _check_solver_setting(name, value):
        if name == "solver_method":
            return None if value in METHODS else (
                f"is {value!r}; allowed: {', '.join(repr(m) for m in METHODS)}")
        allowed = {"solver_tolerance": f"[{TIGHTEST_TOLERANCE:g}, 0.01]",
                   "max_step": ">= 0 (0: no limit)"}[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value) \
                or (name == "solver_tolerance" and not TIGHTEST_TOLERANCE <= value <= 1e-2) \
                or (name == "max_step" and value < 0.0):
            return f"is {value!r}; allowed: {allowed}"
        return None

    def _fail(self, message):
        if self.problem is None:
            self.problem = message
            self._log_error(message)

    def _log_error(self, message):
        # hosts format log messages printf-style: a bare '%' crashes them
        self.log(f"{self.instance_name}: {message}".replace("%", "%%"), Fmi2Status.error)
