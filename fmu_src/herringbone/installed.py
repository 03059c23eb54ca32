"""The installed package, for a process whose `herringbone` would be an FMU's copy of it.

An FMU carries the modules its run imports (carried.py), and pythonfmu puts the FMU's
resources first on sys.path. In a host process that had not imported herringbone before it
loaded the FMU, the FMU's copy would become `herringbone`: the modules it leaves out (the
analysis, the builder, the SSP, the command line) and the package's data (the shipped scenes)
would be missing, and its files gone once the host deletes the unpacked FMU.

`installed_twin` (called by the copy's `__init__`, which the MARKER file tells apart) finds
the installed package where it holds the same text of every module the FMU carries (the same
version: the FMU's run is then the same with either), and the copy's `__init__` makes that
package the process's `herringbone`. Where the installed package is another version, the FMU
runs its own copy and `RefusingFinder`, last on sys.meta_path, answers an import of a module
the copy leaves out with a message that says why and what to do. Only the standard library is
imported here: this runs before the FMU's dependency check.
"""
from __future__ import annotations

import importlib.abc
import importlib.machinery
import os
import sys

# the file stage_package writes into the package an FMU carries, and only there
MARKER = "CARRIED"


class RefusingFinder(importlib.abc.MetaPathFinder):
    """Answers an import of a module of `package` that its carried copy (folder `carried`)
    lacks, where the installed package (folder `installed`) is another version, with a
    ModuleNotFoundError that says so and what to do."""

    def __init__(self, package: str, carried: str, installed: str):
        self.package, self.carried, self.installed = package, carried, installed

    def find_spec(self, fullname, path, target=None):
        """Raise for a module of the package the finders before this one have not found;
        None for any other module."""
        if not fullname.startswith(self.package + "."):
            return None
        raise ModuleNotFoundError(
            f"No module named {fullname!r}: this process imported {self.package} from an "
            f"FMU's resources ({self.carried}), which carry only what the FMU's run needs, "
            f"and the installed {self.package} ({self.installed}) is not the one the FMU was "
            f"built from; import {self.package} before the FMU is loaded, or build the FMU "
            "again with the installed package", name=fullname)


def installed_twin(package: str, carried: str) -> str | None:
    """The folder of the installed `package` where `carried` (the folder of the package being
    imported) is an FMU's copy of it (holds MARKER) and the installed one holds the same text
    of every module it carries; else None, and where the installed one is another version, a
    RefusingFinder last on sys.meta_path."""
    if not os.path.isfile(os.path.join(carried, MARKER)):
        return None
    resources = os.path.realpath(os.path.dirname(carried))
    elsewhere = [entry for entry in sys.path
                 if os.path.realpath(entry or os.curdir) != resources]
    spec = importlib.machinery.PathFinder.find_spec(package, elsewhere)
    if spec is None or not spec.submodule_search_locations:
        return None
    installed = list(spec.submodule_search_locations)[0]
    if os.path.isfile(os.path.join(installed, MARKER)):
        return None  # another FMU's copy (or this one, on the path twice): not an installation
    if _same_text(carried, installed):
        return installed
    sys.meta_path.append(RefusingFinder(package, carried, installed))
    return None


def _same_text(carried: str, installed: str) -> bool:
    """Whether every module file of the folder `carried` has the same bytes in `installed`."""
    for folder, _, files in os.walk(carried):
        for name in files:
            if not name.endswith(".py"):
                continue
            mine = os.path.join(folder, name)
            theirs = os.path.join(installed, os.path.relpath(mine, carried))
            if not os.path.isfile(theirs):
                return False
            with open(mine, "rb") as a, open(theirs, "rb") as b:
                if a.read() != b.read():
                    return False
    return True
