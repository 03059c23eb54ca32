"""The rest of the package, for a process whose `herringbone` is an FMU's copy of it.

An FMU carries the modules its run imports (carried.py), and pythonfmu puts the FMU's
resources first on sys.path. In a host process that had not imported herringbone before it
loaded the FMU, the FMU's copy becomes `herringbone`, and the process's own imports of the
modules the copy leaves out (the analysis, the builder, the SSP, the command line) would fail
although the package is installed, also once the host has deleted the unpacked FMU.

`find_the_rest` (called by the copy's `__init__`, which the MARKER file tells apart) puts a
finder last on sys.meta_path: a module of the package that the copy lacks is taken from the
installed package where that holds the same text of every module the FMU carries (the same
version: the carried modules and the installed ones are then interchangeable), and refused
with a message that says why and what to do where it does not. Only the standard library is
imported here: this runs before the FMU's dependency check.
"""
from __future__ import annotations

import importlib.abc
import importlib.machinery
import os
import sys

# the file stage_package writes into the package an FMU carries, and only there
MARKER = "CARRIED"


class InstalledRest(importlib.abc.MetaPathFinder):
    """Finds the modules of `package` (its name) that its carried copy (folder `carried`)
    lacks in the installed package (folder `installed`, None: none found); `same`: whether the
    installed package has the carried modules' text."""

    def __init__(self, package: str, carried: str, installed: str | None, same: bool):
        self.package, self.carried, self.installed, self.same = package, carried, installed, same

    def find_spec(self, fullname, path, target=None):
        """The installed module's spec, for a module of the package the copy lacks (the
        finders before this one have not found it); None for any other module."""
        if not fullname.startswith(self.package + ".") or self.installed is None:
            return None
        if not self.same:
            raise ModuleNotFoundError(
                f"No module named {fullname!r}: this process imported {self.package} from an "
                f"FMU's resources ({self.carried}), which carry only what the FMU's run "
                f"needs, and the installed {self.package} ({self.installed}) is not the one "
                f"the FMU was built from; import {self.package} before the FMU is loaded, or "
                "build the FMU again with the installed package", name=fullname)
        folder = os.path.join(self.installed, *fullname.split(".")[1:-1])
        return importlib.machinery.PathFinder.find_spec(fullname, [folder])


def find_the_rest(package: str, carried: str) -> None:
    """Put an InstalledRest for `package` last on sys.meta_path, where `carried` (the folder
    of the package being imported) is an FMU's copy of it (holds MARKER)."""
    if not os.path.isfile(os.path.join(carried, MARKER)):
        return
    resources = os.path.realpath(os.path.dirname(carried))
    elsewhere = [entry for entry in sys.path
                 if os.path.realpath(entry or os.curdir) != resources]
    spec = importlib.machinery.PathFinder.find_spec(package, elsewhere)
    installed = (None if spec is None or not spec.submodule_search_locations
                 else list(spec.submodule_search_locations)[0])
    same = installed is not None and _same_text(carried, installed)
    sys.meta_path.append(InstalledRest(package, carried, installed, same))


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
