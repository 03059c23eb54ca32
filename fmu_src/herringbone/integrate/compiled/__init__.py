"""Compiled (numba) kernels: the equations of motion and the integrators that run them.

- `equations`: the right-hand side and the outputs of the assembled gear train, the one home
  of the physics that both the scipy reference and the FMU's integrator evaluate;
- `dop853`, `radau`: one Runge-Kutta step of each method (explicit order 8; implicit, L-stable
  order 5), each step's contract written at its top;
- `walk`: the loop that steps through the segments of a run, stopping at every switch.

Compiled code is cached on disk. numba keys its cache on the source file's folder, and an FMU
host unpacks the FMU to a new temporary folder for every run, so `cache` keys it on the source
text instead: a cache written by one start is found by the next.

Reference counts. numba counts the references to every array's memory as it passes arrays
around (an atomic increment and decrement for every array an argument or record holds, every
view, every field read), and at a step's pace that cost half the loop's time. `walk.advance`,
the one entry from Python, is therefore compiled without that runtime (`_nrt=False`): the
arrays it is given carry no memory record, so every count below it is a test of a null
pointer. Its own body (and what it inlines) must then neither allocate nor copy by slices
(`walk.copy_into`). Kernels it calls inherit that setting unless they name their own, and a
kernel compiled once serves every caller with the same argument types; so every kernel that
allocates, or returns arrays or records of arrays, names `_nrt=True` (it counts, correctly,
wherever it is called from), and the others return numbers only, which is right either way.
tests/integrate/test_compiled_memory.py checks that no run leaks or frees what it was given.
"""
from . import cache

cache.install()
