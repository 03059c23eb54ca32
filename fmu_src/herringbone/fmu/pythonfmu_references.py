"""The Python references pythonfmu 0.7's C++ side releases once too often, and the balance the
FMI 2.0 slave restores. Without it a Python host (fmpy) aborted at exit with "corrupted
double-linked list" in 403 of 1058 runs of the reference scene, 16 at a time on a 16-core
machine (8 of 174 in another batch; once in CI), and 2 in 27 runs of a process that freed
three instances after a Fatal call each: memory freed while still in use, and freed again as
the interpreter tears the slave's module down.

pythonfmu 0.7 (src/pythonfmu/PySlaveInstance.cpp):

- `findClass`, run once per fmi2Instantiate, ends with `Py_DECREF(pGlobals)`, where `pGlobals`
  is the slave module's dictionary as PyModule_GetDict lends it (a borrowed reference). Each
  instance so takes one reference from that dictionary that nothing had given
  (`BalancedSlave.__init__`); measured: sys.getrefcount of the module's __dict__ falls one
  further below the references to it that the garbage collector finds with every instance.
- `handle_py_exception`, run when a callback raises (fmi2Fatal), releases the class, the
  instance and its log queue, and leaves the pointers in place; the instance's destructor,
  run by fmi2FreeInstance, releases the three again (`BalancedSlave._balance_fatal`).

`BalancedSlave`, first among a slave's bases, takes one reference for each one pythonfmu will
release without owning it: only under pythonfmu 0.7 and only in an FMU (where pythonfmu's C++
side passes a logger); a later pythonfmu that no longer over-releases would at worst keep these
objects until exit. A classmethod that raises (pythonfmu's `_fmu_state_from_bytes` and
`_fmu_state_to_bytes`, called on the class) is not balanced: it has no instance to name.

builder.build_slave_fmu ships this module with every FMI 2.0 FMU as the module
`pythonfmu_references` (the example slaves import it so), as it ships `fmi_units`.
"""
from __future__ import annotations

import ctypes
import functools
import sys
from collections.abc import Callable
from typing import Any

_incref = ctypes.pythonapi.Py_IncRef
_incref.argtypes = (ctypes.py_object,)
_incref.restype = None

# the instance methods pythonfmu 0.7 calls, each ending in handle_py_exception if it raises
CALLBACKS = ("setup_experiment", "enter_initialization_mode", "exit_initialization_mode",
             "do_step", "terminate", "get_real", "get_integer", "get_boolean", "get_string",
             "set_real", "set_integer", "set_boolean", "set_string", "_get_fmu_state",
             "_set_fmu_state")


def affected(logger_address: int | None) -> bool:
    """Whether a slave runs under pythonfmu 0.7's C++ side (in an FMU: the `logger` it passes
    is set), whose releases these balance."""
    import pythonfmu

    return bool(logger_address) and pythonfmu.__version__.startswith("0.7.")


class BalancedSlave:
    """A mixin for a pythonfmu 0.7 Fmi2Slave, listed before Fmi2Slave among its bases: gives
    back the slave module's reference at every instantiation, and those of the class, the
    instance and its log queue before an exception leaves one of its CALLBACKS."""

    def __init__(self, **kwargs: Any) -> None:
        """Balance findClass's release of the module's dictionary (it has run by now), then
        go on with the next base's __init__."""
        self._pythonfmu_affected = affected(kwargs.get("logger"))
        if self._pythonfmu_affected:
            _incref(sys.modules[type(self).__module__].__dict__)
        super().__init__(**kwargs)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Wrap each callback the subclass defines or inherits unwrapped."""
        super().__init_subclass__(**kwargs)
        for name in CALLBACKS:
            method = getattr(cls, name, None)
            if method is not None and not getattr(method, "balances_references", False):
                setattr(cls, name, _balanced(method))

    def _balance_fatal(self) -> None:
        """One reference each to the class, the instance and its log queue, for the second
        release at fmi2FreeInstance."""
        for owned in (type(self), self, self._get_log_queue()):  # type: ignore[attr-defined]
            _incref(owned)


def _balanced(method: Callable) -> Callable:
    @functools.wraps(method)
    def call(self, *args, **kwargs):
        try:
            return method(self, *args, **kwargs)
        except BaseException as error:
            # once per exception: an override that calls a wrapped super() sees it twice
            if getattr(self, "_pythonfmu_affected", False) \
                    and not getattr(error, "references_balanced", False):
                error.references_balanced = True  # type: ignore[attr-defined]
                self._balance_fatal()
            raise

    call.balances_references = True  # type: ignore[attr-defined]
    return call
