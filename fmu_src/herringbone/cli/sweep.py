"""`herringbone sweep SCENE`: run a scene over a grid of speeds or parameters (one or two) and
write the table of figures per point and its pictures: the periodic steady state directly
(shooting and continuation) where it applies, else each point past its start-up transient.

Every option is one `add_argument` in `declare`, checked by its `type=` or action; `execute`
hands them to analysis.sweep.run_sweep.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from ..arguments import (
    COMPILED_DEFAULT_TOLERANCE,
    COMPILED_TOLERANCE_ARGUMENT,
    SAMPLES_PER_PERIOD,
    SETTLE_RESIDUAL,
    SETTLE_TIME,
    SPEED_COUNT,
    SWEEP_METHODS,
    WINDOW_PERIODS,
    existing_fmu,
    name_problem,
    number,
    output_folder,
)
from ..model.parameters import INPUTS, PARAMETERS, RPM_PER_RAD_S, values_problem
from ..optional import require
from ..suggest import did_you_mean
from .common import (
    add_progress,
    add_scene,
    add_settings,
    add_speeds,
    changed_name,
    default_output,
    fail,
    progress_of,
    scene_of,
    speeds_of,
)

NAME = "sweep"
HELP = ("run a scene over a grid of speeds or parameters (one or two): K_v, bearing "
        "reactions, dte, contact loss and Floquet multipliers of the periodic steady state per "
        "point, stable and unstable branches and their folds (CSV, resonance curve, waterfall)")
SWEEPABLE = {**PARAMETERS, **INPUTS}


class _ParamAction(argparse.Action):
    """--param NAME FROM TO COUNT: a known parameter (or input), FROM < TO finite, COUNT >= 2."""

    def __call__(self, parser, namespace, values, option_string=None):
        name, *numbers = values
        if name not in SWEEPABLE:
            raise argparse.ArgumentError(self, f"{name}: unknown parameter"
                                               f"{did_you_mean(name, SWEEPABLE)}; allowed: a "
                                               "parameter of the scene, M_motor or M_load")
        try:
            low, high, count = (float(text) for text in numbers)
        except ValueError:
            low = high = count = float("nan")
        if not (low < high and abs(high - low) < float("inf")
                and SPEED_COUNT.problem(count) is None):
            raise argparse.ArgumentError(self, f"{' '.join(values)}: allowed: FROM < TO, "
                                               "finite, and COUNT >= 2 values")
        problem = values_problem(name, _values(low, high, int(count)))
        if problem is not None:
            raise argparse.ArgumentError(self, f"{' '.join(values)}: {problem}")
        getattr(namespace, self.dest).append((name, low, high, int(count)))


def declare(parser) -> None:
    """The options of `sweep`: one declaration each."""
    add_scene(parser)
    add_settings(parser)
    add_speeds(parser, None, "sweep the pinion speed w0_pinion")
    parser.add_argument("--speed", type=number, metavar="W",
                        help="with one --param: the pinion speed it is swept at, rad/s (rpm "
                             "with --rpm); default the scene's w0_pinion")
    parser.add_argument("--param", nargs=4, action=_ParamAction, default=[],
                        metavar=("NAME", "FROM", "TO", "COUNT"),
                        help="sweep a parameter (or M_motor, M_load) over COUNT values from "
                             "FROM to TO, in its unit; twice, or with --speeds, for a grid")
    for argument, default, metavar in ((SETTLE_RESIDUAL, 1e-3, "FRACTION"),
                                       (SETTLE_TIME, None, "SECONDS"),
                                       (WINDOW_PERIODS, 50, "N"), (SAMPLES_PER_PERIOD, 64, "N"),
                                       (COMPILED_TOLERANCE_ARGUMENT, COMPILED_DEFAULT_TOLERANCE,
                                        "TOL")):
        shown = "" if default is None else f"; default {default:g}"
        whole = "a whole number " if argument.whole else ""
        parser.add_argument(argument.option, type=argument.option_type, default=default,
                            metavar=metavar,
                            help=f"{argument.meaning}: {whole}{argument.allowed.describe()}"
                                 f"{shown}")
    parser.add_argument("--method", choices=SWEEP_METHODS, default=None,
                        help="shooting: the periodic steady state directly, followed in the "
                             "swept quantity through folds, stable and unstable branches (the "
                             "default for a sweep of one quantity at balanced constant "
                             "torques: the speed, or one --param at one speed or none, not "
                             "through an FMU); time: each point from its static start past "
                             "its transient (the default elsewhere, a grid of two among them)")
    parser.add_argument("--time-sweeps", action="store_true",
                        help="with shooting: also sweep up and down by time integration, each "
                             "point from the last one's end state, draw both over the branch "
                             "(where the response is multi-valued they jump at folds) and "
                             "write each as <table>_time_up.csv and _time_down.csv")
    parser.add_argument("--no-period-doubling", action="store_true",
                        help="with shooting: flag period doublings on the branch but do not "
                             "switch to and follow the period-2 branch from each (followed by "
                             "default)")
    parser.add_argument("--no-floquet", action="store_true",
                        help="skip a time point's linear_floquet_max (the linear mesh's "
                             "Floquet multiplier at its speed)")
    parser.add_argument("--workers", type=number, metavar="N", help="where the points run: N Dask "
                        "LocalCluster worker processes, with --method time (default: one per "
                        "core); 0: no Dask, run here one after the other, with either method "
                        "(shooting always runs here)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="with --method time: run on an existing Dask cluster at ADDRESS, "
                             "e.g. tcp://HOST:8786 (its workers need herringbone installed)")
    parser.add_argument("--through-fmu", type=existing_fmu, metavar="FMU",
                        help="run each point through this gear FMU with fmpy (one built from "
                             "SCENE: herringbone build-fmu SCENE); its figures are those of "
                             "the recorded samples, which read the ringing's peaks low")
    add_progress(parser)
    parser.add_argument("-o", "--output", type=_output_folder, metavar="FOLDER",
                        help="a folder to write: the table <scene>_sweep_<swept>.csv and its "
                             "pictures; files of those names in it are replaced (default: "
                             "results)")


def execute(args, parser) -> int:
    """Check everything, run the sweep, write the table first, then the pictures."""
    from ..analysis.sweep import (
        chained_time_sweep,
        check_sweep,
        run_checked_points,
        shooting_sweep,
    )
    from ..analysis.sweep_point import Protocol
    from ..analysis.sweep_report import describe, write_outputs

    if args.workers is not None and (args.workers < 0 or args.workers != int(args.workers)):
        fail(parser, f"--workers {args.workers:g}: allowed: a whole number >= 0")
    if args.settings and args.through_fmu is not None:
        fail(parser, "--set with --through-fmu: the FMU runs the values it was built with; "
                     "allowed: --set without --through-fmu, or the values in a scene file "
                     "whose FMU `herringbone build-fmu` builds")
    if args.rpm and args.speeds is None and args.speed is None:
        fail(parser, "--rpm without --speeds; allowed: --rpm with --speeds FROM TO COUNT "
                     "or --speed W")
    sweep = speeds_of(args, parser)
    params = {name: _values(low, high, count) for name, low, high, count in args.param}
    speeds = None if sweep is None else sweep.speeds()
    if args.speed is not None:
        speeds = _one_speed(parser, args)
    protocol = Protocol(settle_residual=args.settle_residual, settle_time=args.settle_time,
                        window_periods=args.window_periods,
                        samples_per_period=args.samples_per_period, tolerance=args.tolerance,
                        floquet=not args.no_floquet)
    scene = scene_of(args, parser)
    folder = default_output(parser, args.output, Path("results"), folder=True)
    require("pandas", "sweep")
    require("matplotlib", "the sweep's pictures")
    method = _method(parser, args, scene, speeds, params)
    # the points, the FMU and what the API checks besides: one line each, before any work
    check_sweep(scene, speeds, params, protocol, method, fmu=args.through_fmu)
    progress = progress_of(args)
    started = time.perf_counter()
    time_sweeps = None
    if method == "shooting":
        table, series = shooting_sweep(scene, speeds, protocol, progress=progress,
                                       params=params,
                                       doubling=not args.no_period_doubling), None
        if args.time_sweeps and speeds is not None:
            time_sweeps = {direction: chained_time_sweep(scene, order, protocol,
                                                         progress=progress)
                           for direction, order in (("up", speeds), ("down", speeds[::-1]))}
    else:
        table, series = run_checked_points(
            scene, speeds, params, protocol,
            workers=None if args.workers is None else int(args.workers),
            scheduler=args.scheduler, fmu=args.through_fmu, progress=progress)
    wall = time.perf_counter() - started
    written = write_outputs(scene, table, series, folder, time_sweeps,
                            changed_name(scene, args))
    print(describe(scene, table, wall, through_fmu=args.through_fmu is not None,
                   time_sweeps=time_sweeps))
    for path in written:
        print(f"written: {path}")
    return 0


def _method(parser, args, scene, speeds, params) -> str:
    """The method the sweep runs by: --method, else shooting where it applies; one line and
    exit 2 where shooting was asked for and cannot run, or --time-sweeps without it."""
    from ..analysis.sweep import shooting_applies

    why_not = shooting_applies(scene, speeds, params, args.through_fmu)
    if args.method == "shooting" and why_not:
        fail(parser, f"--method shooting: this sweep cannot be run so: {why_not}; allowed: "
                     "--method time")
    # where the points run does not choose the method (as in the API): a branch is followed
    # here, each point from the last, so only a sweep by time can go to Dask
    method = args.method or ("time" if why_not else "shooting")
    if method == "shooting" and (args.workers or args.scheduler is not None):
        given = (f"--workers {args.workers:g}" if args.workers
                 else f"--scheduler {args.scheduler}")
        fail(parser, f"{given}: allowed: only with --method time (this sweep runs by "
                     "shooting, which follows its branch here, in milliseconds a point; "
                     "--workers 0 runs here with either method)")
    if args.time_sweeps and method != "shooting":
        fail(parser, "--time-sweeps: allowed: only with a sweep by --method shooting "
                     f"(this one runs by time{': ' + why_not if why_not else ''})")
    if args.no_period_doubling and method != "shooting":
        fail(parser, "--no-period-doubling: allowed: only with a sweep by --method shooting "
                     f"(this one runs by time{': ' + why_not if why_not else ''})")
    if args.time_sweeps and params:
        fail(parser, "--time-sweeps: allowed: only with a sweep of speeds (--speeds alone); "
                     "this one continues in " + ", ".join(params))
    return method


# what -o must not end in: the sweep writes several files into the folder it names
FILE_SUFFIXES = (".csv", ".png", ".svg", ".pdf", ".jpg", ".jpeg", ".txt", ".json", ".xlsx",
                 ".parquet", ".html", ".toml", ".fmu", ".ssp", ".zip")


def _output_folder(text: str) -> Path:
    """argparse `type=` for -o: a folder (arguments.output_folder); a new one not named with
    a file's suffix (FILE_SUFFIXES), checked before output_folder makes it. What exists is
    taken as it is: a folder, or a file that output_folder refuses."""
    if name_problem(Path(text)) is None and not Path(text).exists() \
            and Path(text).suffix.lower() in FILE_SUFFIXES:
        raise argparse.ArgumentTypeError(
            f"{text}: names a {Path(text).suffix} file, but -o is a folder for sweep (the "
            "table and its pictures are written in it); allowed: a folder, e.g. -o "
            f"{Path(text).parent / Path(text).stem}")
    return output_folder(text)


def _one_speed(parser, args):
    """--speed W as [ω] in rad/s: with one --param and without --speeds, W > 0 finite."""
    import numpy as np

    from ..arguments import PINION_SPEED

    if args.speeds is not None or len(args.param) != 1:
        fail(parser, f"--speed {args.speed:g}: allowed: with one --param and without "
                     "--speeds (the speed a parameter is swept at)")
    if PINION_SPEED.problem(args.speed) is not None:
        fail(parser, f"--speed {args.speed:g}: allowed: {PINION_SPEED.allowed.describe()} "
                     f"({'rpm' if args.rpm else 'rad/s'})")
    return np.array([args.speed / RPM_PER_RAD_S if args.rpm else args.speed])


def _values(low: float, high: float, count: int):
    """COUNT evenly spaced values from `low` to `high`."""
    import numpy as np

    return np.linspace(low, high, count)

