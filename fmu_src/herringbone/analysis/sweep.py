"""Sweeps: a scene run at every point of a grid of one or two parameters (pinion speed, any
scene parameter, or an input torque), each point by the protocol of sweep_point, as a tidy table.

    table = herringbone.sweep(scene, speeds=np.linspace(100, 3000, 30))
    table = herringbone.sweep(scene, params={"dbeta_right": np.linspace(-1e-4, 1e-4, 9)},
                              workers=2)

Every point is a task, run here (`workers=0`), on a Dask LocalCluster on this machine
(`workers=N`, default: one per core) or on an existing Dask cluster (`scheduler="tcp://…"`),
with the same numbers whichever (distributed_run.py). `fmu=PATH` runs each point through that
FMU with fmpy instead of the package's integrator.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..model.parameters import INPUTS, unit_of, with_unit
from ..optional import require
from ..suggest import did_you_mean
from .sweep_point import Protocol, point_row, run_window

SPEED = "w0_pinion"
MOST_AXES = 2


@dataclass(frozen=True)
class Point:
    """One task: the values of the swept quantities at this point."""

    index: int
    values: tuple[tuple[str, float], ...]


def sweep_axes(scene, speeds=None, params=None) -> dict[str, np.ndarray]:
    """The swept quantities and their values, checked: at most two, each a scene parameter
    (w0_pinion for `speeds`, rad/s) or M_motor/M_load, finite numbers, no repeats."""
    axes = {} if speeds is None else {SPEED: speeds}
    for name, values in (params or {}).items():
        if name in axes:
            raise ValueError(f"{name} is swept twice; allowed: each quantity once "
                             "(--speeds sweeps w0_pinion)")
        axes[name] = values
    if not axes:
        raise ValueError("nothing to sweep; allowed: speeds or a parameter "
                         "(--speeds FROM TO COUNT, --param NAME FROM TO COUNT)")
    if len(axes) > MOST_AXES:
        raise ValueError(f"{len(axes)} quantities swept ({', '.join(axes)}); allowed: "
                         f"at most {MOST_AXES} (a grid of two)")
    checked = {}
    for name, values in axes.items():
        if name not in scene.parameters and name not in INPUTS:
            known = [*scene.parameters, *INPUTS]
            raise ValueError(f"{name} is not a parameter of scene {scene.name}"
                             f"{did_you_mean(name, known)}; allowed: "
                             f"{', '.join(sorted(scene.parameters))}, M_motor, M_load")
        values = np.atleast_1d(np.asarray(values, dtype=float))
        if values.ndim != 1 or not len(values) or not np.all(np.isfinite(values)):
            raise ValueError(f"{name}: values must be finite numbers, got {values!r}")
        checked[name] = values
    return checked


def grid(axes: dict[str, np.ndarray]) -> list[Point]:
    """Every combination, the last axis varying fastest."""
    names = list(axes)
    return [Point(i, tuple(zip(names, (float(v) for v in combination))))
            for i, combination in enumerate(itertools.product(*axes.values()))]


def scene_at(scene, point: Point):
    """The scene with the point's values; a parameter out of its range raises SceneError
    (a ValueError) naming it and what is allowed."""
    params = {k: v for k, v in point.values if k not in INPUTS}
    torques = {k: v for k, v in point.values if k in INPUTS}
    changed = scene.with_parameters(**params) if params else scene
    return changed.with_inputs(**torques) if torques else changed


def run_point(scene, point: Point, protocol: Protocol, fmu=None):
    """The task of one point: (its table row, its window's time, dte and F_mesh)."""
    at = scene_at(scene, point)
    if fmu is None:
        window = run_window(at, protocol)
    else:
        from .sweep_fmu import run_window_through_fmu
        window = run_window_through_fmu(fmu, at, point, protocol)
    row = {**dict(point.values), **point_row(at, window, protocol)}
    return row, {"time": window["time"], "dte": window["dte"], "F_mesh": window["F_mesh"]}


def run_sweep(scene, speeds=None, params=None, protocol: Protocol = Protocol(),
              workers: int | None = None, scheduler: str | None = None, fmu=None,
              progress: bool = True):
    """The table (pandas DataFrame, a row per point in grid order) and, per point, its
    window series (for spectra). workers: 0 runs the points here, one after the other; N >= 1
    starts a LocalCluster of N single-threaded worker processes (None: one per core);
    scheduler: address of a running Dask scheduler (workers is then ignored)."""
    pd = require("pandas", "a sweep's table")

    from .distributed_run import map_points

    if fmu is not None:
        from .sweep_fmu import check_fmu
        check_fmu(fmu)
    points = grid(sweep_axes(scene, speeds, params))
    for point in points:  # bad values fail here, before any process starts
        scene_at(scene, point)
    results = map_points(run_point, points, (scene, protocol, fmu), workers, scheduler,
                         progress)
    table = pd.DataFrame([row for row, _ in results])
    return table, [series for _, series in results]


def sweep(scene, speeds=None, params=None, protocol: Protocol = Protocol(), **options):
    """Run a scene over speeds and/or parameters past its start-up transient.

    Parameters
    ----------
    scene : Scene
    speeds : array_like or None
        Pinion speeds w0_pinion, rad/s.
    params : dict or None
        {parameter name (or "M_motor", "M_load"): values, in its unit}; with `speeds`, at
        most two quantities in all (a grid).
    protocol : Protocol
        How each point is settled and recorded (analysis.sweep_point.Protocol).
    **options
        workers (0: here, one point after the other; None: one Dask process per core),
        scheduler (a Dask scheduler's address), fmu (run each point through this gear FMU),
        progress (a bar on stderr).

    Returns
    -------
    pandas.DataFrame
        A row per point in grid order: the swept values, then speed_rpm, K_v, forces (N), dte
        (µm), contact_lost_share, floquet_max (the columns name their units).

    Raises
    ------
    ValueError
        A swept name or value that is not allowed, before any work.
    MissingDependency
        pandas (or dask, tqdm) is not installed: `pip install "herringbone[analysis]"`.
    """
    return run_sweep(scene, speeds, params, protocol, **options)[0]


def resonation_summary(table) -> str:
    """Where the largest K_v of a table lies, as 'name = value unit, …'
    ("w0_pinion = 485.714 rad/s (4638 rpm)")."""
    row = table.loc[table["K_v"].idxmax()]
    names = list(table.columns[:list(table.columns).index("speed_rpm")])
    text = ", ".join(f"{name} = {with_unit(f'{row[name]:.6g}', unit_of(name))}" for name in names)
    return text + (f" ({row['speed_rpm']:.0f} rpm)" if SPEED in names else "")
