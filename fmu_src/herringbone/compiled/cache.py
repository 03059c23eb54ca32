"""Where numba caches the compiled kernels of this package.

numba's own locators put the cache beside the source (`__pycache__`) or in a folder named after
the source's path. An FMU is unpacked to a fresh temporary folder for every instance, so either
way each start would compile again (a minute). This locator keys the cache on the source text
of the whole package (numba alone would miss a change to a kernel that another file's kernel
compiled in), in a per-user folder: $HERRINGBONE_CACHE_DIR, else
$XDG_CACHE_HOME/herringbone/numba, else ~/.cache/herringbone/numba. numba itself keeps apart
the Python and numba versions and the CPU. Each version of the package adds a folder there
(a few MB); deleting the folder is always safe.
"""
from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

from numba.core import caching

PACKAGE_DIR = Path(__file__).resolve().parent


@functools.lru_cache(maxsize=None)
def package_digest() -> str:
    """The hash of every source file of this package, in name order."""
    digest = hashlib.sha256()
    for source in sorted(PACKAGE_DIR.glob("*.py")):
        digest.update(source.name.encode() + b"\0" + source.read_bytes())
    return digest.hexdigest()[:20]


def cache_root() -> Path:
    if os.environ.get("HERRINGBONE_CACHE_DIR"):
        return Path(os.environ["HERRINGBONE_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "herringbone" / "numba"


class SourceTextCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """Caches the kernels of this package by the hash of their source text."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = str(cache_root() / f"kernels-{package_digest()}")

    def get_cache_path(self):
        return self._cache_path

    def get_source_stamp(self):
        # numba checks only the function's own file; a kernel compiled into another (walk.py
        # holds dop853.step and the equations) must be compiled anew when any of them changes
        return package_digest()

    @classmethod
    def from_function(cls, py_func, py_file):
        if Path(py_file).resolve().parent != PACKAGE_DIR:
            return None  # not ours: numba's own locators decide
        return super().from_function(py_func, py_file)  # None if the folder is not writable


def install() -> None:
    """Put the locator first (once per process); numba falls back to its own if it declines."""
    implementation = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # numba < 0.62
    locators = implementation._locator_classes
    if SourceTextCacheLocator not in locators:
        locators.insert(0, SourceTextCacheLocator)
