"""Extreme scenes through the FMU, and a long run that must not drift (issue 5).

1. Every scene in models/ (or --scenes) through its FMU at the FMU's default settings, the
   communication step being the scene's output interval, over the scene's stop time (times
   --span-scale, at most --max-span): wall time per simulated second, internal steps per
   simulated second where the FMU reports them (a step-size collapse shows there), and the error
   against the reference integration (cached under results/).
2. The long run: N mesh periods of the torsional train (models/long_run.toml, else
   models/torsional.toml) at communication step 1e-3 s with balanced torques
   M_load = u·M_motor, so the run is periodic. Recorded at a fine step over a window of mesh
   periods at the start and at the end: mean speeds against the rigid-body law, mean mesh force
   against the static one, and the mesh-force fluctuation (max − min) at the start and the end.

Writes extreme_scenes.csv and extreme_scenes.md to the output directory.

    python benchmarks/extreme_scenes.py --quick                           # a quick check
    python benchmarks/extreme_scenes.py                                   # 10^4 periods
    python benchmarks/extreme_scenes.py --no-scenes --periods 1000000     # the issue's long run
    python benchmarks/extreme_scenes.py --fmu-methods dop853 exponential  # a row for each
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402


def scene_rows(scene_paths, span_scale=1.0, max_span=1.0, budget=math.inf,
               reference_tolerance=1e-12, fmu_methods=(None,), log=print) -> list[dict]:
    """One row per scene and FMU solver_method (None: the FMU's default), each against the
    reference of its scene."""
    import herringbone

    rows = []
    for path in scene_paths:
        scene = herringbone.load_scene(path)
        step = scene.experiment.output_interval
        span = min(scene.experiment.stop_time * span_scale, max_span)
        span = max(round(span / step), 1) * step  # a whole number of communication steps
        log(f"{scene.name}: {span:g} s at communication step {step:g} s")
        reference = common.cached_reference(path, span, step, reference_tolerance, log=log)
        try:
            fmu_dir = common.scene_fmu(path, log=log)
        except common.BuildError as error:
            log(f"  {error}")
            rows += [failed_row(scene, step, span, method, reference, str(error))
                     for method in fmu_methods]
            continue
        rows += [fmu_row(scene, fmu_dir, step, span, method, reference, budget, log)
                 for method in fmu_methods]
    return rows


def failed_row(scene, step, span, method, reference, status) -> dict:
    """The row of a scene whose FMU could not be built."""
    return dict(scene=scene.name, method=method or "default", comm_step=step,
                span_requested=span, span_simulated=0.0, wall_s=math.nan,
                wall_per_sim_s=math.nan, startup_s=math.nan, first_startup_s=math.nan,
                error=math.nan, internal_steps="", steps_per_sim_s="",
                reference_wall_per_sim_s=float(reference["wall"]), status=status)


def fmu_row(scene, fmu_dir, step, span, method, reference, budget, log) -> dict:
    """One scene through its FMU with solver_method `method` (None: the FMU's default):
    wall time, start-up, internal steps and the error against the reference."""
    forces, scale = common.force_outputs(scene), common.force_scale(scene)
    start_values = {} if method is None else {"solver_method": method}
    warm_up = common.run_fmu(fmu_dir, common.input_schedule(scene), [(step, step, False)],
                             [], start_values=start_values, budget=budget)
    result = common.run_fmu(fmu_dir, common.input_schedule(scene), [(span, step, True)],
                            forces, start_values=start_values, budget=budget)
    reached = result["reached"]
    error = common.force_error(result["time"], {n: result[n] for n in forces}, reference,
                               scale) if len(result["time"]) > 1 else math.nan
    steps = result["internal_steps"]
    row = dict(scene=scene.name, method=method or "default", comm_step=step,
               span_requested=span, span_simulated=reached, wall_s=result["wall"],
               wall_per_sim_s=result["wall"] / reached if reached else math.nan,
               startup_s=result["startup"], first_startup_s=warm_up["startup"],
               error=error, internal_steps=steps if steps is not None else "",
               steps_per_sim_s=steps / reached if steps and reached else "",
               reference_wall_per_sim_s=float(reference["wall"]), status=result["status"])
    log(f"  FMU ({row['method']}): {row['status']}, {reached:g} s in {row['wall_s']:.3g} s "
        f"({row['wall_per_sim_s']:.3g} s/s), start-up {row['startup_s']:.3g} s "
        f"(first {row['first_startup_s']:.3g} s), error {error:.3g}"
        + (f", {row['steps_per_sim_s']:.4g} internal steps/s" if row["steps_per_sim_s"]
           else ""))
    return row


def long_run(scene_path, periods=10_000, step=1e-3, window_periods=25, window_step=1e-5,
             budget=math.inf, log=print) -> dict:
    """`periods` mesh periods at `step`, with `window_periods` recorded every `window_step` at
    the start and at the end. Returns the figures of drift (see the module docstring)."""
    import herringbone
    from herringbone.model.assembly import output_names
    from herringbone.model.geometry import GearGeometry

    scene = herringbone.load_scene(scene_path)
    geometry = GearGeometry.from_parameters(scene.parameters)
    speed = scene.parameters["w0_pinion"]
    if speed <= 0:
        raise SystemExit(f"extreme_scenes: {scene_path} starts at rest; the long run needs "
                         "a running train (w0_pinion > 0)")
    period = geometry.angular_pitch / speed
    motor_torque = scene.inputs.M_motor[0]
    load_torque = geometry.ratio * motor_torque  # balanced: the run is periodic
    inputs = {"times": [0.0], "M_motor": [motor_torque], "M_load": [load_torque]}
    stop_time = periods * period
    window = min(window_periods, periods / 2) * period
    legs = [(window, window_step, True), (stop_time - window, step, False),
            (stop_time, window_step, True)]
    record = ["F_mesh", "dte"] + [n for n in ("w_motor", "w_pinion", "w_wheel", "w_load")
                                  if n in output_names(scene)]
    log(f"long run: {scene.name}, {periods:g} mesh periods of {period * 1e3:.4g} ms = "
        f"{stop_time:.6g} s at step {step:g} s, M_motor {motor_torque:g}, M_load "
        f"{load_torque:g} N·m; windows of {window:.4g} s every {window_step:g} s")
    fmu_dir = common.scene_fmu(scene_path, log=log)
    common.run_fmu(fmu_dir, inputs, [(step, step, False)], [])  # warm-up: compile once
    result = common.run_fmu(fmu_dir, inputs, legs, record, budget=budget)
    figures = dict(scene=scene.name, periods=periods, period_s=period, stop_time=stop_time,
                   comm_step=step, reached=result["reached"], wall_s=result["wall"],
                   wall_per_sim_s=result["wall"] / result["reached"] if result["reached"]
                   else math.nan, status=result["status"],
                   internal_steps=result["internal_steps"])
    if result["status"] != "ok":
        log(f"  long run: {result['status']} at t = {result['reached']:g} s")
        return figures
    times = result["time"]
    static_force = motor_torque / geometry.radius_pinion
    rigid = {"w_motor": speed, "w_pinion": speed, "w_wheel": speed / geometry.ratio,
             "w_load": speed / geometry.ratio}
    # Balanced torques: no net torque on the rigid rotation r (every element has g·r = 0), so
    # its momentum rᵀ·M·q̇ is conserved exactly, vibrations or not; the speed it implies must
    # stay w0 at every instant, a sharper test of drift than any mean.
    inertia = {"w_motor": "I_motor", "w_pinion": "I_pinion", "w_wheel": "I_wheel",
               "w_load": "I_load"}
    speeds = [n for n in record if n.startswith("w_")]
    momentum_weights = {n: scene.parameters[inertia[n]] * rigid[n] / speed for n in speeds}
    total_inertia = sum(momentum_weights[n] * rigid[n] / speed for n in speeds)
    for label, inside in (("start", times <= window * (1 + 1e-9)),
                          ("end", times >= (stop_time - window) * (1 - 1e-12))):
        t = times[inside]
        if {"w_pinion", "w_wheel"} <= set(speeds) and (scene.has("motor") == (
                "w_motor" in speeds)) and (scene.has("load") == ("w_load" in speeds)):
            rigid_speed = sum(momentum_weights[n] * result[n][inside] for n in speeds) \
                / total_inertia
            figures[f"{label}_rigid_speed_rel"] = float(np.max(np.abs(rigid_speed / speed - 1)))
        for name in record:
            values = result[name][inside]
            mean = np.trapezoid(values, t) / (t[-1] - t[0])
            if name == "dte":  # a drift of speed would show as a drift of this angle
                figures[f"{label}_dte_um"] = mean * 1e6
            elif name == "F_mesh":
                figures[f"{label}_mean_force_rel"] = mean / static_force - 1
                figures[f"{label}_force_fluctuation_rel"] = (values.max() - values.min()) \
                    / static_force
            else:
                figures[f"{label}_{name}_rel"] = mean / rigid[name] - 1
    figures["fluctuation_end_over_start"] = (figures["end_force_fluctuation_rel"]
                                             / figures["start_force_fluctuation_rel"])
    log(f"  long run: {figures['reached']:g} s in {figures['wall_s']:.3g} s "
        f"({figures['wall_per_sim_s']:.3g} s/s)")
    for key, value in figures.items():
        if key.startswith(("start_", "end_", "fluctuation")):
            log(f"    {key}: {value:.3g}")
    return figures


def markdown_report(rows, long, command, reference_tolerance) -> str:
    lines = ["# Extreme scenes and a long run through the FMU", "",
             *common.machine_record(command), ""]
    if rows:
        bases = {r["method"]: r for r in rows if r["scene"] == "reference"}
        lines += ["Each scene through its FMU at the FMU's default settings (but solver_method "
                  "where the FMU method column names one), communication step "
                  "= the scene's output interval. Error: the largest |x − x_ref| of F_mesh and "
                  "the bearing reactions at the communication points, relative to the static "
                  f"mesh force; reference: `reference_simulate` at tolerance "
                  f"{reference_tolerance:g}. Wall time: stepping only. Start-up: instantiate + "
                  "initialize in a fresh process with compiled code cached (first: the very "
                  "first start of that FMU).", ""]
        table = [[r["scene"], r["method"],
                  f"{r['span_simulated']:g}" + ("" if r["status"] == "ok" else "*"),
                  f"{r['comm_step']:g}", common.number(r["error"]),
                  common.number(r["wall_per_sim_s"]),
                  common.number(r["wall_per_sim_s"] / bases[r["method"]]["wall_per_sim_s"])
                  if r["method"] in bases else "—",
                  common.number(r["steps_per_sim_s"] or None),
                  f"{common.number(r['startup_s'])} ({common.number(r['first_startup_s'])})",
                  common.number(r["reference_wall_per_sim_s"]), r["status"]]
                 for r in rows]
        lines += common.markdown_table(["scene", "FMU method", "simulated s", "comm. step s",
                                        "error",
                                        "wall s/s", "cost ÷ reference scene's",
                                        "internal steps/s", "start-up s (first)",
                                        "reference integration s/s", "status"], table)
        lines.append("")
    if long:
        lines += [f"## Long run: {long['scene']}, {long['periods']:g} mesh periods "
                  f"({long['stop_time']:.6g} s), communication step {long['comm_step']:g} s, "
                  "M_load = u·M_motor", "",
                  f"Status {long['status']}; {long['reached']:.6g} s simulated in "
                  f"{long['wall_s']:.4g} s of wall time ({common.number(long['wall_per_sim_s'])} "
                  f"s/s)" + (f", {long['internal_steps']} internal steps" if
                             long.get("internal_steps") else "") + ".", ""]
        if "end_mean_force_rel" in long:
            quantities = [("mean F_mesh / (M_motor/Rp) − 1", "mean_force_rel"),
                          ("(max − min F_mesh) / (M_motor/Rp)", "force_fluctuation_rel")]
            if "start_rigid_speed_rel" in long:
                quantities.append(("largest deviation of the momentum speed from w0, "
                                   "relative (conserved exactly)", "rigid_speed_rel"))
            quantities.append(("mean dte (Rp·φp − Rw·φw), µm", "dte_um"))
            quantities += [(f"mean {n} / rigid-body speed − 1", f"{n}_rel")
                           for n in ("w_motor", "w_pinion", "w_wheel", "w_load")
                           if f"start_{n}_rel" in long]
            digits = {"dte_um": 6}  # a drift of the angle shows in the last digits
            table = [[label, common.number(long[f"start_{key}"], digits.get(key, 3)),
                      common.number(long[f"end_{key}"], digits.get(key, 3))]
                     for label, key in quantities]
            lines += common.markdown_table(["figure (over a window of whole mesh periods)",
                                            "start", "end"], table)
            lines += ["", f"Fluctuation at the end ÷ at the start: "
                          f"{common.number(long['fluctuation_end_over_start'])}.", ""]
    return "\n".join(lines) + "\n"


def main(argv=None, prog="extreme_scenes.py") -> int:
    """Exit code 0; 2, with one line on stderr, for a bad option (checked before any run).
    `prog`: the command as the user typed it, which usage and messages name."""
    from herringbone.arguments import (
        POSITIVE,
        REFERENCE_TOLERANCE_ARGUMENT,
        Argument,
        OneLineParser,
        Range,
        output_folder,
    )

    def positive(meaning, infinite=False):
        return Argument(meaning, None, meaning, POSITIVE, infinite=infinite).option_type

    parser = OneLineParser(prog=prog, description=__doc__.split("\n")[0],
                           help_command="herringbone benchmark extreme-scenes --help")
    parser.add_argument("--scenes", nargs="+", default=["models/*.toml"],
                        help="scene names, files or globs (default: models/*.toml)")
    parser.add_argument("--no-scenes", action="store_true", help="only the long run")
    parser.add_argument("--fmu-methods", nargs="+", default=None,
                        choices=("auto", "dop853", "radau", "exponential"),
                        help="FMU solver_method values, a row each per scene (default: the "
                             "FMU's own default)")
    parser.add_argument("--span-scale", type=positive("fraction of the stop time"),
                        help="simulate this fraction of each scene's stop time (default 1)")
    parser.add_argument("--max-span", type=positive("simulated seconds"), default=1.0,
                        help="at most this many simulated seconds per scene (default 1)")
    parser.add_argument("--budget", type=positive("wall seconds", infinite=True), default=600.0,
                        help="wall seconds per FMU run before it is stopped (default 600)")
    parser.add_argument("--reference-tolerance",
                        type=REFERENCE_TOLERANCE_ARGUMENT.option_type, default=1e-12)
    parser.add_argument("--long-scene", type=Path, default=None,
                        help="scene of the long run (default: models/long_run.toml, else "
                             "models/torsional.toml)")
    parser.add_argument("--periods",
                        type=Argument("periods", None, "mesh periods; 0: no long run",
                                      Range(0.0)).option_type,
                        help="mesh periods of the long run (default 1e4; 0: no long run)")
    parser.add_argument("--long-step", type=positive("seconds"), default=1e-3,
                        help="communication step of the long run (default 1e-3 s)")
    parser.add_argument("--long-budget", type=positive("wall seconds", infinite=True),
                        default=math.inf,
                        help="wall seconds before the long run is stopped (default: none)")
    parser.add_argument("--window-periods", type=positive("mesh periods"),
                        help="mesh periods recorded at the start and at the end (default 25)")
    parser.add_argument("--window-step", type=positive("seconds"), default=1e-5,
                        help="communication step inside the recorded windows (default 1e-5 s)")
    parser.add_argument("--output-dir", type=output_folder, default=common.DEFAULT_OUTPUT_DIR,
                        help="where the CSV and markdown go (default results/benchmark; FMUs "
                             "and references are cached there whatever this says)")
    parser.add_argument("--quick", action="store_true",
                        help="a short check: --span-scale 0.1 --periods 100 --window-periods 5")
    args = parser.parse_args(argv)
    for name, full, quick in (("span_scale", 1.0, 0.1), ("periods", 1e4, 100),
                              ("window_periods", 25, 5)):
        if getattr(args, name) is None:
            setattr(args, name, quick if args.quick else full)
    # every scene found before any run: a long benchmark never ends on a misspelt name
    scenes = [] if args.no_scenes else common.scene_paths(args.scenes, parser)
    if args.periods > 0 and args.long_scene is not None:
        args.long_scene = common.scene_paths([str(args.long_scene)], parser, "--long-scene")[0]
    command = common.command_line(__file__, sys.argv[1:] if argv is None else argv)

    def log(text):
        print(text, flush=True)

    rows = [] if args.no_scenes else scene_rows(
        scenes, span_scale=args.span_scale, max_span=args.max_span,
        budget=args.budget, reference_tolerance=args.reference_tolerance,
        fmu_methods=args.fmu_methods or [None], log=log)
    long = None
    if args.periods > 0:
        long_scene = args.long_scene or next(
            p for p in (common.MODELS / "long_run.toml", common.MODELS / "torsional.toml")
            if p.is_file())
        long = long_run(long_scene, periods=args.periods, step=args.long_step,
                        window_periods=args.window_periods, window_step=args.window_step,
                        budget=args.long_budget, log=log)
    output = Path(args.output_dir)
    if rows:
        common.write_csv(rows, output / "extreme_scenes.csv")
    if long:
        common.write_csv([long], output / "long_run.csv")
    report = markdown_report(rows, long, command, args.reference_tolerance)
    (output / "extreme_scenes.md").write_text(report, encoding="utf-8")
    print(report)
    print(f"written to {output}: " + ", ".join(
        name for name, wanted in (("extreme_scenes.csv", rows), ("long_run.csv", long),
                                  ("extreme_scenes.md", True)) if wanted))
    return 0


if __name__ == "__main__":
    sys.exit(main())
