"""The `herringbone` command: `run` a scene through the reference integration, `info` on a scene,
`stability` chart of a scene, `benchmark` the FMU against scipy (from a source checkout)."""
from __future__ import annotations

import csv
import sys
import time
from pathlib import Path

from .arguments import (OUTPUT_INTERVAL, REFERENCE_TOLERANCE_ARGUMENT, STOP_TIME, OneLineParser,
                        number, output_path, output_path_problem, speed_sweep_problem)
from .scene import SceneError, load_scene

# The benchmarks are repository tools (they build FMUs with build_fmu.py), not part of the package.
BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
BENCHMARK_SCRIPTS = {"error-vs-runtime": "error_vs_runtime", "extreme-scenes": "extreme_scenes"}


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
    try:
        if args.command == "info":
            from .report import info_main
            return info_main([str(args.scene)])
        if args.command == "stability":
            return _stability(args, commands["stability"])
        return _run(args, commands["run"])
    except SceneError as error:
        print(f"herringbone: {error}", file=sys.stderr)
        return 2


def _run(args, parser) -> int:
    from .run_progress import reference_simulate_with_progress

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
        from .sweep_cli import plot_run
        print("\n".join(f"written: {path}" for path in plot_run(scene, results, output)))
    return 0


def _stability(args, parser) -> int:
    import numpy as np

    from .stability import plot_stability_chart, stability_chart

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
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main(arguments)


def write_csv(results: dict, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    names = list(results)
    with open(path, "w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(names)
        for row in zip(*(results[name] for name in names)):
            writer.writerow([f"{value:.12g}" for value in row])


def summary(scene, results: dict, wall_time: float) -> str:
    from .model import GearTrainModel

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
