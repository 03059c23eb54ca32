"""A guard for the FMU's Python inside hosts that are not Python (C, C++ simulators).

Imported first by the slave script (fmu/slave.py), before numpy, scipy or numba; this module
and the packages' __init__.py it runs import none of them. `check_dependencies`: an
interpreter without numpy, scipy or numba gets one message that names what is missing, which
Python was asked, and what to do, instead of an import failing half way (which left the host
to crash at exit).
"""
from __future__ import annotations

import importlib.util
import sys

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
            "Python's libpython first; see documentation/hosts.md in the FMU, What a host needs")
        print(message, file=sys.stderr, flush=True)
        raise ImportError(message)

