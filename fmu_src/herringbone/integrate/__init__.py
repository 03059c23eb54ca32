"""Integrating the gear train: `contract` (Position, the Stepper protocol, IntegrationError, the
initial condition and the one run loop every caller uses), the scipy reference (`reference`,
`stepping`, and `segments`, its own event rule), the compiled integrator (`compiled_stepper`
over the numba kernels in `compiled/`), and `first_start` (compiled code carried by an FMU, a
word before compiling).

The equations they integrate are the model's (`herringbone.model.equations`); this package
sits above the model and imports from it, never the other way."""
