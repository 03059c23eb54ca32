"""Guards for the FMU's Python inside hosts that are not Python (C, C++ simulators).

Imported first by the slave script (fmu/slave.py), before numpy, scipy or numba; this module
and the packages' __init__.py it runs import none of them:

- `check_dependencies`: an interpreter without numpy, scipy or numba gets one message that names
  what is missing, which Python was asked, and what to do, instead of an import failing half way
  (which left the host to crash at exit).
- `finalize_python_first`: the cure of the crash at a C host's exit. pythonfmu 0.7 initializes
  Python itself in a C host and finalizes it from the destructor of a static object of the FMU's
  library, which the C library runs at exit() in the reverse order of registration. The FMU's
  library is loaded before Python imports numpy, scipy and numba, so the static destructors of
  their C++ libraries (LLVM in llvmlite, scipy's _uarray) have run by the time Py_FinalizeEx
  frees the Python objects that point into them: freed memory freed again, SIGSEGV or "free():
  corrupted unsorted chunks" in 3 runs in 10. Registering pythonfmu's own
  `finalizePythonInterpreter` with the C library's exit handlers once those libraries are
  loaded makes Python finalize while they are intact; the later call from the static
  destructor then finds nothing left to do.
"""
from __future__ import annotations

import ctypes
import importlib.util
import os
import sys
from pathlib import Path

REQUIRED = ("numpy", "scipy", "numba")


def check_dependencies() -> None:
    """Raise ImportError (and say so on stderr, which a host without a logger still shows)
    if a runtime dependency cannot be found by this interpreter; import nothing."""
    missing = [name for name in REQUIRED if importlib.util.find_spec(name) is None]
    if missing:
        message = (
            f"herringbone FMU: {', '.join(missing)} cannot be imported by the Python that runs "
            f"the FMU (Python {sys.version.split()[0]} in {sys.prefix}, sys.path {sys.path}). "
            f"The FMU needs {', '.join(REQUIRED)}: set PYTHONPATH to the site-packages folder "
            "of an environment that has them (`python -c \"import sysconfig; "
            "print(sysconfig.get_path('purelib'))\"` in that environment), and load that "
            "Python's libpython first; see the README, section The FMU, What a host needs")
        print(message, file=sys.stderr, flush=True)
        raise ImportError(message)


def finalize_python_first(resources) -> bool:
    """Have Python finalized at exit before the libraries it loaded are torn down (see the
    module's docstring), for the FMU whose resources folder is `resources`. Only where the
    host is not a Python executable (a Python host finalizes Python itself, before exit). Call
    it once the libraries are loaded; each call registers the handler again, which moves the
    finalization ahead of libraries loaded since (the extra calls find nothing to do).
    Returns whether the handler is registered."""
    if sys.platform != "linux" or _host_is_python():
        return False
    libraries = sorted((Path(resources) / ".." / "binaries" / "linux64").glob("*.so"))
    if len(libraries) != 1:
        return False
    path = str(libraries[0].resolve())
    # pin the library: the exit handler points into it, so it must outlive a dlclose
    library = ctypes.CDLL(path, mode=os.RTLD_NOLOAD | os.RTLD_NODELETE | os.RTLD_NOW)
    finalize = getattr(library, "finalizePythonInterpreter", None)
    if finalize is None:
        return False
    register = getattr(ctypes.CDLL(None), "__cxa_atexit")
    register.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
    return register(ctypes.cast(finalize, ctypes.c_void_p), None, None) == 0


def _host_is_python() -> bool:
    try:
        return Path(os.readlink("/proc/self/exe")).name.startswith(("python", "pypy"))
    except OSError:
        return True  # cannot tell: do nothing
