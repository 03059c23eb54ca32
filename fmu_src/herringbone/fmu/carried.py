"""What a gear FMU carries of the herringbone package: the modules its run imports.

A host unpacks an FMU at every instance (fmpy at every `simulate_fmu`) and deletes it after,
file by file, so the FMU carries the modules its slave imports, directly or through others
(the closure of their import statements, those inside functions included: `runtime_modules`),
and every kernel file, whose text is the key of the compiled code it carries
(compiling.sources, compiling.cache.package_digest). The analysis, the command line, the builder
and the scipy reference stay behind. What they import from outside the package
(`outside_imports`) the host's Python gives, or the FMU's resources, where pythonfmu (FMI 2.0)
or pythonfmu3 (FMI 3.0) puts its own package: each slave's run imports its own alone.
"""
from __future__ import annotations

import ast
import shutil
from collections.abc import Iterable
from pathlib import Path

from .. import installed
from ..compiling import sources

PACKAGE = sources.ROOT  # herringbone
# the slaves' modules: what pythonfmu's script (a copy of slave.py or slave3.py) imports
ENTRY_MODULES = ("herringbone.fmu.slave", "herringbone.fmu.slave3")


def runtime_modules(entries: Iterable[str] = ENTRY_MODULES) -> set[str]:
    """The names of the package's modules an FMU's run can import: the slaves' modules
    `entries` (one alone: an FMU of that FMI version), every kernel module (carried whole:
    their text is the compiled code's key), and every module their import statements name,
    followed through, with the packages that hold them."""
    found: set[str] = set()
    waiting = [*entries, *sources.kernel_modules()]
    while waiting:
        name = waiting.pop()
        if name not in found:
            found.add(name)
            waiting.extend(_imported(name))
    return found


def stage_package(folder: Path) -> Path:
    """A copy of the package holding the runtime_modules alone, in `folder`/herringbone (for
    the FMU's resources), marked as such (installed.MARKER). Returns that folder."""
    target = Path(folder) / PACKAGE.name
    for name in sorted(runtime_modules()):
        source = _file_of(name)
        copy = target / source.relative_to(PACKAGE)
        copy.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source, copy)
    (target / installed.MARKER).write_text("an FMU's copy of the package (installed.py)\n")
    return target


def outside_imports(modules: Iterable[str]) -> set[str]:
    """The top-level names of what the import statements of the package's `modules` name
    outside the package (those inside functions included): "numpy", "pythonfmu3", ..."""
    return {named.split(".")[0] for name in modules for named in _named(name)
            if named.split(".")[0] != PACKAGE.name}


def _imported(name: str) -> set[str]:
    """The package's modules that module `name`'s import statements name, and the packages
    above them (whose __init__ an import runs first)."""
    modules = set()
    for module in _named(name):
        while module.startswith(PACKAGE.name):
            if _module_path(module) is not None:
                modules.add(module)
            module = module.rpartition(".")[0]
    return modules


def _named(name: str) -> set[str]:
    """What module `name`'s import statements name, as absolute names: modules, and for
    `from m import x` also "m.x" (a submodule, maybe)."""
    path = _file_of(name)
    here = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    named: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            named.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = (".".join(here[:len(here) - node.level + 1] + [node.module or ""]).strip(".")
                    if node.level else node.module or "")
            named.add(base)
            named.update(f"{base}.{alias.name}" for alias in node.names)  # a submodule, maybe
    return named


def _module_path(name: str) -> Path | None:
    """The file of the package's module `name`; None for a name that is not one (an
    attribute imported from a module)."""
    path = PACKAGE.parent.joinpath(*name.split("."))
    for candidate in (path / "__init__.py", path.with_suffix(".py")):
        if candidate.is_file():
            return candidate
    return None


def _file_of(name: str) -> Path:
    """The file of the package's module `name` (one runtime_modules found)."""
    path = _module_path(name)
    if path is None:
        raise ValueError(f"{name} is not a module of {PACKAGE}")
    return path
