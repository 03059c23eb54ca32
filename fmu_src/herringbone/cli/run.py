"""`herringbone run SCENE`: simulate a scene (the compiled integrator the FMU runs, or the
scipy reference with --reference), print a summary and write the outputs as CSV."""
from __future__ import annotations

import time
from pathlib import Path

from ..arguments import (
    COMPILED_DEFAULT_TOLERANCE,
    COMPILED_TOLERANCE_ARGUMENT,
    OUTPUT_INTERVAL,
    REFERENCE_DEFAULT_TOLERANCE,
    REFERENCE_TOLERANCE_ARGUMENT,
    STOP_TIME,
    number,
    samples_problem,
)
from ..optional import require
from .common import (
    add_output,
    add_progress,
    add_scene,
    add_settings,
    default_output,
    fail,
    scene_of,
)

NAME = "run"
HELP = ("simulate a scene on the compiled integrator (what the FMU runs; --reference: the scipy "
        "reference), print a summary and write the outputs as CSV")
SUFFIXES = (".csv",)


def declare(parser) -> None:
    """The options of `run`."""
    add_scene(parser)
    add_settings(parser)
    parser.add_argument("--stop-time", type=STOP_TIME.option_type,
                        help="simulated seconds (default: the scene's)")
    parser.add_argument("--output-interval", type=OUTPUT_INTERVAL.option_type,
                        help="seconds between output samples, at most the stop time "
                             "(default: the scene's)")
    parser.add_argument("--reference", action="store_true",
                        help="run the scipy reference (DOP853) instead: independent of the "
                             "compiled integrator, about 40-50 s of wall time per simulated "
                             "second of the reference scene at its default tolerance, and in "
                             "proportion to the fastest natural frequency (`info`) elsewhere: "
                             "hours a second for modes in the MHz")
    compiled, reference = COMPILED_TOLERANCE_ARGUMENT.allowed, REFERENCE_TOLERANCE_ARGUMENT.allowed
    parser.add_argument("--tolerance", type=number,
                        help="relative to the static mesh force: the error per step "
                             f"{compiled.describe()} (default {COMPILED_DEFAULT_TOLERANCE:g}); "
                             f"with --reference the error over the run {reference.describe()} "
                             f"(default {REFERENCE_DEFAULT_TOLERANCE:g})")
    add_output(parser, "the outputs, one column per output with its unit; an existing file is "
               "replaced", "results/<scene>.csv", SUFFIXES)
    parser.add_argument("--plot", action="store_true",
                        help="also write PNGs beside the CSV: time histories and amplitude "
                             "spectra with mesh harmonics and natural frequencies")
    add_progress(parser)


def tolerance_of(args, parser) -> float:
    """--tolerance, checked against the range of the integrator chosen, or its default."""
    argument = REFERENCE_TOLERANCE_ARGUMENT if args.reference else COMPILED_TOLERANCE_ARGUMENT
    if args.tolerance is None:
        return REFERENCE_DEFAULT_TOLERANCE if args.reference else COMPILED_DEFAULT_TOLERANCE
    if argument.problem(args.tolerance) is not None:
        fail(parser, f"--tolerance {args.tolerance:g}: allowed: {argument.describe()}")
    return args.tolerance


def execute(args, parser) -> int:
    """Check everything, run, write the CSV (and the PNGs), print the summary."""
    from ..analysis.run_progress import simulate_with_progress
    from ..analysis.run_report import summary, write_csv

    tolerance = tolerance_of(args, parser)
    scene = scene_of(args, parser)
    stop_time = args.stop_time or scene.experiment.stop_time
    interval = args.output_interval or scene.experiment.output_interval
    if interval > stop_time:
        fail(parser, f"--output-interval {interval:g} s is longer than the stop time "
                     f"{stop_time:g} s; allowed: > 0 and <= the stop time (give a shorter "
                     "--output-interval or a longer --stop-time)")
    # here, not only in simulate's own check, so that the message names the options (or the
    # scene's [experiment], where an option was not given)
    names = ("--stop-time" if args.stop_time else "[experiment] stop_time",
             "--output-interval" if args.output_interval else "[experiment] output_interval")
    too_many = samples_problem(scene, stop_time, interval, names)
    if too_many is not None:
        fail(parser, too_many)
    output = default_output(parser, args.output, Path("results") / f"{scene.name}.csv",
                            SUFFIXES)
    if args.plot:
        require("matplotlib", "--plot")
    started, start_time = time.perf_counter(), []

    def ready():
        start_time.append(time.perf_counter() - started)

    # (the scipy reference has no compiled code to load: its start is not told apart)
    results = simulate_with_progress(scene, stop_time=stop_time, output_interval=interval,
                                     tolerance=tolerance, reference=args.reference,
                                     progress=not args.no_progress,
                                     on_ready=None if args.reference else ready)
    wall = time.perf_counter() - started
    write_csv(results, output)
    integrator = "the scipy reference" if args.reference else "the compiled integrator"
    print(summary(scene, results, wall, integrator, start_time[0] if start_time else None))
    print(f"outputs written to {output}")
    if args.plot:
        from ..analysis.run_report import plot_run
        written = plot_run(scene, results, output, None if args.reference else tolerance)
        print("\n".join(f"written: {path}" for path in written))
    return 0
