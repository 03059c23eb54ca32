"""The resonance curve by continuation of periodic orbits against the time sweep (issue 23).

    python benchmarks/steady_state.py                 # reference scene, 200 speeds 100-3000 rad/s
    python benchmarks/steady_state.py --time-points 5 --scene models/reference.toml
    python benchmarks/steady_state.py --param zeta_mesh 0.02 0.1 20 --speed 500
                                                      # a parameter at one speed
    python benchmarks/steady_state.py --differences   # and the Jacobian by differences

Prints, side by side, one core's CPU time (process time, this process alone: the points run
here one after the other) of
- the branch by continuation (analysis/continuation.py) over all the speeds (or values of
  --param at --speed), and its period integrations a point;
- the time sweep (sweep_point's protocol, `sweep(..., method="time", workers=0)`) over an
  evenly spread subset of them, extrapolated to all by its mean time a point (and labelled
  so: a time point costs what its settle costs, which does not depend on the others);
and, at the subset's values, how far the time sweep's K_v and dte peak-to-peak lie from the
orbits' (the time protocol stops its settle at a residual of 1e-3 of the start's transient).
With --differences the branch is also run with the period map's Jacobian by forward
differences (steady_state.PeriodMap(jacobian_method="differences"), the method before the
variational monodromy, docs/monodromy.md), side by side in the same process.
The compiled integrator is loaded (or compiled) before anything is timed.
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices: threads only cost

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def timed(function, *args, **kwargs):
    """(result, CPU seconds of this process, wall seconds)."""
    cpu, wall = time.process_time(), time.perf_counter()
    result = function(*args, **kwargs)
    return result, time.process_time() - cpu, time.perf_counter() - wall


def arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", type=Path, default=ROOT / "models" / "reference.toml")
    parser.add_argument("--speeds", nargs=3, type=float, default=[100.0, 3000.0, 200],
                        metavar=("LO", "HI", "N"))
    parser.add_argument("--param", nargs=4, metavar=("NAME", "LO", "HI", "N"),
                        help="continue in this parameter (or M_motor, M_load) instead, at "
                             "--speed")
    parser.add_argument("--speed", type=float, default=500.0, help="rad/s, with --param")
    parser.add_argument("--differences", action="store_true",
                        help="also run the branch with the Jacobian by forward differences")
    parser.add_argument("--time-points", type=int, default=10,
                        help="values of the subset the time sweep runs (evenly spread)")
    return parser.parse_args(argv)


def by_differences(continued):
    """(branch, CPU s) of the same continuation with every period map's Jacobian by forward
    differences: the continuation builds its maps by the name it imported, which this
    replaces for the one call."""
    import functools

    from herringbone.analysis import continuation
    from herringbone.analysis.steady_state import PeriodMap

    continuation.PeriodMap = functools.partial(PeriodMap, jacobian_method="differences")
    try:
        branch, cpu, _ = timed(*continued)
    finally:
        continuation.PeriodMap = PeriodMap
    return branch, cpu


def main(argv=None) -> int:
    args = arguments(argv)

    import herringbone
    from herringbone.analysis.continuation import continue_in_parameter, continue_in_speed
    from herringbone.analysis.distributed_run import load_integrator
    from herringbone.analysis.steady_state import periodic_orbit
    from herringbone.analysis.sweep import sweep

    scene = herringbone.load_scene(args.scene)
    if args.param:
        name, (low, high, count), unit = args.param[0], map(float, args.param[1:]), ""
        values = np.linspace(low, high, int(count))
        continued = (continue_in_parameter, scene, name, values, args.speed)
    else:
        name, (low, high, count), unit = "w0_pinion", args.speeds, " rad/s"
        values = np.linspace(low, high, int(count))
        continued = (continue_in_speed, scene, values)
    load_integrator(scene)
    periodic_orbit(scene, args.speed if args.param else values[0])  # its numba functions loaded

    branch, branch_cpu, branch_wall = timed(*continued)
    if args.differences:
        compared = by_differences(continued)
    table = branch.table()
    grid = table[table["on_grid"]]
    subset = values[np.linspace(0, len(values) - 1, args.time_points).round().astype(int)]
    timed_table, time_cpu, time_wall = timed(
        sweep, scene, **({"speeds": [args.speed], "params": {name: subset}} if args.param
                         else {"speeds": subset}), method="time", workers=0, progress=False)
    per_time_point = time_cpu / len(subset)

    at = f" at {args.speed:g} rad/s" if args.param else ""
    print(f"scene {scene.name}: {len(values)} values of {name} {low:g}-{high:g}{unit}{at}, "
          "one core")
    print(f"{'':38s}{'continuation':>16s}{'time sweep':>16s}")
    print(f"{'CPU s, all values':38s}{branch_cpu:16.3f}"
          f"{per_time_point * len(values):16.1f}  (extrapolated from {len(subset)} points)")
    print(f"{'CPU ms a requested value':38s}{1e3 * branch_cpu / len(values):16.2f}"
          f"{1e3 * per_time_point:16.1f}")
    print(f"{'wall s (this machine, shared)':38s}{branch_wall:16.3f}"
          f"{time_wall / len(subset) * len(values):16.1f}")
    print(f"{'points (branch) / requested values':38s}{len(table):>10d} / {len(grid):<5d}")
    print(f"{'period integrations a branch point':38s}"
          f"{branch.evaluations / len(table):16.1f}")
    if args.differences:
        other, other_cpu = compared
        print(f"{'by differences: CPU s, points':38s}{other_cpu:16.3f}{len(other.points):>10d}"
              f"  ({other.evaluations / len(other.points):.1f} period integrations a point)")
    methods = dict(zip(*np.unique(table["method"], return_counts=True)))
    stabilities = dict(zip(*np.unique(table["stability"], return_counts=True)))
    print(f"branch: {methods}, stability {stabilities}, "
          f"folds {[float(f'{f:.6g}') for f in branch.folds]}")
    for figure in ("K_v", "dte_p2p_um"):  # against the nearest orbit at the value
        spread = np.array([np.abs(grid.loc[grid[name] == value, figure] / timed - 1.0).min()
                           for value, timed in zip(subset, timed_table[figure])])
        print(f"time sweep against the orbits, {figure}: relative difference "
              f"max {spread.max():.2e}, median {np.median(spread):.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
