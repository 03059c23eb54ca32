"""Sweeps: a scene over one or two quantities (pinion speed, any scene parameter, or an input
torque) as a tidy table: the branch of periodic steady states by continuation where one
quantity is swept (analysis/continuation.py), else every point of the grid by the time
protocol of sweep_point.

    table = herringbone.sweep(scene, speeds=np.linspace(100, 3000, 30))
    table = herringbone.sweep(scene, params={"dbeta_right": np.linspace(-1e-4, 1e-4, 9)})
    table = herringbone.sweep(scene, speeds=[300, 600], params={"M_motor": [250, 500]},
                              workers=2)     # a grid: the time protocol

Every time point is a task, run here (`workers=0`), on a Dask LocalCluster on this machine
(`workers=N`, default: one per core) or on an existing Dask cluster (`scheduler="tcp://…"`),
with the same numbers whichever (distributed_run.py). `fmu=PATH` runs each point through that
FMU with fmpy instead of the package's integrator.
"""
from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..arguments import SWEEP_METHODS, check_scene, check_speeds, check_values
from ..model.parameters import INPUTS, unit_of, values_problem, with_unit
from ..optional import require
from ..shipped import named_as_typed
from ..suggest import did_you_mean
from .progress_bar import progress_bar
from .sweep_point import (
    Protocol,
    least_damped_decay_rate,
    point_row,
    run_window,
    settle_problem,
)

SPEED = "w0_pinion"
MOST_AXES = 2


@dataclass(frozen=True)
class Point:
    """One task: the values of the swept quantities at this point."""

    index: int
    values: tuple[tuple[str, float], ...]


def sweep_axes(scene, speeds=None, params=None) -> dict[str, np.ndarray]:
    """The swept quantities and their values, checked: a Scene (else SceneError), at most two
    quantities, each a scene parameter (w0_pinion for `speeds`, rad/s) or M_motor/M_load,
    `params` a dict of them, finite numbers, each value once."""
    check_scene(scene)
    if params is not None and not isinstance(params, Mapping):
        raise ValueError(f"params is a {type(params).__name__} ({params!r}); allowed: a dict "
                         "{parameter name: values}, e.g. {\"zeta_mesh\": [0.02, 0.05]}")
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
        label = "speeds" if name == SPEED else name
        checked[name] = (check_values(check_speeds(values), label) if name == SPEED
                         else check_values(values, name))
        problem = None if name == SPEED else values_problem(name, checked[name])
        if problem is not None:
            raise ValueError(f"params[{name!r}]: {problem}")
        unique, counts = np.unique(checked[name], return_counts=True)
        if (counts > 1).any():
            # a point twice is a mistake: a branch cannot step from a value to itself
            raise ValueError(f"{label} holds {unique[counts > 1][0]:g} more than once; "
                             "allowed: distinct values, each point once")
    return checked


def grid(axes: dict[str, np.ndarray]) -> list[Point]:
    """Every combination, the last axis varying fastest."""
    names = list(axes)
    return [Point(i, tuple(zip(names, (float(v) for v in combination))))
            for i, combination in enumerate(itertools.product(*axes.values()))]


def scene_at(scene, point: Point):
    """The scene with the point's values; a parameter out of its range raises SceneError
    (a ValueError) naming it and what is allowed. One torque swept on a scene whose torques
    balance sets the transmitted torque: the other follows (steady_state.balanced_torques),
    as a continuation in it does, so that the train runs steadily at every point; a tooth
    count swept on such a scene changes the ratio u, and the load torque follows it,
    M_load = u·M_motor, the motor's torque kept."""
    from .steady_state import ShootingError, balanced_torques, check_balanced

    params = {k: v for k, v in point.values if k not in INPUTS}
    torques = {k: v for k, v in point.values if k in INPUTS}
    # the torque the other one follows: the swept one, or for a tooth count the motor's
    held = (next(iter(torques.items())) if len(torques) == 1 else
            ("M_motor", scene.inputs.at(0.0)[0]) if not torques and RATIO_SETTERS & params.keys()
            else None)
    try:
        if held is not None:
            check_balanced(scene)
    except ShootingError:
        held = None  # unbalanced already: what is swept alone changes
    changed = scene.with_parameters(**params) if params else scene
    if held is not None:
        torques = balanced_torques(changed, *held)
    return changed.with_inputs(**torques) if torques else changed


