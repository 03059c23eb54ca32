"""Compiled (numba) kernels of the integrators that run the equations of motion
(`herringbone.model.equations`, the one home of the physics that both the scipy reference
and the FMU's integrator evaluate):

- `dop853`, `radau`: one Runge-Kutta step of each method (explicit order 8; implicit, L-stable
  order 5), each step's contract written at its top;
- `walk`: the loop that steps through the segments of a run, stopping at every switch;
- `exponential`: the exact propagation of a linear, time-invariant segment;
- `buffers`: the loop's records as the few flat buffers each call is handed;
- `variational`: the sensitivities through the segments, for the monodromy;
- `reference_events`: the scipy reference's own screening of a step for events, compiled
  (its rule is the reference's, in integrate/stepping.py; the loop above never imports it).

How they are compiled and cached (on the source text, so that an FMU's next start finds what
the last compiled): `herringbone.compiling`.
"""
