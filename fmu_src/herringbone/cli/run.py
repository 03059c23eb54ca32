"""`herringbone run SCENE`: simulate a scene (the compiled integrator the FMU runs, by the method
--method names, or the scipy reference with --reference), print a summary and write the
outputs as CSV.

The summary (analysis.run_report.summary) is printed before the CSV is written, its time that
of the run alone; the CSV's writing is timed on a line of its own, since a long run's table
takes longer to write than to compute (high_speed over 20 s: 4.6 s of run, then 40 s writing
486 MB). After the table, a line each where the samples miss what the table reads from them
(`sampling_note`) or where the run has left what the model describes (`slip_notes`).
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ..arguments import (
    COMPILED_DEFAULT_TOLERANCE,
    COMPILED_METHODS,
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
    changed_name,
    default_output,
    fail,
    progress_of,
    say,
    scene_of,
)

if TYPE_CHECKING:
    from ..integrate.contract import Result

NAME = "run"
HELP = ("simulate a scene on the compiled integrator (what the FMU runs; --reference: the scipy "
        "reference), print a summary and write the outputs as CSV")
SUFFIXES = (".csv",)
# samples a period of the train's fastest natural mode below which the output samples miss
# its swings: the table's least and largest samples fall short of the extremes (the
# reference scene every 1e-4 s, 0.76 samples a period of its 13.2 kHz mode: F_mesh's least
# sample 21 275 N where the steady state dips to 15 844 N)
RESOLVING_SAMPLES = 8
# rows of a CSV from which `run` says on stderr that it is writing them (about 20 µs a row)
LONG_TABLE = 100_000


def declare(parser) -> None:
    """The options of `run`."""
    add_scene(parser)
    add_settings(parser)
    parser.add_argument("--stop-time", type=STOP_TIME.option_type, metavar="SECONDS",
                        help="simulated seconds (default: the scene's)")
    parser.add_argument("--output-interval", type=OUTPUT_INTERVAL.option_type,
                        metavar="SECONDS",
                        help="seconds between output samples, at most the stop time (default: "
                             "the scene's); the summary says when they are too far apart for "
                             "the train's fastest natural mode")
    parser.add_argument("--method", choices=COMPILED_METHODS, default=None,
                        help="the compiled integrator's method: auto (the default) picks for "
                             "the scene (exponential where the mesh's contact sets allow it, "
                             "else dop853, or radau for an overdamped stiff train); dop853: "
                             "explicit Runge-Kutta of order 8, radau: implicit Radau IIA, "
                             "exponential: "
                             "exact steps of the linear contact sets (DOP853 elsewhere); not "
                             "with --reference, which always runs scipy's DOP853")
    parser.add_argument("--reference", action="store_true",
                        help="run the scipy reference (DOP853) instead: independent of the "
                             "compiled integrator, about 20 s of CPU per simulated second of "
                             "the reference scene at its default tolerance, and in proportion "
                             "to the fastest natural frequency (`info`) elsewhere: hours a "
                             "second for modes in the MHz")
    compiled, reference = COMPILED_TOLERANCE_ARGUMENT.allowed, REFERENCE_TOLERANCE_ARGUMENT.allowed
    parser.add_argument("--tolerance", type=number, metavar="TOL",
                        help="relative to the static mesh force: the error per step "
                             f"{compiled.describe()} (default {COMPILED_DEFAULT_TOLERANCE:g}); "
                             f"with --reference the error over the run {reference.describe()} "
                             f"(default {REFERENCE_DEFAULT_TOLERANCE:g})")
    add_output(parser, "the outputs, one column per output with its unit; an existing file is "
               "replaced", "results/<scene>.csv, <scene> with +NAME=VALUE for each --set; "
               "with --reference results/<scene>_scipy.csv",
               SUFFIXES)
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


def span_of(args, parser, scene) -> tuple[float, float]:
    """(stop time, output interval), s: the options, else the scene's [experiment]; one line
    where the interval outlasts the stop time or the samples would not fit in memory."""
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
    return stop_time, interval


def execute(args, parser) -> int:
    """Check everything, run, print the summary, write the CSV (and the PNGs)."""
    from ..analysis.run_report import summary

    tolerance = tolerance_of(args, parser)
    if args.reference and args.method is not None:
        fail(parser, f"--method {args.method} with --reference: the scipy reference runs "
                     "scipy's DOP853, whatever --method says; allowed: --method without "
                     "--reference (the compiled integrator's methods)")
    scene = scene_of(args, parser)
    stop_time, interval = span_of(args, parser, scene)
    # the scipy reference's run beside the compiled one's, not in its place: they are compared
    ran_by = "_scipy" if args.reference else ""
    output = default_output(parser, args.output,
                            Path("results") / f"{changed_name(scene, args)}{ran_by}.csv",
                            SUFFIXES)
    if args.plot:
        require("matplotlib", "--plot")
    progress = progress_of(args)
    if args.reference:
        run = reference_run(scene, stop_time, interval, tolerance, progress)
    else:
        run = compiled_run(scene, stop_time, interval, tolerance, args.method or "auto",
                           progress)
    results = run.results
    lines = [summary(scene, results, run.wall, run.integrator, run.start, steps=results.steps),
             *sampling_note(scene, results), *slip_notes(scene, results)]
    print("\n".join(lines), flush=True)  # before the CSV, which may take longer than the run
    write_timed(results, output, run.wall)
    if args.plot:
        from ..analysis.run_report import plot_run
        written = plot_run(scene, results, output, None if args.reference else tolerance)
        print("\n".join(f"written: {path}" for path in written))
    return 0


class FinishedRun(NamedTuple):
    """A run as its summary tells it."""
    results: Result  # its steps: the integrator's internal steps (None: not counted)
    wall: float  # s, the run's wall time
    integrator: str  # what ran it, in words
    start: float | None  # s of `wall` before the first step (None: not told apart)


def reference_run(scene, stop_time: float, interval: float, tolerance: float,
                  progress: bool) -> FinishedRun:
    """The scipy reference's run: its start is not told apart, there being no compiled code to
    load, and its steps are not counted."""
    from ..analysis.run_progress import simulate_with_progress

    started = time.perf_counter()
    results = simulate_with_progress(scene, stop_time=stop_time, output_interval=interval,
                                     tolerance=tolerance, reference=True, progress=progress)
    return FinishedRun(results, time.perf_counter() - started, "the scipy reference", None)


def compiled_run(scene, stop_time: float, interval: float, tolerance: float, method: str,
                 progress: bool) -> FinishedRun:
    """The compiled integrator's run by `method` with its bar (run_progress), its start the
    model's tables and the compiled loop loaded."""
    from ..analysis.run_progress import simulate_with_progress

    started, ready = time.perf_counter(), []
    results = simulate_with_progress(
        scene, stop_time=stop_time, output_interval=interval, tolerance=tolerance,
        method=method, progress=progress,
        on_ready=lambda chosen, note: ready.append((time.perf_counter() - started, chosen,
                                                    note)))
    start, chosen, note = ready[0]
    picked = ", picked by --method auto" if method == "auto" else ""
    note = f": {note}" if note else ""
    return FinishedRun(results, time.perf_counter() - started,
                       f"the compiled integrator ({chosen}{picked}{note})", start)


