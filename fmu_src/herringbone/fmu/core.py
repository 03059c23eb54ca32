"""The gear train as an FMI co-simulation slave, independent of the FMI version: the core that
the FMI 2.0 adapter (fmu/slave.py, pythonfmu's Fmi2Slave) and the FMI 3.0 adapter
(fmu/slave3.py, pythonfmu3's Fmi3Slave) share. Nothing here imports pythonfmu or pythonfmu3.

The FMU carries its scene (resources/scene.toml) and declares exactly that scene's variables:
its parameters (start values from the scene), the two input torques, the outputs of the model
(herringbone.model.parameters.OUTPUTS) and the solver's settings, all from one table
(`GearCore._declarations`: names, kinds, units, ranges, descriptions, causality and
variability); an adapter turns each `Declaration` into its pythonfmu variable. doStep advances
the same model that reference_simulate uses, stopping at every contact switch.

What the core keeps: the values, the run (start, step, the runaway guard), the checks and their
messages, the FMU state and its serialization. What an adapter gives it: `_register`
(declare one variable, return its value reference), `_log` (queue a message with the host's
logger), `host_logs` (whether the host hears it), and `API` (the FMI function names the
messages cite). How each version answers a problem: the adapters' docstrings and the README
("Errors in each host").

A problem is logged once at error status; where the host does not hear the log it is also
written to the process's stderr. A problem of the inputs (a non-finite torque, a doStep from
the wrong time) lasts until they are valid again; one of the parameters, a solver failure or a
runaway lasts for the instance (or until the FMU state is set). A call that cannot be honoured
but harms nothing (setting an output, or a fixed parameter after initialization; reading a
variable through the wrong type) is refused with a message and answered OK.
"""
import dataclasses
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

# first: a missing dependency is named before anything imports it (herringbone/__init__.py
# and herringbone/fmu/__init__.py import nothing)
from herringbone.fmu import runtime as fmu_runtime

fmu_runtime.check_dependencies()
import numpy as np  # noqa: E402

import herringbone  # noqa: E402
from herringbone.arguments import (  # noqa: E402
    FMU_MAX_STEP,
    FMU_SCENE_FILE,
    FMU_SOLVER_METHOD,
    FMU_SOLVER_TOLERANCE,
    max_step_note,
)
from herringbone.fmu.pythonfmu_logger import HostLine  # noqa: E402
from herringbone.integrate import first_start  # noqa: E402
from herringbone.integrate.compiled_stepper import (  # noqa: E402
    DEFAULT_TOLERANCE,
    STEP_BUDGET_FLOOR,
    STEP_BUDGET_PER_MAX_STEP,
    STIFFNESS_RATIO,
    CompiledStepper,
    StepBudgetExceeded,
    step_budget,
    warm_up,
)
from herringbone.integrate.contract import Position, start_position  # noqa: E402
from herringbone.integrate.segments import Segment  # noqa: E402
from herringbone.model.assembly import GearTrainModel, output_names  # noqa: E402
from herringbone.model.geometry import solid_cylinder_transverse_inertia  # noqa: E402
from herringbone.model.parameters import (  # noqa: E402
    INPUTS,
    NON_NEGATIVE,
    OUTPUTS,
    PARAMETERS,
    Parameter,
    check_value,
    parameters_of,
)

DESCRIPTION = ("Herringbone Novikov gear train: motor, pinion, wheel and load (its model: "
               "documentation/model.md in the FMU)")
# a run's times must resolve the train's fastest time scale to this share (_resolution_problem)
RESOLVED_SHARE = 1e-3
EPSILON = float(np.finfo(float).eps)
STATE_FORMAT = "herringbone-fmu-state-3"  # the serialized FMU state's layout (_get_fmu_state)
STATE_KEYS = {"format", "values", "start_time", "stop_time", "mode", "experiment_tolerance",
              "problem", "input_problem", "run"}
RUN_STATE_KEYS = {"time", "state", "cycle", "interval", "loaded", "step_hint", "outputs",
                  "first_steps", "internal_steps", "stepper_inputs"}
WARNING, ERROR = 1, 3  # the same numbers in fmi2Status and fmi3Status
STATUS_NAMES = {WARNING: "warning", ERROR: "error"}

# The instance's place in the FMI state machine, and where each call may come (as the
# Reference FMUs allow them: a call elsewhere is refused with a message, _order_problem)
INSTANTIATED, INITIALIZATION, STEPPING, TERMINATED = (
    "instantiated", "initialization", "stepping", "terminated")
