"""The gear train as an FMI 3.0 co-simulation slave: pythonfmu3's Fmi3Slave over the
version-independent core (fmu/core.py), the same one as the FMI 2.0 slave (fmu/slave.py): the
same variables from the same table, the same checks, messages, run and state.

What pythonfmu3 (0.3) lets a slave do, and what differs from the FMI 2.0 slave because of it
(README, "Errors in each host"):
- doStep can answer any status: a problem (of the parameters, the inputs, the solver, a
  runaway) makes it answer fmi3Error, and the instance lives on (a problem of the inputs clears
  once they are valid; fmi3SetFMUState rolls back). The FMI 2.0 slave answers fmi2Discard, or
  fmi2Fatal where the host does not log: pythonfmu has no fmi2Error.
- Every other callback answers fmi3OK, or fmi3Fatal for a Python exception (which destroys the
  instance): exitInitializationMode with a problem raises only where the host has no log
  callback, as the FMI 2.0 slave does where the host does not log; otherwise the problem is
  logged and the first doStep answers fmi3Error.
- pythonfmu3 passes every message to the host's log callback, whatever loggingOn says (which
  only gates debug messages), so a message is written to stderr as well only where the host
  gave no callback (fmpy gives one by default and prints the messages).
- fmi3EnterInitializationMode's startTime, stopTime and tolerance do not reach the slave. The
  run starts where the host's first doStep starts it (FMI 3.0 requires that to be the start
  time), and the experiment's tolerance is not used: set solver_tolerance instead.
"""
import ctypes
import sys

import pythonfmu3
from pythonfmu3 import (
    Boolean,
    DefaultExperiment,
    Float64,
    Fmi3Causality,
    Fmi3Slave,
    Fmi3Variability,
    Int32,
    String,
)
from pythonfmu3.enums import Fmi3Status
from pythonfmu3.fmi3slave import Fmi3StepResult

# first: the core checks the dependencies before anything imports numpy
from herringbone.fmu.core import DESCRIPTION, Declaration, GearCore
from herringbone.fmu.pythonfmu_references import tear_down_state_first


# The callback pythonfmu3 0.3.4 logs through (cppfmu's Logger, `host_logs`) where the host gave
# none: FMI 3.0 lets a host pass logMessage = NULL, and pythonfmu3 calls it unchecked with every
# message and with the message of every exception (fmi_functions.cpp), a segmentation fault.
# The slave writes its own messages to stderr where the host hears none (core._report); this
# one writes the rest, which are pythonfmu3's account of an exception (answered fmi3Fatal).
@ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)
def _log_unheard(environment, status, category, message):
    if status == Fmi3Status.fatal:
        text = (message or b"").decode("utf-8", "replace").replace("\n", "; ")
        print(f"HerringboneGear: fatal: {text}", file=sys.stderr, flush=True)


def _logger_callback(logger_address) -> ctypes.c_void_p:
    """The log callback field of cppfmu's Logger at `logger_address` (pythonfmu3 0.3.4: the
    instance environment, then the callback; cppfmu_common.hpp)."""
    return ctypes.c_void_p.from_address(logger_address + ctypes.sizeof(ctypes.c_void_p))


def _with_range(node, low, high, start=None):
    for attribute, bound in (("min", low), ("max", high)):
        if bound is not None:
            node.set(attribute, repr(bound))
    if start is not None:
        node.set("start", repr(start))  # every bit (pythonfmu3 writes 16 digits)
    return node


class RangedFloat64(Float64):
    """A Float64 with `min`/`max` where given, and its start value written exactly."""

    def __init__(self, name, *, low=None, high=None, **kwargs):
        super().__init__(name, **kwargs)
        self.low, self.high = low, high

    def to_xml(self):
        """pythonfmu3's element, with the range and an exact (repr) start value."""
        start = None if self.start is None else float(self.start)
        return _with_range(super().to_xml(), self.low, self.high, start)


class RangedInt32(Int32):
    """An Int32 with `min`/`max` where given."""

    def __init__(self, name, *, low=None, high=None, **kwargs):
        super().__init__(name, **kwargs)
        self.low, self.high = low, high

    def to_xml(self):
        """pythonfmu3's element, with the range."""
        return _with_range(super().to_xml(), self.low, self.high)


