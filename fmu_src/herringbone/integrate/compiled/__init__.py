"""Compiled (numba) kernels: the equations of motion and the integrators that run them.

- `equations`: the right-hand side and the outputs of the assembled gear train, the one home
  of the physics that both the scipy reference and the FMU's integrator evaluate;
- `dop853`, `radau`: one Runge-Kutta step of each method (explicit order 8; implicit, L-stable
  order 5), each step's contract written at its top;
- `walk`: the loop that steps through the segments of a run, stopping at every switch;
- `exponential`: the exact propagation of a linear, time-invariant segment.
- `reference_events`: the scipy reference's own screening of a step for events, compiled
  (its rule is the reference's, in integrate/stepping.py; the loop above never imports it).

Compiled code is cached on disk. numba keys its cache on the source file's folder, and an FMU
host unpacks the FMU to a new temporary folder for every run, so `cache` keys it on the source
text instead: a cache written by one start is found by the next.

`counting` says how the kernels are compiled with respect to numba's reference counts: the loop
runs without them.
"""
from . import cache

cache.install()
