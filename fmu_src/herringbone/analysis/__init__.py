"""What is computed from the model and its runs: `stability` (Floquet), `phasing` and `report`
(mesh-phase theory, `herringbone info`), `campbell`, `plots`, `run_progress`; sweeps:
`sweep` (grids, the API), `sweep_point` (one point's protocol and figures), `distributed_run`
(serial or Dask), `sweep_fmu` (a point through the FMU), `sweep_report`, `sweep_plots`;
`run_report` (what `herringbone run` writes); the periodic steady state directly:
`steady_state` (Newton shooting, Floquet multipliers), `continuation` (the branch over speed,
folds). The command line is herringbone.cli."""
