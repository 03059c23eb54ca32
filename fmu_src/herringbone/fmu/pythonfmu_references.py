"""The Python references pythonfmu 0.7's C++ side releases once too often, and the balance the
FMI 2.0 slave restores. Without it a Python host (fmpy) aborted at exit with "corrupted
double-linked list" in 403 of 1058 runs of the reference scene, 16 at a time on a 16-core
machine (8 of 174 in another batch; once in CI), and at every run that freed an instance after
a Fatal call: memory freed while still in use, and freed again as the interpreter tears the
slave's module down.

pythonfmu 0.7 (src/pythonfmu/PySlaveInstance.cpp):

- `findClass`, run once per fmi2Instantiate, ends with `Py_DECREF(pGlobals)`, where `pGlobals`
  is the slave module's dictionary as PyModule_GetDict lends it (a borrowed reference). Each
  instance so takes one reference from that dictionary that nothing had given
  (`balance_instantiation`); measured: sys.getrefcount of the module's __dict__ falls one
  further below the references to it that the garbage collector finds with every instance.
- `handle_py_exception`, run when a callback raises (fmi2Fatal), releases the class, the
  instance and its log queue, and leaves the pointers in place; the instance's destructor,
  run by fmi2FreeInstance, releases the three again (`balance_fatal`).

Each balance takes one reference for each one pythonfmu will release without owning it. Only
under pythonfmu 0.7 and only in an FMU (where pythonfmu's C++ side passes a logger); a later
pythonfmu that no longer over-releases would at worst keep these objects until exit.
"""
from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable
from typing import Any

_incref = ctypes.pythonapi.Py_IncRef
_incref.argtypes = (ctypes.py_object,)
_incref.restype = None


def affected(logger_address: int | None) -> bool:
    """Whether this slave runs under pythonfmu 0.7's C++ side (in an FMU: the `logger` it
    passes is set), whose releases these balance."""
    import pythonfmu

    return bool(logger_address) and pythonfmu.__version__.startswith("0.7.")


def balance_instantiation(module_globals: dict) -> None:
    """Give back the reference findClass took from the slave module's dictionary: call once
    per instance, from the slave's constructor (findClass has run by then)."""
    _incref(module_globals)


def balance_fatal(slave: Any) -> None:
    """Before an exception leaves a callback of `slave`: one reference each to the class, the
    instance and its log queue, for the second release at fmi2FreeInstance."""
    for owned in (type(slave), slave, slave._get_log_queue()):
        _incref(owned)


# the instance methods pythonfmu 0.7 calls, each ending in handle_py_exception if it raises
CALLBACKS = ("setup_experiment", "enter_initialization_mode", "exit_initialization_mode",
             "do_step", "terminate", "get_real", "get_integer", "get_boolean", "get_string",
             "set_real", "set_integer", "set_boolean", "set_string", "_get_fmu_state",
             "_set_fmu_state")


def balanced_callbacks(cls: type) -> type:
    """Class decorator: each of the slave's CALLBACKS balances the references before an
    exception leaves it (where `affected`)."""
    for name in CALLBACKS:
        setattr(cls, name, _balanced(getattr(cls, name)))
    return cls


def _balanced(method: Callable) -> Callable:
    @functools.wraps(method)
    def call(self, *args, **kwargs):
        try:
            return method(self, *args, **kwargs)
        except BaseException:
            if affected(getattr(self, "logger_address", None)):
                balance_fatal(self)
            raise

    return call
