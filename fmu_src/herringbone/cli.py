"""The `herringbone` command: `run` a scene through the reference integration, `info` on a scene,
`stability` chart of a scene, `sweep`, `campbell`, `build-fmu` (the FMU of a scene), `scenes`
(the shipped scenes), `benchmark` the FMU against scipy (from a source checkout). SCENE is a
scene file or the name of a shipped scene."""
from __future__ import annotations

import csv
import sys
import time
from pathlib import Path

from .arguments import (
    OUTPUT_INTERVAL,
    REFERENCE_TOLERANCE_ARGUMENT,
    STOP_TIME,
    OneLineParser,
    number,
    output_path,
    output_path_problem,
    speed_sweep_problem,
)
from .model.scene import SceneError, load_scene

# The benchmarks are repository tools (they build FMUs with build_fmu.py), not part of the package.
BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
BENCHMARK_SCRIPTS = {"error-vs-runtime": "error_vs_runtime", "extreme-scenes": "extreme_scenes"}
SCENE_HELP = "scene file (TOML), or the name of a shipped scene (`herringbone scenes`)"


def main(argv=None) -> int:
    """Exit code 0 on success; 2, with one line on stderr naming the argument and what is
    allowed, for a bad argument or scene (checked before any work)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["benchmark"]:  # its options belong to the script: argparse must not see them
        return _benchmark(argv[1:])
    parser, commands, added_commands = _parser()
    args = parser.parse_args(argv)
    if args.command in added_commands:
        return added_commands[args.command](args)
    if args.command == "build-fmu":
        from .fmu.builder import build_command
        return build_command(args, commands["build-fmu"])
    if args.command == "scenes":
        from .shipped import scene_list
        print("\n".join(scene_list()))
        return 0
    try:
        if args.command == "info":
            from .analysis.report import info_main
            return info_main([str(args.scene)])
        if args.command == "stability":
            return _stability(args, commands["stability"])
        return _run(args, commands["run"])
    except SceneError as error:
        print(f"herringbone: {error}", file=sys.stderr)
        return 2


def _parser():
    """The parser and its command parsers; every value is checked by its `type=` (arguments.py),
    and every error is one line (OneLineParser)."""
    parser = OneLineParser(prog="herringbone", description=__doc__)
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = subparsers.add_parser("run", help="simulate a scene with the reference integration, "
                                "print a summary and write a CSV of the outputs")
    run.add_argument("scene", type=Path, metavar="SCENE", help=SCENE_HELP)
    run.add_argument("--stop-time", type=STOP_TIME.option_type,
                     help="simulated seconds (default: the scene's)")
    run.add_argument("--output-interval", type=OUTPUT_INTERVAL.option_type,
                     help="seconds between output samples, at most the stop time "
                          "(default: the scene's)")
    tolerance = REFERENCE_TOLERANCE_ARGUMENT.allowed
    run.add_argument("--tolerance", type=REFERENCE_TOLERANCE_ARGUMENT.option_type, default=1e-10,
                     help="error per step relative to the static mesh force, "
                          f"{tolerance.low:g} to {tolerance.high:g} (default 1e-10)")
    run.add_argument("-o", "--output", type=output_path,
                     help="CSV file to write (default: results/<scene>.csv)")
    info = subparsers.add_parser("info", help="geometry, mesh phase and modes of a scene")
    info.add_argument("scene", type=Path, metavar="SCENE", help=SCENE_HELP)
    stability = subparsers.add_parser("stability", help="Floquet chart: the largest multiplier "
                                      "of the linear mesh against pinion speed, with its "
                                      "unstable bands (PNG and a list of the bands)")
    stability.add_argument("scene", type=Path, metavar="SCENE", help=SCENE_HELP)
    stability.add_argument("--speeds", type=number, nargs=3, default=(50.0, 3000.0, 300),
                           metavar=("FROM", "TO", "COUNT"),
                           help="pinion speeds, rad/s: 0 < FROM < TO, COUNT >= 2 speeds "
                                "(default 50 3000 300)")
    stability.add_argument("-o", "--output", type=output_path,
                           help="PNG to write (default: results/<scene>_stability.png)")
    build = subparsers.add_parser("build-fmu", help="build the FMI 2.0 (--fmi 3: 3.0) "
                                  "co-simulation FMU of a scene (or --examples DIR: the motor "
                                  "and fan FMUs)")
    from .fmu.builder import add_arguments
    add_arguments(build)
    subparsers.add_parser("scenes", help="list the shipped scenes: name and what each tests")
    subparsers.add_parser("benchmark", help="[error-vs-runtime | extreme-scenes] [OPTIONS]: run "
                          "benchmarks/error_vs_runtime.py (the default) or "
                          "benchmarks/extreme_scenes.py of the source checkout; "
                          "`herringbone benchmark --help` lists the options")
    # sweep, campbell and run --plot: their handlers live in sweep_cli.py
    from .analysis.sweep_cli import register
    added_commands = register(subparsers)
    return parser, {"run": run, "stability": stability, "build-fmu": build}, added_commands


def _output(parser, given, default: Path) -> Path:
    """The file to write: `given` (checked by its type) or `default`, which is checked here."""
    if given is not None:
        return given
    problem = output_path_problem(default)
    if problem is not None:
        parser.error(f"cannot write {default}: {problem}; give -o FILE in a folder you can "
                     "write in")
    return default


def _run(args, parser) -> int:
    from .analysis.run_progress import reference_simulate_with_progress

    scene = load_scene(args.scene)
    stop_time = args.stop_time or scene.experiment.stop_time
    interval = args.output_interval or scene.experiment.output_interval
    if interval > stop_time:
        parser.error(f"--output-interval {interval:g} s is longer than the stop time "
                     f"{stop_time:g} s; allowed: > 0 and <= the stop time (give a shorter "
                     "--output-interval or a longer --stop-time)")
    output = _output(parser, args.output, Path("results") / f"{scene.name}.csv")
    started = time.perf_counter()
    results = reference_simulate_with_progress(scene, stop_time=args.stop_time,
                                               output_interval=args.output_interval,
                                               tolerance=args.tolerance,
                                               progress=not args.no_progress)
    wall = time.perf_counter() - started
    write_csv(results, output)
    print(summary(scene, results, wall))
    print(f"outputs written to {output}")
    if args.plot:
        from .analysis.sweep_cli import plot_run
        print("\n".join(f"written: {path}" for path in plot_run(scene, results, output)))
    return 0


def _stability(args, parser) -> int:
    import numpy as np

    from .analysis.stability import plot_stability_chart, stability_chart

    low, high, count = args.speeds
    problem = speed_sweep_problem(low, high, count)
    if problem is not None:
        parser.error(f"--speeds {low:g} {high:g} {count:g}: {problem}; allowed: "
                     "0 < FROM < TO (rad/s), COUNT >= 2 speeds")
    scene = load_scene(args.scene)
    output = _output(parser, args.output, Path("results") / f"{scene.name}_stability.png")
    chart = stability_chart(scene, np.linspace(low, high, int(count)))
    output.parent.mkdir(parents=True, exist_ok=True)
    plot_stability_chart(chart, output, title=f"{scene.name}: parametric stability")
    rpm = 60.0 / (2.0 * np.pi)
    print(f"largest multiplier |λ|max from {chart.largest_modulus.min():.6g} to "
          f"{chart.largest_modulus.max():.6g} over {low:g}-{high:g} rad/s")
    for band_low, band_high in chart.unstable_bands:
        print(f"unstable: {band_low:.1f}-{band_high:.1f} rad/s "
              f"({band_low * rpm:.0f}-{band_high * rpm:.0f} rpm)")
    if not chart.unstable_bands:
        print("no unstable band: every multiplier inside the unit circle")
    print(f"chart written to {output}")
    return 0


def _benchmark(arguments: list[str]) -> int:
    import importlib.util

    if arguments[:1] and not arguments[0].startswith("-") \
            and arguments[0] not in BENCHMARK_SCRIPTS:
        print(f"herringbone benchmark: unknown benchmark {arguments[0]!r}; allowed: "
              f"{', '.join(BENCHMARK_SCRIPTS)} (`herringbone benchmark --help` lists the "
              "options)", file=sys.stderr)
        return 2
    name = arguments.pop(0) if arguments[:1] and arguments[0] in BENCHMARK_SCRIPTS \
        else "error-vs-runtime"
    script = BENCHMARKS / f"{BENCHMARK_SCRIPTS[name]}.py"
    if not script.is_file():
        print(f"herringbone: benchmark needs the source checkout: {script} is not there (this "
              "herringbone was installed without its repository); clone the repository, "
              "`pip install -e .` it and run `herringbone benchmark` from there", file=sys.stderr)
        return 2
    spec = importlib.util.spec_from_file_location(f"benchmarks_{script.stem}", script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main(arguments)


def write_csv(results: dict, path: Path) -> None:
    """A run's outputs ({name: samples}) as CSV, one column a name, 12 significant digits."""
    path.parent.mkdir(parents=True, exist_ok=True)
    names = list(results)
    with open(path, "w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(names)
        for row in zip(*(results[name] for name in names)):
            writer.writerow([f"{value:.12g}" for value in row])


def summary(scene, results: dict, wall_time: float) -> str:
    """A few lines on a finished run: its span, the largest forces and the time it took."""
    from .model.assembly import GearTrainModel

    model = GearTrainModel(scene)
    stop = results["time"][-1]
    static_force = scene.inputs.M_motor[0] / model.geometry.radius_pinion
    lines = [f"scene {scene.name} ({scene.source}): {model.size} degrees of freedom "
             f"({', '.join(model.coordinates)})",
             f"simulated {stop:g} s in {wall_time:.2f} s of wall time "
             f"({wall_time / stop:.1f} s per simulated second)",
             f"static mesh force M_motor/Rp = {static_force:.1f} N",
             # no mean: samples synchronous with the mesh period alias its fast content
             f"{'output':<20}{'at t=0':>14}{'min of samples':>16}{'max of samples':>16}"
             f"{'at the end':>14}"]
    for name, values in results.items():
        if name != "time":
            lines.append(f"{name:<20}{values[0]:>14.6g}{values.min():>16.6g}"
                         f"{values.max():>16.6g}{values[-1]:>14.6g}")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
