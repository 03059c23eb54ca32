"""The FMI 2.0 and 3.0 co-simulation FMUs: `core` (the slave's logic and its variables' table,
whatever the FMI version), `slave` (the FMI 2.0 pythonfmu slave, a thin adapter over the core),
`slave3` (the FMI 3.0 pythonfmu3 slave, likewise),
`units` (units and ranges on pythonfmu variables), `runtime` (guards for hosts that are not
Python, run before numpy is imported), `builder` (builds and validates FMUs; `herringbone
build-fmu`), `run` (a scene through its FMU with fmpy).

Kept free of imports: `import herringbone.fmu.runtime` must not import numpy."""
