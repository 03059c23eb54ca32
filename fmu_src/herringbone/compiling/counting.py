"""How the kernels are compiled with respect to numba's reference counts.

numba counts the references to every array's memory as it passes arrays
around (an atomic increment and decrement for every array an argument or record holds, every
view, every field read), and at a step's pace that cost half the loop's time. `walk.advance`,
the one entry from Python, is therefore compiled without that runtime (UNCOUNTED): the
arrays it is given carry no memory record, so every count below it is a test of a null
pointer. Its own body (and what it inlines) must then neither allocate nor copy by slices
(`walk.copy_into`). Kernels it calls inherit that setting unless they name their own, and a
kernel compiled once serves every caller with the same argument types; so every kernel that
allocates, or returns arrays or records of arrays, is compiled with COUNTED (it counts, correctly,
wherever it is called from), and the others return numbers only, which is right either way.
tests/integrate/test_compiled_memory.py checks that no run leaks or frees what it was given.

numba's option for this, `_nrt`, is private (its own tests use it); it is set here alone.

Every kernel is cached (`"cache": True`) by cache.py's locator, which must be in place before
numba sees the first kernel: importing this module puts it there, and announce.py's word on
every compile.
"""
from __future__ import annotations

from typing import Any

from . import announce, cache

cache.install()
announce.install()

# walk.advance alone: the entry from Python, and what it inlines
UNCOUNTED: dict[str, Any] = {"cache": True, "error_model": "numpy", "_nrt": False}
# a kernel that returns numbers only and allocates nothing: called from a kernel compiled
# COUNTED, it would inherit its counts and count every array of every record it is handed at
# every call; so it names its own
NUMBERS_ONLY: dict[str, Any] = {"cache": True, "error_model": "numpy", "_nrt": False}
# every kernel that allocates or hands back arrays
COUNTED: dict[str, Any] = {"cache": True, "error_model": "numpy", "_nrt": True}