def write_timed(results: dict, output: Path, run_wall: float) -> None:
    """Write the CSV and say where, in how long and how large, apart from the run's own
    `run_wall` s; a long table is announced on stderr first."""
    from ..analysis.run_report import write_csv

    rows = len(results["time"])
    if rows >= LONG_TABLE:
        say(f"writing {rows} rows to {output} ...")
    started = time.perf_counter()
    write_csv(results, output)
    seconds = time.perf_counter() - started
    size = output.stat().st_size
    print(f"outputs written to {output} ({rows} rows, {size / 1e6:.3g} MB) in {seconds:.2f} s "
          f"of wall time, which the run's {run_wall:.2f} s above leaves out")


def sampling_note(scene, results: dict) -> list[str]:
    """A line where the output samples give the train's fastest natural mode
    (sweep_point.fastest_ringing, as --plot's spectra) fewer than RESOLVING_SAMPLES a period:
    what they resolve, what they miss, and what to do."""
    from ..analysis.sweep_point import fastest_ringing
    from ..model.assembly import GearTrainModel
    from ..shipped import named_as_typed

    times = results["time"]
    if len(times) < 3:
        return []
    interval = float(times[1] - times[0])
    fastest = fastest_ringing(GearTrainModel(scene))
    per_period = 1.0 / (interval * fastest)
    if per_period >= RESOLVING_SAMPLES:
        return []
    finer = _two_digits_down(1.0 / (RESOLVING_SAMPLES * fastest))
    speed = scene.parameters["w0_pinion"]
    aliases = ", and a mean of them aliases it (below 2 a period)" if per_period < 2.0 else ""
    return [f"The samples, every {interval * 1e6:.3g} µs, follow motion up to "
            f"{1.0 / (RESOLVING_SAMPLES * interval):.0f} Hz ({RESOLVING_SAMPLES} a period) but "
            f"give the train's fastest mode, ringing at {fastest:.0f} Hz with its damping "
            f"(`herringbone info` lists it undamped), {per_period:.2g} a period: the min and "
            "max of samples can miss its swings between them, reading F_mesh's peak and dip "
            f"(K_v) short{aliases}; --output-interval {finer:g} or shorter follows the "
            "ringing, but the force's jumps at contact switches fall between samples at any "
            "interval (a finer one can read a peak lower); for the steady state's true peaks "
            f"`herringbone sweep {named_as_typed(scene)} --speeds FROM TO COUNT` about "
            f"w0_pinion = {speed:g} rad/s"]


