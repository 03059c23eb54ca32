"""How the package's numba kernels are compiled and where they are kept, beneath every
package that holds kernels (`model.equations`, `integrate.compiled`):

- `counting`: the options every kernel is compiled with: which count numba's references and
  which do not (the integrator's loop); importing it puts the cache's locator in place, so a
  kernel module imports it before it defines a kernel;
- `cache`: the compiled code on disk, keyed on the kernels' source text rather than on their
  folder: an FMU host unpacks the FMU to a new temporary folder for every run, and a cache
  written by one start is found by the next;
- `sources`: the files that text is read from, plain paths (no numba);
- `announce`: a line on stderr (or to a caller's `say`) before, while and after numba compiles
  kernels of the package.
"""