MODE_WORDS = {INSTANTIATED: "before {prefix}EnterInitializationMode",
              INITIALIZATION: "in initialization mode",
              STEPPING: "after the FMU was initialized", TERMINATED: "after {prefix}Terminate"}
CALLS = {  # call (without its prefix): (the modes it may come in, when that is, in words)
    "SetupExperiment": ({INSTANTIATED}, "once, before {prefix}EnterInitializationMode"),
    "EnterInitializationMode": ({INSTANTIATED}, "once, before the first doStep ({prefix}Reset "
                                "starts again)"),
    "ExitInitializationMode": ({INITIALIZATION}, "once, after {prefix}EnterInitializationMode"),
    "DoStep": ({STEPPING}, "doStep once {prefix}EnterInitializationMode and "
               "{prefix}ExitInitializationMode have initialized the FMU, until "
               "{prefix}Terminate"),
    "Terminate": ({STEPPING}, "once, after {prefix}ExitInitializationMode"),
    "Set": ({INSTANTIATED, INITIALIZATION, STEPPING}, "before {prefix}Terminate"),
}

# The solver's settings, declared next to their meaning like the model's parameters.
SOLVER_SETTINGS = {
    "solver_tolerance": Parameter(
        "solver_tolerance", DEFAULT_TOLERANCE, "1", "error allowed per internal step, "
        "relative to the static mesh force (tighter: more accurate, slower); left at its start "
        "value, a tolerance given by fmi2SetupExperiment takes its place (FMI 2.0; the FMI 3.0 "
        "FMU does not receive the experiment's tolerance)",
        allowed=FMU_SOLVER_TOLERANCE.allowed),
    "max_step": Parameter(
        "max_step", 0.0, "s", "largest internal step (0: no limit beyond accuracy; else at "
        f"least {FMU_MAX_STEP.allowed.low:g} s)", allowed=NON_NEGATIVE),
    "solver_method": Parameter(
        "solver_method", "auto", "", "internal integrator: 'dop853' (explicit, order 8), "
        "'radau' (implicit, L-stable, order 5, for overdamped stiff trains), 'exponential' "
        "(time-invariant segments propagated exactly, the others by dop853) or 'auto' "
        "(exponential where every "
        "contact set, or at least half where dop853 would run, is time-invariant; else radau "
        f"when the fastest eigenvalue is over {STIFFNESS_RATIO:g} times the fastest "
        "oscillation, dop853 otherwise)", kind=str),
}
KINDS = {bool: "boolean", int: "integer", str: "string", float: "real"}
CONVERT = {"real": float, "integer": int, "boolean": bool, "string": str}
# what a refused read returns
REFUSED = {"real": math.nan, "integer": 0, "int64": 0, "boolean": False, "string": ""}


def latest_end(fastest_rate) -> float:
    """The latest time (s) a doStep may end at: where double precision's spacing of times
    reaches RESOLVED_SHARE of the train's fastest time scale 1/|λ|max (`fastest_rate`, 1/s),
    past which the integrator's steps and event times are rounding, not the train. Fixed for a
    stepper: taken once where it is built."""
    return RESOLVED_SHARE / (fastest_rate * EPSILON)


def _resolution_problem(end, limit, fastest_rate) -> str | None:
    """Why a doStep may not end at `end` (s), past `limit` (latest_end), or None (a doStep of
    1e300 s, or an experiment started at 1e9 s, is refused)."""
    if abs(end) <= limit:
        return None
    return (f"doStep to t = {end:g} s: there double precision resolves "
            f"{np.spacing(abs(end)):.2g} s, over {RESOLVED_SHARE:g} of the train's fastest time "
            f"scale (1/|λ|max = {1.0 / fastest_rate:.2g} s); allowed: doSteps that end within "
            f"{limit:.3g} s of t = 0 (an experiment that starts nearer 0, shorter steps)")


def _masters_rounding(step_size, time) -> float:
    """How far (s) a doStep's times may be off the FMU's own for a master's rounding: masters
    add up their times in their own way; forgive that, not a skipped step."""
    return 1e-6 * step_size + 1e-12 * abs(time)


def _step_size_problem(current_time, step_size) -> str | None:
    """Why a doStep's currentCommunicationPoint or communicationStepSize (s) is not allowed,
    or None: the point must be finite, the step finite and > 0, as the FMI standard asks (the
    Reference FMUs answer Error to one that is not)."""
    if not math.isfinite(current_time):
        return f"currentCommunicationPoint is {current_time!r} s; allowed: finite"
    if math.isfinite(step_size) and step_size > 0.0:
        return None
    return f"communicationStepSize is {step_size!r} s; allowed: finite and > 0 s"


