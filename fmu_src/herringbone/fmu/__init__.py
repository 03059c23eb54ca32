"""The FMI 2.0 co-simulation FMU: `slave` (the pythonfmu slave, a thin adapter over the model),
`units` (units and ranges on pythonfmu variables), `runtime` (guards for hosts that are not
Python, run before numpy is imported), `builder` (builds and validates FMUs; `herringbone
build-fmu`), `run` (a scene through its FMU with fmpy).

Kept free of imports: `import herringbone.fmu.runtime` must not import numpy."""
