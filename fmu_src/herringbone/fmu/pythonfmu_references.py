"""What pythonfmu 0.7's C++ side gets wrong about memory, and the repairs a slave makes from
Python (docs/known-issues.md has the whole story and a reproducer).

1. **Its teardown at exit releases freed memory** (pythonfmu 0.7, and pythonfmu3 0.3.4 alike,
   src/pythonfmu/PySlaveInstance.cpp): the library keeps its Python state in a global
   `std::shared_ptr` and resets that global from an `__attribute__((destructor))` function,
   `onLibraryUnload`. The library is never unloaded (its std::regex code has GNU-unique
   symbols, which make dlclose a no-op), so both run at the host's exit(), in this order: the
   C library runs the global's destructor among the exit handlers, which frees the state's
   block, and afterwards, from _dl_fini, the destructor function assigns to the destroyed
   global, releasing the freed block again (valgrind: "Invalid read ... in
   finalizePythonInterpreter ... inside a block of size 128 free'd ... by __run_exit_handlers").
   That write into freed memory is harmless while glibc keeps the block in its thread cache and
   corrupts the heap's lists when it does not: "corrupted double-linked list", exit status 134,
   in about 1 process in 200 of every host, after all the work is done.
   **Repair** (`tear_down_state_first`): register the library's own exported teardown,
   `finalizePythonInterpreter`, with the exit handlers once the library is loaded; handlers
   run in reverse order of registration, so it runs first and releases the state through the
   live global, and the destructor and the destructor function then find it empty. In a C host
   the same call finalizes the Python that pythonfmu started, while the C++ libraries Python
   loaded (LLVM in llvmlite, scipy's) are still intact, instead of after their destructors.

2. **References released once too often** (pythonfmu 0.7 only), which made a Python host abort
   at exit in 403 of 1058 runs, 16 at a time:

   - `findClass`, run once per fmi2Instantiate, ends with `Py_DECREF(pGlobals)`, where
     `pGlobals` is the slave module's dictionary as PyModule_GetDict lends it (a borrowed
     reference). Each instance so takes one reference from that dictionary that nothing had
     given (`BalancedSlave.__init__`).
   - `handle_py_exception`, run when a callback raises (fmi2Fatal), releases the class, the
     instance and its log queue, and leaves the pointers in place; the instance's destructor,
     run by fmi2FreeInstance, releases the three again (`BalancedSlave._balance_fatal`).

   **Repair** (`BalancedSlave`, first among a slave's bases): take one reference for each one
   pythonfmu will release without owning it, only under pythonfmu 0.7 and only in an FMU
   (where pythonfmu's C++ side passes a logger); a later pythonfmu that no longer
   over-releases would at worst keep these objects until exit. A classmethod that raises
   (pythonfmu's `_fmu_state_from_bytes` and `_fmu_state_to_bytes`, called on the class) is not
   balanced: it has no instance to name.

builder.build_slave_fmu ships this module with every FMI 2.0 FMU as the module
`pythonfmu_references` (the example slaves import it so), as it ships `fmi_units`; the FMI
3.0 slave calls `tear_down_state_first` itself.
"""
from __future__ import annotations

import ctypes
import functools
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

# pythonfmu's library in an FMI 2.0 FMU of this package is named so, beside the FMU's own,
# which calls it (fmu/resource_path.c)
PYTHONFMU_LIBRARY_PREFIX = "pythonfmu-"

_incref = ctypes.pythonapi.Py_IncRef
_incref.argtypes = (ctypes.py_object,)
_incref.restype = None

# the instance methods pythonfmu 0.7 calls, each ending in handle_py_exception if it raises
CALLBACKS = ("setup_experiment", "enter_initialization_mode", "exit_initialization_mode",
             "do_step", "terminate", "get_real", "get_integer", "get_boolean", "get_string",
             "set_real", "set_integer", "set_boolean", "set_string", "_get_fmu_state",
             "_set_fmu_state")


def tear_down_state_first(resources: str | os.PathLike | None) -> bool:
    """Register the teardown of pythonfmu's library (the FMU's binary beside `resources`) with
    the C library's exit handlers, so that it runs before the library's static destructors (see
    the module's docstring). Call it once the libraries the slave needs are loaded (in the
    slave's __init__); each call registers the handler again, which moves it ahead of
    libraries loaded since, and the later calls find nothing left to do. Returns whether it is
    registered: only on Linux, for a library that exports `finalizePythonInterpreter`."""
    if sys.platform != "linux" or not resources:
        return False
    binaries = Path(resources).parent / "binaries"
    libraries = sorted([*binaries.glob("linux64/*.so"), *binaries.glob("x86_64-linux/*.so")])
    # an FMI 2.0 FMU of this package: pythonfmu's library behind the FMU's own (resource_path)
    libraries = [p for p in libraries if p.name.startswith(PYTHONFMU_LIBRARY_PREFIX)] or libraries
    if len(libraries) != 1:
        return False
    try:
        # pinned: the exit handler points into the library, which must outlive any dlclose
        library = ctypes.CDLL(str(libraries[0].resolve()),
                              mode=os.RTLD_NOLOAD | os.RTLD_NODELETE | os.RTLD_NOW)
    except OSError:  # not the library this process loaded (another copy of the FMU)
        return False
    teardown = getattr(library, "finalizePythonInterpreter", None)
    if teardown is None:
        return False
    register = getattr(ctypes.CDLL(None), "__cxa_atexit")
    register.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
    return register(ctypes.cast(teardown, ctypes.c_void_p), None, None) == 0


def affected(logger_address: int | None) -> bool:
    """Whether a slave runs under pythonfmu 0.7's C++ side (in an FMU: the `logger` it passes
    is set), whose releases these balance. Reads the pythonfmu that runs the slave, imported
    already, and never imports it: the FMI 3.0 slave imports this module too, in a host that
    may have pythonfmu3 alone."""
    pythonfmu = sys.modules.get("pythonfmu")
    return bool(logger_address) and pythonfmu is not None \
        and pythonfmu.__version__.startswith("0.7.")


class BalancedSlave:
    """A mixin for a pythonfmu 0.7 Fmi2Slave, listed before Fmi2Slave among its bases: gives
    back the slave module's reference at every instantiation, and those of the class, the
    instance and its log queue before an exception leaves one of its CALLBACKS; has the
    library's state torn down first at exit (`tear_down_state_first`)."""

    def __init__(self, **kwargs: Any) -> None:
        """Balance findClass's release of the module's dictionary (it has run by now), then
        go on with the next base's __init__."""
        self._pythonfmu_affected = affected(kwargs.get("logger"))
        if self._pythonfmu_affected:
            _incref(sys.modules[type(self).__module__].__dict__)
        if kwargs.get("logger"):  # in an FMU: pythonfmu's library is loaded
            tear_down_state_first(kwargs.get("resources"))
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