# the largest count an FMI Integer (32 bits) holds: internal_steps stays there, not wrapping
# to a negative count past it (1.7e6 steps a second on stiff_bearings by DOP853: 21 minutes)
MOST_COUNTED = 2**31 - 1
# what a variable that cannot be set is, in a refusal's words (by its causality)
CAUSALITY_WORDS = {"output": "an output", "local": "a local variable",
                   "independent": "the independent variable (the time)"}


@dataclasses.dataclass
class Declaration:
    """One variable of the FMU, in FMI terms both versions share: `kind` is "real", "integer",
    "boolean" or "string" (FMI 3.0: Float64, Int32, Boolean, String); `causality` and
    `variability` are the FMI names; `unit` only for reals; `low`/`high` the range (None: open);
    `setter` None for what cannot be set; `output_entry`: where a real output sits in the
    model's output vector (read in one pass by the adapters' getters)."""
    name: str
    kind: str
    causality: str
    variability: str
    description: str
    getter: Callable[[], Any]
    setter: Callable[[Any], None] | None = None
    unit: str | None = None
    low: float | None = None
    high: float | None = None
    output_entry: int | None = None


class GearCore:
    """The slave's logic; an adapter class derives from it and from its pythonfmu slave class
    (GearCore first), calls `_setup` from its __init__ and forwards the FMI callbacks."""

    # the FMI functions the messages name; an adapter replaces them
    API = {"prefix": "fmi2", "set_state": "fmi2SetFMUstate", "setup": "fmi2SetupExperiment",
           "kinds": {"real": "Real", "integer": "Integer", "boolean": "Boolean",
                     "string": "String"}}

    def _setup(self, logger_address):
        """Load the scene, declare the variables (through the adapter's `_register`) and
        start the train at t = 0 with the scene's own values."""
        # before anything is compiled
        first_start.prepare(self.resources, HostLine(self, logger_address).say)
        self.scene = herringbone.load_scene(Path(self.resources) / FMU_SCENE_FILE)
        self.values = dict(self.scene.parameters)
        self.values.update({name: p.default for name, p in SOLVER_SETTINGS.items()})
        motor_torque, load_torque = self.scene.inputs.at(0.0)
        self.values.update(M_motor=motor_torque, M_load=load_torque)
        self.start_values = dict(self.values)
        # from the host's experiment (FMI 2.0: fmi2SetupExperiment; stop_time None: none)
        self.start_time, self.stop_time, self.experiment_tolerance = 0.0, None, None
        self.mode = INSTANTIATED
        self.started_from = None  # (values, start time) the run was started from (_start)
        # model.output_vector at the current position (zeros until a valid start): the
        # outputs' getters read it where the scene's layout puts them
        scene_model = GearTrainModel(self.scene)
        self.output_values = np.zeros(scene_model.output_layout_size)
        self.problem = None  # what stops the run for good (parameters, solver), logged once
        self.input_problem = None  # what stops doSteps until the inputs are valid, logged once
        self.run = None  # compiled_stepper.Run, advanced in place by every doStep
        self.stepper = None
        self.latest_end = math.inf  # latest_end of self.stepper, set where it is built
        self.built_from = None  # the values self.stepper was built from, inputs included
        self.declared = {}  # value reference -> Declaration
        self.real_output_entries = {}  # value reference -> entry of output_values (reals)
        # the value references of the outputs last read together, and their entries
        self.read_plan: tuple = (None, None)
        for declaration in self._declarations(dict(scene_model.output_layout)):
            vr = self._register(declaration)
            self.declared[vr] = declaration
            if declaration.output_entry is not None:
                self.real_output_entries[vr] = declaration.output_entry
        self._start()  # outputs at t = 0 for the scene's own values

    def _declarations(self, layout):
        """The FMU's variables, in value-reference order: parameters and solver settings
        (fixed), the inputs (continuous), the outputs, and the steps taken (local)."""
        declarations = []
        for name, parameter in {**parameters_of(self.scene.components),
                                **SOLVER_SETTINGS}.items():
            declarations.append(self._declaration(name, parameter, "parameter", "fixed"))
        for name, parameter in INPUTS.items():
            declarations.append(self._declaration(name, parameter, "input", "continuous"))
        for name in output_names(self.scene):
            declarations.append(self._output_declaration(name, layout[name]))
        declarations.append(Declaration(
            "internal_steps", "integer", "local", "discrete", "internal steps the integrator "
            f"has taken since initialization (a diagnostic of its cost; {MOST_COUNTED} "
            "from there on: the most an FMI Integer holds)",
            getter=lambda: min(self.stepper.accepted_steps, MOST_COUNTED) if self.stepper
            else 0))
        return declarations

    def _declaration(self, name, parameter, causality, variability):
        """A parameter or input: its range as low/high (an open bound as the closed one; the
        slave checks the open one), its setter through _set. A variable that is not a real
        carries its unit in its description."""
        kind = KINDS[parameter.kind]
        description = parameter.description if kind == "real" or parameter.unit in ("", "1") \
            else f"{parameter.description} [{parameter.unit}]"
        if parameter.default is None and name not in self.scene.given:
            description += "; follows the masses and geometry set while at its start value"
        declaration = Declaration(
            name, kind, causality, variability, description,
            getter=lambda: self._value_taken(name), setter=lambda value: self._set(name, value))
        if kind == "real":
            declaration.unit = parameter.unit
        if kind in ("real", "integer"):
            declaration.low, declaration.high = parameter.allowed.low, parameter.allowed.high
        return declaration

    def _output_declaration(self, name, entry):
        output = OUTPUTS[name]
        if output.kind is int:
            return Declaration(name, "integer", "output", "discrete", output.description,
                               getter=lambda: self._whole(self.output_values.item(entry)))
        return Declaration(name, "real", "output", "continuous", output.description,
                           getter=lambda: self.output_values.item(entry), unit=output.unit,
                           output_entry=entry)

    @property
    def initialized(self):
        """exitInitializationMode passed: the fixed parameters are fixed, doSteps run."""
        return self.mode in (STEPPING, TERMINATED)

    @staticmethod
    def _whole(value):
        return int(value) if math.isfinite(value) else 0  # NaN: no valid start (see _fail)

    # --- the FMI calls, whatever the version ---------------------------------------------------

    def _set_experiment(self, start_time, tolerance=None, stop_time=None):
        """The run starts at start_time (the model's time origin: the train at t0 is where the
        scene puts it at 0) and no doStep may end past `stop_time` (s; None: no end). A
        tolerance takes the place of solver_tolerance unless the host set solver_tolerance to
        something other than its start value. Only before enterInitializationMode (refused
        with a message after, and nothing changes)."""
        problem = self._order_problem("SetupExperiment")
        if problem is not None:
            return self._report(problem)
        self.start_time = float(start_time)
        self.stop_time = None if stop_time is None else float(stop_time)
        self.experiment_tolerance = tolerance
        if self.run is not None:  # outputs before initialization: the same place, moved
            self.run.clock[0] = self.start_time
            self.started_from = (self.started_from[0], self.start_time)

    def _enter_initialization(self):
        """enterInitializationMode: once, before initialization (refused with a message
        elsewhere)."""
        problem = self._order_problem("EnterInitializationMode")
        if problem is not None:
            return self._report(problem)
        self.mode = INITIALIZATION

    def _exit_initialization(self):
        """exitInitializationMode: the run starts from the values set; refused with a message
        where initialization mode was not entered, or after (it would start the run again)."""
        problem = self._order_problem("ExitInitializationMode")
        if problem is not None:
            return self._report(problem)
        self._apply_experiment_tolerance()
        self.mode = STEPPING
        self._start_if_changed()

    def _terminate(self):
        """terminate: the run ends; doSteps and sets are refused after it (fmi2Reset or a
        state set starts again)."""
        problem = self._order_problem("Terminate")
        if problem is not None:
            return self._report(problem)
        self.mode = TERMINATED

    def _step(self, current_time, step_size):
        """Advance by one communication step; returns the problem that stops it (already
        reported), or None."""
        if self.problem is None and self.run is None and self.initialized:
            self._start_if_changed()  # a start an input held back (_start), valid now?
        if self.problem is None:
            self.input_problem = self._step_problem(current_time, step_size)
            if self.input_problem is None:
                self._advance(current_time, step_size)
        return self.problem or self.input_problem

    def _step_problem(self, current_time, step_size):
        """What is wrong with this doStep (reported once while it lasts): a call before
        initialization, its step size, an input, its start time. None of them harms the
        instance: the next doStep without the problem goes on."""
        problem = (self._order_problem("DoStep") or _step_size_problem(current_time, step_size)
                   or _resolution_problem(current_time + step_size, self.latest_end,
                                          self.stepper.fastest_rate)
                   or self._stop_time_problem(current_time, step_size) or self._input_problem())
        if problem is None and \
                abs(current_time - self.run.time) > _masters_rounding(step_size, current_time):
            problem = (f"doStep from t = {current_time!r} s, but the FMU is at "
                       f"t = {self.run.time!r} s (roll back with {self.API['set_state']})")
        if problem is not None and problem != self.input_problem:
            self._report(problem)
        return problem

    def _order_problem(self, call, named=None):
        """Why `call` (a key of CALLS: an FMI function's name without its prefix) may not come
        in the instance's mode, or None (`named`: the function's name where CALLS has a
        family of them, SetReal for Set)."""
        modes, allowed = CALLS[call]
        if self.mode in modes:
            return None
        prefix = self.API["prefix"]
        when = MODE_WORDS[self.mode].format(prefix=prefix)
        goes_on = ", the run goes on" if self.mode == STEPPING else ""
        return (f"{prefix}{named or call} {when}: refused{goes_on}; allowed: "
                f"{allowed.format(prefix=prefix)}")

    def _stop_time_problem(self, current_time, step_size):
        """Why a doStep may not end where it would, past the experiment's stop time (the
        Reference FMUs answer Error), or None; a master's rounding of its times is forgiven
        (_masters_rounding)."""
        end = current_time + step_size
        if self.stop_time is None or \
                end - self.stop_time <= _masters_rounding(step_size, self.stop_time):
            return None
        return (f"doStep from t = {current_time:.16g} s by {step_size:.16g} s ends past the "
                f"experiment's stop time {self.stop_time:.16g} s ({self.API['setup']}); "
                "allowed: doSteps that end by it")

    def _advance(self, current_time, step_size):
        torques = (self.values["M_motor"], self.values["M_load"])
        budget = step_budget(step_size, self.stepper.fastest_rate, self.built_from["max_step"],
                             self.stepper.budget_per_mode)
        try:
            self.stepper.run_to(self.run, current_time + step_size, torques, max_steps=budget)
        except StepBudgetExceeded:
            self._fail(self._runaway_message(current_time, step_size, budget))
        except Exception as error:  # never let an exception reach the host unasked
            self._fail(f"doStep from t = {current_time:g} s by {step_size:g} s "
                       f"failed: {error}")

    def _runaway_message(self, current_time, step_size, budget):
        speed = self.stepper.model.named_outputs(self.run.outputs)["w_pinion"]
        max_step = self.built_from["max_step"]
        forced = (f" + {STEP_BUDGET_PER_MAX_STEP}·h/max_step, max_step = {max_step:g} s"
                  if 0.0 < max_step < math.inf else "")
        return (f"doStep from t = {current_time:g} s by {step_size:g} s failed: it took over "
                f"{budget} internal steps (the bound: {STEP_BUDGET_FLOOR} + "
                f"{self.stepper.budget_per_mode:.0f}·h·|λ|max, |λ|max = "
                f"{self.stepper.fastest_rate:.3g} "
                f"1/s{forced}) and stopped at t = {self.run.time:.9g} s with the pinion at "
                f"{speed:.3g} rad/s: the train runs away. Check the torques M_motor = "
                f"{self.values['M_motor']:g} N.m and M_load = {self.values['M_load']:g} N.m "
                f"(a runaway is most likely one far beyond the scene's, "
                f"{self.start_values['M_motor']:g} and {self.start_values['M_load']:g} N.m)")

    # --- get and set: never an exception, which pythonfmu(3) would make Fatal -----------------

    def _get_reals(self, vrs):
        # A master reads the same outputs after every doStep: they all sit in output_values,
        # taken by one numpy index of their entries, made for the last list asked for rather
        # than a getter or a lookup a variable (CHANGELOG has the figures)
        if not self.initialized:
            self._start_if_changed()
        asked = tuple(vrs)
        if asked != self.read_plan[0]:
            entries = self.real_output_entries
            if not all(vr in entries for vr in asked):
                return self._get(vrs, "real")
            self.read_plan = (asked, np.array([entries[vr] for vr in asked], dtype=np.intp))
        return self.output_values[self.read_plan[1]].tolist()

    def _get(self, vrs, kind):
        """The values of `vrs`; one that is not a `kind` variable reads REFUSED[kind] (NaN for a
        real) and is reported."""
        if not self.initialized:
            self._start_if_changed()
        values = []
        for vr in vrs:
            declaration = self._variable(vr, kind, "read")
            values.append(REFUSED[kind] if declaration is None
                          else CONVERT[kind](declaration.getter()))
        return values

    def _set_all(self, vrs, values, kind):
        """Set `vrs` to `values` in turn; after terminate, none (refused with a message)."""
        if self.mode not in CALLS["Set"][0]:  # the name made only then: hosts set every step
            return self._report(self._order_problem(
                "Set", f"Set{self.API['kinds'].get(kind, kind)}"))
        for vr, value in zip(vrs, values):
            declaration = self._variable(vr, kind, "set")
            if declaration is not None and declaration.setter is None:
                what = CAUSALITY_WORDS.get(declaration.causality, declaration.causality)
                self._report(f"{declaration.name} is {what}: it cannot be set; only parameters "
                             "(before initialization) and inputs can be")
            elif declaration is not None:
                declaration.setter(value)

    def _variable(self, vr, kind, verb):
        declaration = self.declared.get(vr)
        if declaration is None:
            self._report(f"no variable has value reference {vr}; cannot {verb} it "
                         f"(value references: 0 to {len(self.declared) - 1})")
        elif declaration.kind != kind:
            names, prefix = self.API["kinds"], self.API["prefix"]
            action = "Get" if verb == "read" else "Set"
            actual = names[declaration.kind]
            article = "an" if actual[0] in "AEIOU" else "a"
            self._report(f"{declaration.name} is {article} {actual} variable: {verb} it with "
                         f"{prefix}{action}{actual}, not "
                         f"{prefix}{action}{names.get(kind, kind)}")
            return None
        return declaration

    def _worked_out(self, name) -> bool:
        """Whether parameter `name` is one a scene works out from others where it is not given
        (a transverse inertia, J = m·(3R² + L²)/12: its default is None) and neither the
        scene file nor the host gave it: it then follows the mass and geometry the host set,
        as a scene's does."""
        parameter = PARAMETERS.get(name)
        return (parameter is not None and parameter.default is None
                and name not in self.scene.given
                and self.values[name] == self.start_values[name])

    def _value_taken(self, name):
        """A parameter's or input's value as the run takes it (`_worked_out`'s from the values
        set now; where they make no geometry, the start value)."""
        if not self._worked_out(name):
            return self.values[name]
        try:
            return solid_cylinder_transverse_inertia(self.values, name.removeprefix("J_"))
        except (ValueError, ZeroDivisionError, KeyError):
            return self.values[name]

    def _set(self, name, value):
        """A parameter's or input's new value; a fixed parameter only before initialization
        (it keeps the value it was initialized with, which a get then reads)."""
        if self.initialized and name not in INPUTS:
            self._report(f"{name} is a fixed parameter: it can be set only before "
                         f"exitInitializationMode; it keeps {self.values[name]!r} "
                         f"(refused: {value!r})")
            return
        self.values[name] = value

    # --- FMU state: plain data, so that it serializes (canSerializeFMUstate) ----------------

    def _get_fmu_state(self):
        """Everything the run goes on from, as JSON data: the position (floats exactly, by
        repr; the contact set by its cycle and interval), the steps taken, the values. Before
        initialization the run is first brought up to the values set, as a get of an output
        brings it: a state keeps a run with the values it was started from."""
        if not self.initialized:
            self._start_if_changed()
        state = {"format": STATE_FORMAT, "values": dict(self.values),
                 "start_time": self.start_time, "stop_time": self.stop_time, "mode": self.mode,
                 "experiment_tolerance": self.experiment_tolerance,
                 "problem": self.problem, "input_problem": self.input_problem, "run": None}
        if self.run is not None:
            position = self.stepper.position(self.run)
            contact_set = position.segment.contact_set
            state["run"] = {
                "time": position.time, "state": position.state.tolist(),
                "cycle": contact_set.cycle, "interval": contact_set.index,
                "loaded": position.segment.loaded.tolist(), "step_hint": position.step_hint,
                "outputs": position.outputs.tolist(),
                "first_steps": position.first_steps.tolist(),
                "internal_steps": self.stepper.accepted_steps,
                # the torques' static scales its tolerances and modal forms were taken in
                "stepper_inputs": {name: self.built_from[name] for name in INPUTS}}
        return state

    def _set_fmu_state(self, state):
        """A state of this FMU set (`_restore`); another is refused, the FMU keeping its own,
        and where the host does not hear the log the call raises (Fatal), as a doStep's
        problem does: a master must not go on as if it had rolled back."""
        if not self._own_state(state):
            refused = (f"{self.API['set_state']}: the state is not one of this FMU (expected "
                       f"{STATE_FORMAT} with this scene's variables); the FMU keeps its own")
            self._report(refused)
            if self.host_logs() is False:
                raise RuntimeError(refused)
            return None
        try:
            self._restore(state)
        except Exception as error:  # its own layout, numbers that are not this run's
            self.problem = None  # perhaps the state's: this one is what the user must hear
            self._fail(f"{self.API['set_state']}: the state could not be restored: {error!r}")

    def _own_state(self, state) -> bool:
        """Whether `state` has the layout `_get_fmu_state` gives, with this scene's
        variables."""
        if not (isinstance(state, dict) and state.get("format") == STATE_FORMAT
                and set(state) == STATE_KEYS and isinstance(state["values"], dict)
                and set(state["values"]) == set(self.values) and state["mode"] in MODE_WORDS):
            return False
        return state["run"] is None or (isinstance(state["run"], dict)
                                        and set(state["run"]) == RUN_STATE_KEYS)

    def _restore(self, state):
        """Take the values and the run of `state` (one of this FMU's)."""
        self.values = dict(state["values"])
        self.start_time, self.stop_time = state["start_time"], state["stop_time"]
        self.mode, self.experiment_tolerance = state["mode"], state["experiment_tolerance"]
        self.started_from = (dict(self.values), self.start_time)
        self.problem, self.input_problem = state["problem"], state["input_problem"]
        self.run = None
        self.output_values = np.zeros_like(self.output_values)
        saved = state["run"]
        if saved is None:
            return
        # the stepper the saved run was taken by: its values, its inputs when it was built
        inputs = saved["stepper_inputs"]
        if self.stepper is None or self.built_from != {**self.values, **inputs}:
            problem = self._build(inputs)
            if problem is not None:
                return self._fail(problem)
        self.run = self.stepper.start(self._position(saved))
        self.stepper.accepted_steps = saved["internal_steps"]
        self.output_values = self.run.outputs

    def _position(self, saved):
        contact_set = self.stepper.model.mesh.contact_set(saved["cycle"], saved["interval"])
        return Position(saved["time"], np.array(saved["state"]),
                        Segment(contact_set, np.array(saved["loaded"])), saved["step_hint"],
                        np.array(saved["outputs"]), np.array(saved["first_steps"]))

    @staticmethod
    def _fmu_state_to_bytes(state):
        # sorted keys and floats by repr: the same state is the same bytes, and reads back
        # bit-identical (NaN and infinities as JSON's extensions NaN, Infinity)
        return json.dumps(state, sort_keys=True, separators=(",", ":")).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(data):
        try:
            return json.loads(data.decode("utf-8"))
        except ValueError:
            return None  # _set_fmu_state reports it

    # --- the model behind it -----------------------------------------------------------------

    def _start_if_changed(self):
        """_start, unless the run was started from the values and start time as they are now
        (and its problems, if any, reported): before initialization the outputs follow what the
        host sets, as the FMI standard asks of outputs read in initialization mode."""
        if self.started_from != (self.values, self.start_time):
            self._start()

    def _start(self):
        """Validate the values and place the train in its initial state (docs/model.md section 6)
        at the start time. An input torque that is not valid holds the start back, not the
        instance: the static deflection it starts from is the torque's, so the run starts at
        the first doStep whose inputs are valid (_step), from the start time."""
        self.started_from = (dict(self.values), self.start_time)
        self.problem, self.run = None, None
        input_problem = self._input_problem()
        if input_problem is not None:
            if input_problem != self.input_problem:
                self._report(input_problem)
            self.input_problem = input_problem
            self.output_values = np.full_like(self.output_values, math.nan)
            return
        self.input_problem = None
        problem = self._check_values() or self._build_if_changed()
        if problem is not None:
            return self._fail(problem)
        note = max_step_note(self.values["max_step"])
        if note is not None:
            self._report(note, WARNING)
        try:
            position = dataclasses.replace(
                start_position(self.stepper.model, self.values["M_motor"]), time=self.start_time)
            warm_up(self.stepper, position)  # a compile says so itself (first_start)
            self.run = self.stepper.start(position)
            self.output_values = self.run.outputs  # updated in place by every doStep
        except Exception as error:
            self._fail(f"initialization failed: {error}")

    def _input_problem(self):
        """The first input torque that is not valid, as its message, or None."""
        problems = ((name, check_value(p, self.values[name])) for name, p in INPUTS.items())
        return next((f"input {name} {problem}" for name, problem in problems if problem), None)

    def _check_values(self):
        """The first problem of the solver settings (the scene checks the model's parameters,
        `_input_problem` the inputs), or None."""
        problems = ((name, self._check_solver_setting(name, self.values[name]))
                    for name in SOLVER_SETTINGS)
        return next((f"{name} {problem}" for name, problem in problems if problem), None)

    def _build_if_changed(self):
        """_build, unless the stepper was built from the values as they are now: the one built
        at instantiation, for the outputs before initialization, serves the run where the host
        changed nothing (docs/integrator.md, First start, says what that saves), its count of
        steps set back to 0 as a new one's. Returns what _build returns."""
        if self.stepper is not None and self.built_from == self.values:
            self.stepper.accepted_steps = 0
            return None
        return self._build()

    def _build(self, inputs=None):
        """Model and stepper of the current values, with the input torques `inputs` ({name:
        N·m}; None: the current ones), whose static scales the stepper's tolerances and modal
        forms are taken in; returns what is wrong with them, or None."""
        built_from = {**self.values, **(inputs or {})}
        try:
            given = {k: v for k, v in built_from.items()
                     if k in self.scene.parameters and not self._worked_out(k)}
            scene = self.scene.with_parameters(**given).with_inputs(
                M_motor=built_from["M_motor"], M_load=built_from["M_load"])
            self.stepper = CompiledStepper(GearTrainModel(scene), built_from["solver_tolerance"],
                                           method=built_from["solver_method"],
                                           max_step=built_from["max_step"] or math.inf)
            self.latest_end = latest_end(self.stepper.fastest_rate)
            self.built_from = built_from
        except herringbone.SceneError as error:
            # the scene's own words, without its file: the FMU's variables are the parameters
            where = ("parameter " if error.table == "parameters" else
                     "" if error.table is None else f"[{error.table}] ")
            return where + error.problem
        except Exception as error:
            return f"initialization failed: {error}"
        return None

    def _apply_experiment_tolerance(self):
        """The experiment's tolerance (FMI 2.0: fmi2SetupExperiment's) becomes solver_tolerance
        (both are relative errors per step), unless the host set solver_tolerance to other than
        its start value; one outside solver_tolerance's range is clamped into it, with a
        warning."""
        tolerance = self.experiment_tolerance
        if tolerance is None or \
                self.values["solver_tolerance"] != self.start_values["solver_tolerance"]:
            return
        if not (isinstance(tolerance, float) and tolerance > 0.0 and math.isfinite(tolerance)):
            return self._report(f"{self.API['setup']}: tolerance {tolerance!r} is not a "
                                "positive number; solver_tolerance keeps its value",
                                WARNING)
        allowed = FMU_SOLVER_TOLERANCE.allowed
        used = min(max(tolerance, allowed.low), allowed.high)
        if used != tolerance:
            self._report(f"{self.API['setup']}: tolerance {tolerance:g} is outside "
                         f"solver_tolerance's range {allowed.describe()}; using {used:g}",
                         WARNING)
        self.values["solver_tolerance"] = used

    @staticmethod
    def _check_solver_setting(name, value):
        """Why a solver setting's value is not allowed, or None (ranges: arguments.py)."""
        return {"solver_tolerance": FMU_SOLVER_TOLERANCE, "max_step": FMU_MAX_STEP,
                "solver_method": FMU_SOLVER_METHOD}[name].problem(value)

    # --- how problems reach the user -----------------------------------------------------------

    def _fail(self, message):
        """A problem that stops the run for good: reported once. Without a run the outputs
        read NaN, not the values of an earlier start that look plausible."""
        if self.problem is None:
            self.problem = message
            self._report(message)
        if self.run is None:
            self.output_values = np.full_like(self.output_values, math.nan)

    def _report(self, message, status=ERROR):
        """Log `message`; also on stderr unless the host is known to hear the log."""
        # hosts format log messages printf-style: a bare '%' crashes them
        self._log(f"{self.instance_name}: {message}".replace("%", "%%"), status)
        if self.host_logs(status) is not True:
            print(f"{self.instance_name}: {STATUS_NAMES[status]}: {message}", file=sys.stderr,
                  flush=True)

    def _raise_if_unheard(self):
        """Where the host does not hear the log, a problem is an exception: pythonfmu makes it
        Fatal, which fmpy raises (FMICallException) where a Discard would end its run
        silently."""
        problem = self.problem or self.input_problem
        if problem is not None and self.host_logs() is False:
            raise RuntimeError(problem)

    # --- what an adapter provides --------------------------------------------------------------

    def _register(self, declaration) -> int:
        raise NotImplementedError

    def _log(self, text, status):
        raise NotImplementedError

    def host_logs(self, status=ERROR):
        """Whether the host hears this instance's log messages of `status`: True, False, or
        None (not known)."""
        return None
