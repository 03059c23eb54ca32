"""The files the package's kernels are compiled from: their text is the key of the compiled
code (cache.package_digest), and an FMU carries them whole (fmu/carried.py). Plain paths, no
numba: the builder and the command line read them without loading the compiler."""
from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]  # the herringbone package
# the files that hold kernels or say how they are compiled, relative to ROOT
KERNEL_SOURCES = ("compiling/*.py", "model/equations.py", "integrate/compiled/*.py")


def kernel_files() -> list[Path]:
    """The package's files that hold kernels or decide how they are compiled (KERNEL_SOURCES),
    in path order."""
    return sorted({path for pattern in KERNEL_SOURCES for path in ROOT.glob(pattern)})


def kernel_modules() -> list[str]:
    """The module names of kernel_files (a package's __init__.py: the package)."""
    names = []
    for path in kernel_files():
        parts = (package_name(), *path.relative_to(ROOT).with_suffix("").parts)
        names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


def package_name() -> str:
    """The module name of ROOT, the package this module belongs to."""
    return __name__.rpartition(".")[0].rpartition(".")[0]
