"""The gear train as an FMI 2.0 co-simulation slave: pythonfmu's Fmi2Slave over the
version-independent core (fmu/core.py), which holds the slave's logic and its variables' table.

How errors reach the host (docs/hosts.md, "Errors in each host"): pythonfmu 0.7 can answer a
call only with fmi2OK, fmi2Discard (do_step returning False) or fmi2Fatal (any Python
exception, after which the standard allows no call), and passes log messages on only when the
host enabled logging, in the categories it named. So a problem is logged once at error status;
where the host does not hear it (_category) it is also written to the process's stderr and the
call that meets it raises (fmi2Fatal: fmpy raises FMICallException). Where the host logs
(libcosim always does, and a Fatal aborts it) nothing raises: doStep answers fmi2Discard while
the problem lasts. A call that cannot be honoured but harms nothing (setting an output, or a
fixed parameter after initialization; reading a variable through the wrong type) is refused
with a message and answered fmi2OK: pythonfmu has no fmi2Error to give.
"""
from typing import Any

# before pythonfmu: the core checks the dependencies (herringbone.fmu.runtime) before anything
# imports numpy; `isort: split` keeps it there
from herringbone.fmu.core import DESCRIPTION, ERROR, Declaration, GearCore

# isort: split
from pythonfmu import Boolean, DefaultExperiment, Fmi2Causality, Fmi2Slave, Fmi2Variability, String
from pythonfmu.enums import Fmi2Status

from herringbone.fmu import pythonfmu_logger
from herringbone.fmu.pythonfmu_references import BalancedSlave
from herringbone.fmu.units import BoundedInteger, RealWithUnit


class HerringboneGear(BalancedSlave, GearCore, Fmi2Slave):
    """The gear FMU's FMI 2.0 slave: GearCore's logic behind pythonfmu's callbacks. Values
    cross in the units the variables declare (SI: the model description's <UnitDefinitions>);
    value references are those `_register` hands out."""

    description = DESCRIPTION

    def __init__(self, **kwargs: Any) -> None:
        """pythonfmu's instantiation (instance_name, resources, logger, ...): load the scene
        from the resources and declare its variables; the scene's experiment becomes the
        default experiment."""
        super().__init__(**kwargs)
        self.logger_address = kwargs.get("logger")  # pythonfmu's C++ PyLogger (see host_logs)
        self._setup(kwargs.get("logger"))
        experiment = self.scene.experiment
        type(self).default_experiment = DefaultExperiment(
            start_time=0.0, stop_time=experiment.stop_time,
            step_size=experiment.output_interval)

    def _register(self, declaration: Declaration) -> int:
        """Declare `declaration` as a pythonfmu variable (a Real with its unit and range, an
        Integer with its range, a Boolean or a String); returns its value reference."""
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

    def _log(self, text: str, status: int) -> None:
        """Queue `text` with pythonfmu's logger at `status` (an fmi2Status value), in the
        category the host hears it in (_category)."""
        self.log(text, Fmi2Status(status), self._category(status)[0])

    def _category(self, status: int) -> tuple[str, bool | None]:
        """The log category for a message of `status`, and whether the host hears it there
        (None: not known): the status's own (logStatusError, ...), or logAll where the host
        enabled only that. pythonfmu passes a message only in a category the host named in
        fmi2SetDebugLogging, matched by name, and the model description declares logAll as
        every message."""
        own = f"logStatus{Fmi2Status(status).name.capitalize()}"
        if own not in self.log_categories:
            own = "logAll"
        heard = pythonfmu_logger.hears(self.logger_address, self.instance_name, own)
        if heard is False and pythonfmu_logger.hears(self.logger_address, self.instance_name,
                                                     "logAll"):
            return "logAll", True
        return own, heard

    # --- FMI callbacks: times in s, values in the variables' units ---------------------------

    def setup_experiment(self, start_time: float, stop_time: float | None = None,
                         tolerance: float | None = None) -> None:
        """fmi2SetupExperiment: the run starts at `start_time`, and a doStep that would end
        past `stop_time` is refused; a `tolerance` takes the place of solver_tolerance unless
        the host set that itself (GearCore._set_experiment)."""
        self._set_experiment(start_time, tolerance, stop_time)

    def enter_initialization_mode(self) -> None:
        """fmi2EnterInitializationMode: refused with a message where it may not come."""
        self._enter_initialization()

    def exit_initialization_mode(self) -> None:
        """fmi2ExitInitializationMode: check the parameters and build the model; a problem
        raises (fmi2Fatal) only where the host does not hear the log."""
        self._exit_initialization()
        self._raise_if_unheard()

    def do_step(self, current_time: float, step_size: float) -> bool:
        """fmi2DoStep: advance from `current_time` by `step_size`; False (fmi2Discard) on a
        problem, which raises instead (fmi2Fatal) where the host does not hear the log."""
        if self._step(current_time, step_size) is not None:
            self._raise_if_unheard()
            return False
        return True

    def terminate(self) -> None:
        """fmi2Terminate: the run ends (doSteps and sets are refused after it)."""
        self._terminate()

    def get_real(self, vrs: list[int]) -> list[float]:
        """fmi2GetReal: the values of `vrs` (NaN, reported, for one that is not a Real)."""
        return self._get_reals(vrs)

    def get_integer(self, vrs: list[int]) -> list[int]:
        """fmi2GetInteger: the values of `vrs` (see core.REFUSED for one that is not one)."""
        return self._get(vrs, "integer")

    def get_boolean(self, vrs: list[int]) -> list[bool]:
        """fmi2GetBoolean: the values of `vrs` (see core.REFUSED for one that is not one)."""
        return self._get(vrs, "boolean")

    def get_string(self, vrs: list[int]) -> list[str]:
        """fmi2GetString: the values of `vrs` (see core.REFUSED for one that is not one)."""
        return self._get(vrs, "string")

    def set_real(self, vrs: list[int], values: list[float]) -> None:
        """fmi2SetReal: set `vrs` to `values`; what cannot be set is refused with a message."""
        self._set_all(vrs, values, "real")

    def set_integer(self, vrs: list[int], values: list[int]) -> None:
        """fmi2SetInteger: as set_real."""
        self._set_all(vrs, values, "integer")

    def set_boolean(self, vrs: list[int], values: list[bool]) -> None:
        """fmi2SetBoolean: as set_real."""
        self._set_all(vrs, values, "boolean")

    def set_string(self, vrs: list[int], values: list[str]) -> None:
        """fmi2SetString: as set_real."""
        self._set_all(vrs, values, "string")

    def host_logs(self, status: int = ERROR) -> bool | None:
        """Whether pythonfmu passes this instance's log messages of `status` to the host: it
        does not tell the slave, so this reads its logger (fmu.pythonfmu_logger), with the
        categories the host enabled; None where not known."""
        return self._category(status)[1]
