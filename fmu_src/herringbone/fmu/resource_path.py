"""An FMI 2.0 FMU's own library in front of pythonfmu 0.7's, so that the FMU loads from any
folder (resource_path.c says why): `with_resource_path` compiles it with the system's C compiler
and puts it into a built FMU. Where no compiler is found, the FMU keeps pythonfmu's library alone
and a ResourcePathWarning says what that leaves: a host crashes in fmi2Instantiate where the
folder it unpacked the FMU into has a character in its path that a URI escapes, other than a
space ("ü", "#", "%").
"""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import warnings
import zipfile
from pathlib import Path

from .pythonfmu_references import PYTHONFMU_LIBRARY_PREFIX

SOURCE = Path(__file__).with_name("resource_path.c")
FMI2_BINARIES = "binaries/linux64/"


class ResourcePathWarning(UserWarning):
    """An FMI 2.0 FMU built without its own library in front of pythonfmu's (no C compiler):
    it loads only from folders whose path needs no escape in a URI but spaces."""


def c_compiler() -> str | None:
    """The C compiler that builds the library: $CC, else `cc`, where it is on the PATH."""
    return shutil.which(os.environ.get("CC") or "cc")


def fmi2_headers() -> Path:
    """The FMI 2.0 headers fmpy ships (fmi2Functions.h and the files it includes)."""
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def with_resource_path(fmu_path: Path) -> bool:
    """Rewrite the FMI 2.0 FMU `fmu_path` (pythonfmu's build) with its library
    binaries/linux64/ID.so renamed `PYTHONFMU_LIBRARY_PREFIX` + ID.so and resource_path.c's
    library, compiled, in its place. Returns whether it did; where no C compiler is found, the
    FMU stays as it is and a ResourcePathWarning says what that leaves. Raises RuntimeError
    where the FMU has not one such library or the compiler fails."""
    with zipfile.ZipFile(fmu_path) as zf:
        entries = {info.filename: zf.read(info) for info in zf.infolist()}
    libraries = [name for name in entries if name.startswith(FMI2_BINARIES)
                 and name.endswith(".so") and name.count("/") == FMI2_BINARIES.count("/")]
    compiler = c_compiler()
    if compiler is None:
        warnings.warn(ResourcePathWarning(
            "no C compiler ($CC or cc): the FMI 2.0 FMU keeps pythonfmu 0.7's library alone, "
            "and a host that loads it from a folder whose path holds a character a URI "
            "escapes, other than a space (such as ü, # or %), crashes in fmi2Instantiate; "
            "install a C compiler (Debian: apt install gcc) and build again, or have hosts "
            "unpack it into a folder whose path has none"), stacklevel=2)
        return False
    if len(libraries) != 1:
        raise RuntimeError(f"{fmu_path}: pythonfmu's one library expected in {FMI2_BINARIES}, "
                           f"found {libraries}")
    name = libraries[0]
    pythonfmu_name = FMI2_BINARIES + PYTHONFMU_LIBRARY_PREFIX + Path(name).name
    entries[pythonfmu_name] = entries[name]
    entries[name] = _compiled(compiler, Path(pythonfmu_name).name)
    with zipfile.ZipFile(fmu_path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for entry, data in entries.items():
            zf.writestr(entry, data)
    return True


def _compiled(compiler: str, pythonfmu_library: str) -> bytes:
    """resource_path.c as a shared library that calls `pythonfmu_library`, beside it."""
    with tempfile.TemporaryDirectory(prefix="resource_path_") as folder:
        library = Path(folder) / "library.so"
        command = [compiler, "-shared", "-fPIC", "-O2", "-Wall", "-I", str(fmi2_headers()),
                   f'-DPYTHONFMU_LIBRARY="{pythonfmu_library}"', "-o", str(library),
                   str(SOURCE), "-ldl"]
        run = subprocess.run(command, capture_output=True, text=True)
        if run.returncode != 0:
            raise RuntimeError(f"{compiler} could not build the FMU's library from {SOURCE}:"
                               f"\n{run.stderr}")
        return library.read_bytes()
