"""The gear train as an FMI 2.0 co-simulation slave: pythonfmu's Fmi2Slave over the
version-independent core (fmu/core.py), which holds the slave's logic and its variables' table.

How errors reach the host (README "Errors in each host"): pythonfmu 0.7 can answer a call
only with fmi2OK, fmi2Discard (do_step returning False) or fmi2Fatal (any Python exception,
which also destroys the instance), and passes log messages on only when the host enabled
logging. So a problem is logged once at error status; where the host did not enable logging it
is also written to the process's stderr and the call that meets it raises (fmi2Fatal: fmpy
raises FMICallException). Where the host logs (libcosim always does, and a Fatal aborts it)
nothing raises: doStep answers fmi2Discard while the problem lasts. A call that cannot be
honoured but harms nothing (setting an output, or a fixed parameter after initialization;
reading a variable through the wrong type) is refused with a message and answered fmi2OK:
pythonfmu has no fmi2Error to give.
"""
# first: the core checks the dependencies before anything imports numpy
from herringbone.fmu.core import DESCRIPTION, GearCore
from herringbone.fmu.core import (SOLVER_SETTINGS, STEP_BUDGET_FLOOR,  # noqa: F401
                                  STEP_BUDGET_PER_MODE, STATE_FORMAT)

from pythonfmu import (DefaultExperiment, Fmi2Causality, Fmi2Slave, Fmi2Variability, Boolean,
                       String)
from pythonfmu.enums import Fmi2Status

from herringbone.fmu import pythonfmu_logger
from herringbone.fmu.units import BoundedInteger, RealWithUnit


class HerringboneGear(GearCore, Fmi2Slave):
    description = DESCRIPTION

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.logger_address = kwargs.get("logger")  # pythonfmu's C++ PyLogger (see host_logs)
        self._setup(kwargs.get("logger"))
        experiment = self.scene.experiment
        type(self).default_experiment = DefaultExperiment(
            start_time=0.0, stop_time=experiment.stop_time,
            step_size=experiment.output_interval)

    def _register(self, declaration):
        arguments = dict(description=declaration.description,
                         causality=Fmi2Causality[declaration.causality],
                         variability=Fmi2Variability[declaration.variability],
                         getter=declaration.getter, setter=declaration.setter)
        if declaration.kind in ("real", "integer"):
            arguments.update(min=declaration.low, max=declaration.high)
        if declaration.kind == "real":
            variable = RealWithUnit(declaration.name, unit=declaration.unit, **arguments)
        else:
            kind = {"integer": BoundedInteger, "boolean": Boolean, "string": String}
            variable = kind[declaration.kind](declaration.name, **arguments)
        self.register_variable(variable)
        return variable.value_reference

    def _log(self, text, status):
        self.log(text, Fmi2Status(status))

    # --- FMI callbacks -----------------------------------------------------------------------

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._set_experiment(start_time, tolerance)

    def exit_initialization_mode(self):
        self._exit_initialization()
        self._raise_if_unheard()

    def do_step(self, current_time, step_size):
        if self._step(current_time, step_size) is not None:
            self._raise_if_unheard()
            return False
        return True

    def get_real(self, vrs):
        return self._get_reals(vrs)

    def get_integer(self, vrs):
        return self._get(vrs, "integer")

    def get_boolean(self, vrs):
        return self._get(vrs, "boolean")

    def get_string(self, vrs):
        return self._get(vrs, "string")

    def set_real(self, vrs, values):
        self._set_all(vrs, values, "real")

    def set_integer(self, vrs, values):
        self._set_all(vrs, values, "integer")

    def set_boolean(self, vrs, values):
        self._set_all(vrs, values, "boolean")

    def set_string(self, vrs, values):
        self._set_all(vrs, values, "string")

    def host_logs(self):
        """Whether pythonfmu passes this instance's log messages to the host: it does not tell
        the slave, so this reads its logger (fmu.pythonfmu_logger); None where not known."""
        return pythonfmu_logger.logging_on(self.logger_address, self.instance_name)