class HerringboneGear(GearCore, Fmi3Slave):
    """The gear train as an FMI 3.0 co-simulation slave (pythonfmu3): GearCore's variables,
    solver and checks behind pythonfmu3's callbacks; value references equal the FMI 2.0
    FMU's, with the independent variable `time` declared last."""

    API = {"prefix": "fmi3", "set_state": "fmi3SetFMUState",
           "setup": "fmi3EnterInitializationMode",
           "kinds": {"real": "Float64", "integer": "Int32", "boolean": "Boolean",
                     "string": "String", "int64": "Int64"}}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.description = DESCRIPTION  # Fmi3SlaveBase.__init__ sets it (to None)
        self.logger_address = kwargs.get("logger")  # cppfmu's Logger (see host_logs)
        # pythonfmu3 does not pass fmi3EnterInitializationMode's startTime on: the first doStep
        # of the instance sets it (fmi3Reset makes a new instance)
        self.start_open = True
        self.host_gave_no_logger = False
        if self.logger_address:  # in an FMU: pythonfmu3's library shares pythonfmu's teardown
            tear_down_state_first(kwargs.get("resources"))
            stand_in = ctypes.cast(_log_unheard, ctypes.c_void_p).value
            # fmi3Reset makes a new slave over the same Logger, whose callback is the stand-in
            # an earlier one put there
            if pythonfmu3.__version__ == "0.3.4" \
                    and _logger_callback(self.logger_address).value in (None, stand_in):
                _logger_callback(self.logger_address).value = stand_in
                self.host_gave_no_logger = True
        # pythonfmu3's logger is not pythonfmu's: no direct line to it while compiling
        self._setup(None)
        # FMI 3.0 wants the independent variable declared: last, so that every other variable
        # has the value reference it has in the FMI 2.0 FMU
        time = Declaration("time", "real", "independent", "continuous", "simulation time",
                           getter=lambda: self.run.time if self.run else self.start_time,
                           unit="s")
        self.declared[self._register(time)] = time
        experiment = self.scene.experiment
        self.default_experiment = DefaultExperiment(
            start_time=0.0, stop_time=experiment.stop_time,
            step_size=experiment.output_interval)

    def _register(self, declaration):
        arguments = dict(description=declaration.description,
                         causality=Fmi3Causality[declaration.causality],
                         variability=Fmi3Variability[declaration.variability],
                         getter=declaration.getter, setter=declaration.setter)
        if declaration.kind == "real":
            variable = RangedFloat64(declaration.name, unit=declaration.unit or None,
                                     low=declaration.low, high=declaration.high, **arguments)
        elif declaration.kind == "integer":
            variable = RangedInt32(declaration.name, low=declaration.low,
                                   high=declaration.high, **arguments)
        else:
            kind = {"boolean": Boolean, "string": String}[declaration.kind]
            variable = kind(declaration.name, **arguments)
        self.register_variable(variable, nested=False)
        return variable.value_reference

    def _log(self, text, status):
        self.log(text, Fmi3Status(status))

    # --- FMI callbacks -----------------------------------------------------------------------

    def enter_initialization_mode(self):
        """fmi3EnterInitializationMode: refused with a message where it may not come."""
        self._enter_initialization()

    def exit_initialization_mode(self):
        """Start the run from the values set in initialization mode (fmi3ExitInitializationMode);
        a refused value or start raises, after the message has reached the host."""
        self._exit_initialization()
        self._raise_if_unheard()

    def do_step(self, current_time, step_size):
        """Advance from `current_time` by `step_size` seconds with the inputs held
        (fmi3DoStep); a failed step answers Error with the reason in the log."""
        if self.start_open and self.run is not None and self.run.time == self.start_time \
                and self.stepper.accepted_steps == 0:
            # no step taken yet: the start time pythonfmu3 did not pass on is this one
            self.start_time = float(current_time)
            self.run.clock[0] = self.start_time
        # once set, it stays, also where a state taken before the first step is set again
        self.start_open = self.start_open and self.run is None
        if self._step(current_time, step_size) is not None:
            return Fmi3StepResult(status=Fmi3Status.error)
        return Fmi3StepResult()

    def terminate(self):
        """fmi3Terminate: the run ends (doSteps and sets are refused after it)."""
        self._terminate()

    def get_float64(self, vrs):
        """Values of the Float64 variables `vrs` (outputs, inputs, parameters, time)."""
        return self._get_reals(vrs)

    def get_int32(self, vrs):
        """Values of the Int32 variables `vrs`."""
        return self._get(vrs, "integer")

    def get_int64(self, vrs):
        """There are no Int64 variables: any reference is refused with a message."""
        return self._get(vrs, "int64")  # none: refused with a message, not a Fatal

    def get_boolean(self, vrs):
        """Values of the Boolean variables `vrs`."""
        return self._get(vrs, "boolean")

    def get_string(self, vrs):
        """Values of the String variables `vrs`."""
        return self._get(vrs, "string")

    def set_float64(self, vrs, values):
        """Set Float64 variables in turn; one that cannot be set (an output, a fixed parameter
        after initialization, a value out of its range) is refused with an Error message."""
        self._set_all(vrs, values, "real")

    def set_int32(self, vrs, values):
        """Set Int32 variables, checked as set_float64's."""
        self._set_all(vrs, values, "integer")

    def set_int64(self, vrs, values):
        """There are no Int64 variables: refused with a message."""
        self._set_all(vrs, values, "int64")

    def set_boolean(self, vrs, values):
        """Set Boolean variables, checked as set_float64's."""
        self._set_all(vrs, values, "boolean")

    def set_string(self, vrs, values):
        """Set String variables, checked as set_float64's."""
        self._set_all(vrs, values, "string")

    def host_logs(self, status=None):
        """Whether the host gave a log callback, which pythonfmu3 calls with every message
        (not only when loggingOn): read from cppfmu's Logger, whose address pythonfmu3 hands to
        the slave (the instance environment, then the callback: cppfmu_common.hpp). None (not
        known) for another pythonfmu3 version or without a logger (outside an FMU); the
        same for every `status`. Where the host gave none, the slave put _log_unheard in its
        place when it was instantiated."""
        if not self.logger_address or pythonfmu3.__version__ != "0.3.4":
            return None
        return not self.host_gave_no_logger