# the parameters that set the gear ratio u, which a balanced scene's load torque follows
RATIO_SETTERS = frozenset({"z_pinion", "z_wheel"})


def run_point(scene, point: Point, protocol: Protocol, fmu=None):
    """The task of one point: (its table row, its window's time, dte and F_mesh)."""
    at = scene_at(scene, point)
    window: dict  # run_window's carries its figures' finer samples (sweep_point.Window)
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
    scheduler: address of a running Dask scheduler (workers is then ignored). Every argument
    and every point is checked before any process starts (check_sweep, method "time")."""
    check_sweep(scene, speeds, params, protocol, "time", workers=workers,
                scheduler=scheduler, fmu=fmu, progress=progress)
    return run_checked_points(scene, speeds, params, protocol, workers, scheduler, fmu,
                              progress)


def run_checked_points(scene, speeds, params, protocol, workers=None, scheduler=None,
                       fmu=None, progress=True):
    """run_sweep's work, its arguments checked already (check_sweep: every point, the FMU's
    scene), so that a caller that checked them does not check them again."""
    pd = require("pandas", "a sweep's table")

    from .distributed_run import map_points

    points = grid(sweep_axes(scene, speeds, params))
    results = map_points(run_point, points, (scene, protocol, fmu), workers, scheduler,
                         progress)
    table = pd.DataFrame([row for row, _ in results])
    return table, [series for _, series in results]


METHODS = SWEEP_METHODS  # its home: arguments.py


def shooting_applies(scene, speeds, params, fmu) -> str | None:
    """Why the periodic steady state cannot be computed directly for this sweep, or None: it
    needs one swept quantity — the speed, or a parameter that varies continuously or a torque
    at one speed —, run by the package (not through an FMU), at constant torques that
    balance."""
    from .continuation import continued_problem
    from .steady_state import ShootingError, check_balanced

    names = [name for name in (params or {}) if name != SPEED]
    if len(names) > 1 or (names and speeds is not None and np.size(speeds) > 1):
        return ("it sweeps two quantities (a grid); continuation follows one: the speed, or "
                "a parameter or torque at one speed")
    if fmu is not None:
        return "it runs through an FMU"
    problem = continued_problem(scene, names[0]) if names else None
    if problem:
        return problem
    try:
        check_balanced(scene)
    except ShootingError as error:
        return str(error)
    return None


def sweep(scene, speeds=None, params=None, protocol: Protocol = Protocol(), method=None,
          **options):
    """Run a scene over speeds and/or parameters: its steady state by shooting or by time.

    Parameters
    ----------
    scene : Scene
    speeds : array_like or None
        Pinion speeds w0_pinion, rad/s, each once; `[450.0]` with `params`: at that speed.
    params : dict or None
        {parameter name (or "M_motor", "M_load"): values, in its unit, each once}; with
        `speeds`, at most two quantities (a grid). One torque swept, the other follows; a
        tooth count, M_load: each point needs M_load = u·M_motor, M_motor > 0.
    protocol : Protocol
        How each time-integration point is settled and recorded (herringbone.Protocol).
    method : {"shooting", "time"} or None
        "shooting" (None's choice where it applies: the speed, or a continuous parameter or
        torque at one speed or none, no FMU): the branches of periodic steady states
        (continuation), elsewhere refused with the reason; "time" (None's choice elsewhere):
        each point past its transient. Never chosen by `workers`.
    **options
        workers (0: here, one point after the other; None: one Dask process per core; N >= 1
        and scheduler, a Dask scheduler's address: time only), fmu (through this gear FMU of
        the scene: time), progress (a bar on stderr), doubling (False: no period-2 branch).

    Returns
    -------
    pandas.DataFrame
        "time": a row per point in grid order: the swept values, speed_rpm, K_v, K_v_half (the
        more loaded helix half's), forces (N; each half's peak too), load_share_left, dte (µm),
        contact_lost_share (window_figures), window_drift, linear_floquet_max (the linear
        mesh's |λ|max; columns name their units), method, stability "time". "shooting": a row
        per branch point in branch order (at each value it passes, several where it folds
        back, and those between, on_grid False): the continued quantity, speed_rpm, the torque
        following a swept one (M_load_Nm, M_motor_Nm), the same figures, floquet_max and
        floquet_exponent_per_s (1/s) of the orbit, stability ("stable", "unstable", "time": no
        orbit converged), method, on_grid, event, mesh_periods, branch; attrs: continued,
        folds, period_doublings, folds_2T, and units ({swept column: its unit}).

    Raises
    ------
    ValueError
        Before any work, anything not allowed (check_sweep); SceneError for no Scene.
    MissingDependency
        pandas (or dask, tqdm) is not installed: `pip install pandas`, or the analysis extra.

    Examples
    --------
    >>> import herringbone
    >>> scene = herringbone.load_scene("reference")
    >>> table = herringbone.sweep(scene, speeds=[200.0, 400.0, 600.0], progress=False)
    >>> table.loc[table.on_grid, "K_v"].round(2).tolist()  # the dynamic factor at each speed
    [1.5, 1.47, 1.5]
    """
    method = check_sweep(scene, speeds, params, protocol, method, **options)
    doubling = options.pop("doubling", True)  # False only with shooting (check_sweep)
    return with_swept_units(
        run_checked_points(scene, speeds, params, protocol, **options)[0].assign(
            stability="time", method="time") if method == "time" else
        shooting_sweep(scene, speeds, protocol, options.get("progress", True), params, doubling))


def with_swept_units(table):
    """The table with attrs["units"]: the unit of each swept column (those before speed_rpm:
    w0_pinion in rad/s, a parameter or torque in its own), which the other columns name
    (F_mesh_max_N) and the CSV's header gives ("w0_pinion [rad/s]")."""
    table.attrs["units"] = {name: unit_of(name) for name in swept_columns(table)}
    return table


def swept_columns(table) -> list[str]:
    """A sweep table's swept columns: those before speed_rpm."""
    return list(table.columns[:list(table.columns).index("speed_rpm")])


def point_label(row, names, rpm: bool = True) -> str:
    """A table row's point as 'name = value unit, …' over the swept columns `names`, the speed
    in rpm beside it (`rpm`; not after the other quantities): "w0_pinion = 485.714 rad/s
    (4638 rpm)"."""
    def value(name):
        beside = f" ({row['speed_rpm']:.0f} rpm)" if rpm and name == SPEED else ""
        return f"{name} = {with_unit(f'{row[name]:.6g}', unit_of(name))}{beside}"

    return ", ".join(value(name) for name in names)


def runs_by_time(scene, speeds, params, method, fmu) -> bool:
    """Whether `sweep` runs by time integration: by `method` "time", or by None where
    shooting does not apply (shooting_applies; `fmu`: the gear FMU it would run through, or
    None). Before any work: ValueError for another method, for "shooting" where it does not
    apply and for swept values not allowed; MissingDependency where pandas is not installed."""
    if method not in (None, *METHODS):
        raise ValueError(f"method {method!r}; allowed: {', '.join(METHODS)}")
    require("pandas", "a sweep's table")  # whichever method runs
    sweep_axes(scene, speeds, params)
    why_not = shooting_applies(scene, speeds, params, fmu)
    if method == "shooting" and why_not:
        raise ValueError(f"method 'shooting' cannot run this sweep: {why_not}; "
                         "allowed: method='time'")
    return method == "time" or bool(why_not)


def check_sweep(scene, speeds=None, params=None, protocol: Protocol = Protocol(),
                method=None, **options) -> str:
    """Every argument of `sweep` and every point, before any work: the method the sweep runs
    by ("shooting" or "time"; runs_by_time). ValueError (SceneError for something that is
    not a Scene) naming the first culprit and what is allowed: the swept values
    (sweep_axes), the protocol, the options (check_options), each point (point_problem) and
    the FMU (sweep_fmu.check_fmu: a gear FMU of this scene)."""
    check_scene(scene)
    if not isinstance(protocol, Protocol):
        raise ValueError(f"protocol is a {type(protocol).__name__} ({protocol!r}); allowed: "
                         "a herringbone.Protocol, e.g. "
                         "herringbone.Protocol(settle_time=0.05)")
    unknown = sorted(set(options) - set(OPTIONS))
    if unknown:
        raise ValueError(f"unknown option {unknown[0]}{did_you_mean(unknown[0], OPTIONS)}; "
                         f"allowed: {', '.join(OPTIONS)}")
    by_time = runs_by_time(scene, speeds, params, method, options.get("fmu"))
    check_options(options, by_time)
    axes = sweep_axes(scene, speeds, params)
    for point in grid(axes):
        at = scene_at(scene, point)
        problem = point_problem(at) or (settle_problem(protocol, least_damped_decay_rate(at))
                                        if by_time else None)
        if problem is not None:
            where = ", ".join(f"{name} = {value:g}" for name, value in point.values)
            raise ValueError(f"{named_as_typed(scene)} at {where}: {problem}")
    if options.get("fmu") is not None:
        from .sweep_fmu import check_fmu
        check_fmu(options["fmu"], scene, list(axes))
    return "time" if by_time else "shooting"


# the keyword options of `sweep`, in the order its docstring gives them
OPTIONS = ("workers", "scheduler", "fmu", "progress", "doubling")


def check_options(options: dict, by_time: bool) -> None:
    """The options of `sweep` for a sweep by time (`by_time`) or by shooting: workers a whole
    number >= 0 or None, scheduler an address or None, and a sweep by shooting run here
    (it follows its branch one point from the last: workers 0 or None, no scheduler);
    doubling=False only with shooting. ValueError naming the first one not allowed."""
    workers, scheduler = options.get("workers"), options.get("scheduler")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 0):
        raise ValueError(f"workers is {workers!r}; allowed: a whole number >= 0 "
                         "(0: no Dask, run here), or None (one process per core)")
    if scheduler is not None and not isinstance(scheduler, str):
        raise ValueError(f"scheduler is {scheduler!r}; allowed: the address of a running "
                         "Dask scheduler, e.g. \"tcp://HOST:8786\", or None")
    if not by_time and (workers or scheduler is not None):
        what = f"workers={workers!r}" if workers else f"scheduler={scheduler!r}"
        raise ValueError(f"{what}: a sweep by shooting follows its branch here, each point "
                         "from the last; allowed: workers=0 or None and no scheduler, or "
                         "method='time' to run the points on Dask")
    if by_time and options.get("doubling") is False:
        raise ValueError("doubling=False: allowed: only with a sweep by method 'shooting' "
                         "(this one runs by time: it follows no branch)")


def point_problem(scene) -> str | None:
    """Why `scene` (a point's) has no steady running state for a sweep to record, or None.
    It needs constant input torques; a turning pinion; M_motor > 0, since K_v is measured
    against the static mesh force M_motor/Rp and a negative torque would load the back
    flanks, on which the model has no contact (docs/model.md section 3); and torques that
    balance (M_load = u·M_motor), else the train accelerates through the settle and the
    window, away from the speed the row is labelled with."""
    from .steady_state import ShootingError, check_balanced

    if len(scene.inputs.times) != 1:
        return ("a sweep point needs constant input torques; the scene has an input table "
                "(allowed: [inputs] M_motor, M_load)")
    if scene.parameters["w0_pinion"] == 0.0:
        return ("w0_pinion is 0: a sweep point needs a turning pinion (allowed: w0_pinion "
                "!= 0 rad/s in the scene, or the speeds swept or given)")
    motor = scene.inputs.M_motor[0]
    if motor <= 0.0:
        return (f"M_motor = {motor:g} N·m: the static mesh force M_motor/Rp would be "
                f"{'zero' if motor == 0.0 else 'negative'} (a negative torque loads the back "
                "flanks, on which the model has no contact); allowed: M_motor > 0 N·m, "
                "M_load = u·M_motor")
    try:
        check_balanced(scene)
    except ShootingError as error:
        return str(error)
    return None


def shooting_sweep(scene, speeds, protocol: Protocol = Protocol(), progress: bool = True,
                   params=None, doubling: bool = True):
    """The branch table of `sweep`'s method "shooting": in speed, or in the one parameter or
    torque of `params` at the one speed of `speeds` (None: the scene's w0_pinion); each row's
    mesh frequency and static force added after speed_rpm, as the time table has them.
    doubling: the period-2 branches from the period doublings as well (their rows after the
    period-1 branch's, mesh_periods 2)."""
    import math

    from .continuation import continue_in_parameter, continue_in_speed
    from .sweep_point import static_mesh_force

    checked = sweep_axes(scene, speeds, params)
    speed_values = checked.pop(SPEED, None)
    if checked:
        (name, values), = checked.items()
        speed = None if speed_values is None else float(speed_values[0])
        branch = continue_in_parameter(scene, name, values, speed, protocol=protocol,
                                       progress=progress, doubling=doubling)
    else:
        name = SPEED
        branch = continue_in_speed(scene, speed_values, protocol=protocol, progress=progress,
                                   doubling=doubling)
    table = branch.table()
    speeds_of_points = np.array([point.speed for part in (branch, *branch.doubled)
                                 for point in part.points])  # the table's rows
    forces = (static_mesh_force(scene) if name == SPEED else  # M_motor/Rp: Rp, M_motor may vary
              [static_mesh_force(scene_at(scene, Point(0, ((name, value),))))
               for value in table[name]])
    after = table.columns.get_loc("speed_rpm") + 1
    table.insert(after, "mesh_frequency_Hz",
                 speeds_of_points * scene.parameters["z_pinion"] / (2.0 * math.pi))
    table.insert(after + 1, "static_mesh_force_N", forces)
    table.attrs["folds"] = list(branch.folds)
    table.attrs["period_doublings"] = list(branch.doublings)
    table.attrs["folds_2T"] = [fold for doubled in branch.doubled for fold in doubled.folds]
    table.attrs["continued"] = name
    return table


def chained_time_sweep(scene, speeds, protocol: Protocol = Protocol(), progress: bool = False):
    """A speed sweep by time integration in the order of `speeds` (rad/s), each point started
    from the end state of the point before (the first from the static start), its rigid speed
    moved to the point's: what a test rig sees when the speed is raised or lowered slowly,
    which stays on one branch of a multi-valued response until that branch ends at a fold.
    A table as `sweep`'s (method "time"), one row a speed, in the order given."""
    import pandas as pd

    from ..integrate.contract import Position
    from ..model.assembly import GearTrainModel
    from .sweep_point import at_speed, run_window_from

    values = np.atleast_1d(np.asarray(speeds, dtype=float))
    sweep_axes(scene, speeds=values)
    rows: list[dict] = []
    end = None
    with progress_bar(len(values), "time sweep", progress, unit="point") as bar:
        for speed in values:
            at = scene.with_parameters(w0_pinion=float(speed))
            start: Position | None = (None if end is None
                                      else at_speed(GearTrainModel(at), end, float(speed)))
            window, end = run_window_from(at, protocol, start)
            rows.append({SPEED: float(speed), **point_row(at, window, protocol),
                         "stability": "time", "method": "time"})
            bar.update(1)
    return pd.DataFrame(rows)


def resonation_summary(table, column: str = "K_v") -> str:
    """Where the largest K_v (or the `column` given) of a table lies, as 'name = value unit,
    …' ("w0_pinion = 485.714 rad/s (4638 rpm)")."""
    return point_label(table.loc[table[column].idxmax()], swept_columns(table))