def _two_digits_down(value: float) -> float:
    """`value` (> 0) cut to two significant digits, never rounded up: 9.47e-06 -> 9.4e-06."""
    unit = 10.0 ** (math.floor(math.log10(value)) - 1)
    return math.floor(value / unit * (1.0 + 1e-12)) * unit


# the model's contact: one engaged tooth pair, loaded on its working flanks only (docs/model.md)
MODEL_CONTACT = ("the model (one engaged tooth pair, no back flank, no re-engagement at the "
                 "next tooth) does not describe that, and the outputs from there on are not "
                 "the gear's")


def slip_notes(scene, results: dict) -> list[str]:
    """A line where the run has left what the model describes: the transmission error's swing
    (dte's range so far) past a tooth pitch on the pitch circle, π·m_n/cos β (dte is
    Rp·φp − Rw·φw: one pitch is the pinion a tooth ahead of or behind the wheel); and one
    where no tooth is in contact from some time to the end of the run, for longer than a
    period of the slowest natural mode (not a bounce: the pinion runs free of the wheel)."""
    from ..model.geometry import GearGeometry

    geometry = GearGeometry.from_parameters(scene.parameters)
    pitch = geometry.radius_pinion * geometry.angular_pitch
    times, dte = results["time"], results["dte"]
    swing = np.maximum.accumulate(dte) - np.minimum.accumulate(dte)
    past = np.flatnonzero(swing > pitch)
    lines = []
    if past.size:
        first = past[0]
        lines.append(f"From t = {times[first]:.4g} s the transmission error has swung over "
                     f"{1e3 * swing[first]:.3g} mm, more than a tooth pitch ("
                     f"{1e3 * pitch:.3g} mm on the pitch circle, π·m_n/cos β): the pinion has "
                     f"slipped a tooth or more against the wheel; {MODEL_CONTACT}")
    lost = _contact_lost_to_the_end(scene, times, results["n_contacts"])
    if lost is not None:
        lines.append(f"From t = {lost:.4g} s to the end ({times[-1] - lost:.3g} s) no tooth is "
                     "in contact: the pinion runs free of the wheel, where a real pair meets "
                     f"the back flank or the next tooth; {MODEL_CONTACT}")
    return lines


def _contact_lost_to_the_end(scene, times, contacts) -> float | None:
    """The time (s) from which no tooth is in contact at any sample to the end of the run,
    where contact was made before and the span is longer than a period of the slowest
    natural mode; else None."""
    from ..analysis.campbell import elastic_frequencies

    held = np.flatnonzero(np.asarray(contacts) > 0)
    if contacts[-1] > 0 or held.size == 0:
        return None
    since = float(times[held[-1] + 1])
    elastic = elastic_frequencies(scene)
    if elastic.size == 0 or times[-1] - since <= 1.0 / elastic.min():
        return None
    return since
