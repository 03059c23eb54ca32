"""Error against wall time: the gear FMU (through fmpy) and scipy's solve_ivp on the same model.

For each scene: the FMU at every solver tolerance and communication step, and scipy's RK45,
DOP853, Radau, BDF and LSODA at every tolerance (herringbone's ScipyStepper: the same model and
the same restarts at every contact switch as the reference), all judged against the reference
integration (reference_simulate at a tight tolerance, cached under results/). Writes
benchmark.csv (one row per configuration), error_vs_runtime.png (log-log, error against wall
time per simulated second) and benchmark.md (the tables, the goals of issue 4, the machine).

    python benchmarks/error_vs_runtime.py --quick              # a minute: the pipeline works
    python benchmarks/error_vs_runtime.py                      # the shipped scenes, 0.2 s
    python benchmarks/error_vs_runtime.py --stop-time 1        # the issue's figures
    python benchmarks/error_vs_runtime.py --stop-time 1 --fmu-methods auto dop853 radau
    herringbone benchmark [the same options]                    # the same, installed
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402
from tqdm import tqdm  # noqa: E402

SCIPY_METHODS = ("RK45", "DOP853", "Radau", "BDF", "LSODA")
SHIPPED_SCENES = ("reference", "torsional", "staggered", "lead_error")
FULL = dict(scenes=[s for s in SHIPPED_SCENES if (common.MODELS / f"{s}.toml").is_file()],
            stop_time=0.2, steps=[1e-5, 1e-4, 1e-3, 1e-2],
            tolerances=[1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
            methods=["fmu", *SCIPY_METHODS], budget=120.0)
QUICK = dict(scenes=["reference"], stop_time=0.01, steps=[1e-4, 1e-3], tolerances=[1e-6, 1e-8],
             methods=["fmu", "RK45", "DOP853"], budget=60.0)


def benchmark_scene(scene_path, stop_time, steps, tolerances, methods, fmu_methods=(None,),
                    scipy_step=1e-3, budget=math.inf, reference_tolerance=1e-12, repeat=3,
                    log=print, done=lambda: None) -> list[dict]:
    """One row per configuration (see the module docstring) of one scene file; `done()` is
    called as each row is made (a progress bar's step). Each FMU
    configuration runs `repeat` times, in a fresh process each, and gives the run of median
    wall time: a run of 0.02 s of wall time can take half as long again when the machine
    stirs. (scipy's runs take seconds each and run once.)"""
    import herringbone

    scene = herringbone.load_scene(scene_path)
    forces, scale = common.force_outputs(scene), common.force_scale(scene)
    log(f"{scene.name}: {stop_time:g} s simulated, error over {', '.join(forces)} "
        f"relative to {scale:.1f} N")
    references = {}
    for interval in sorted(set(steps if "fmu" in methods else []) | {scipy_step}):
        # the finest first: the coarser ones are then read from its cache
        references[interval] = common.cached_reference(scene_path, stop_time, interval,
                                                        reference_tolerance, log=log)

    def row(integrator, method, tolerance, step, result, default=False):
        reached = result["reached"]
        error = (common.force_error(result["time"], {n: result[n] for n in forces},
                                    references[step], scale)
                 if len(result["time"]) > 1 else math.nan)
        steps_taken = result["internal_steps"]
        entry = dict(scene=scene.name, integrator=integrator, method=method,
                     tolerance=tolerance, default=default, comm_step=step,
                     span_requested=stop_time, span_simulated=reached, wall_s=result["wall"],
                     wall_per_sim_s=result["wall"] / reached if reached > 0 else math.nan,
                     startup_s=result["startup"], error=error,
                     internal_steps=steps_taken if steps_taken is not None else "",
                     steps_per_sim_s=steps_taken / reached if steps_taken and reached else "",
                     status=result["status"])
        log(f"  {integrator} {method} tolerance {tolerance:g} step {step:g}: {result['status']}, "
            f"{reached:g} s in {entry['wall_s']:.3g} s ({entry['wall_per_sim_s']:.3g} s/s), "
            f"start-up {entry['startup_s']:.3g} s, error {error:.3g}"
            + (f", {entry['steps_per_sim_s']:.4g} internal steps/s" if entry["steps_per_sim_s"]
               else ""))
        return entry

    rows = []

    def add(entry):
        rows.append(entry)
        done()

    try:
        fmu_dir = common.scene_fmu(scene_path, log=log) if "fmu" in methods else None
    except common.BuildError as error:
        log(f"  {error}")
        add({**_skipped(scene, "FMU", "default", math.nan, math.nan, stop_time),
                     "status": str(error)})
        fmu_dir = None
    if fmu_dir is not None:
        variables = common.fmu_variables(fmu_dir)
        default_tolerance = float(variables["solver_tolerance"].start)
        default_method = getattr(variables.get("solver_method"), "start", None)
        warm_up = common.run_fmu(fmu_dir, common.input_schedule(scene), [(1e-3, 1e-4, False)],
                                 [], budget=budget)
        log(f"  FMU warm-up (first start-up, compiles what is not cached): "
            f"{warm_up['startup']:.3g} s, {warm_up['status']}")
        for fmu_method in fmu_methods:
            if fmu_method is not None and "solver_method" not in variables:
                log(f"  FMU solver_method {fmu_method}: this FMU has no solver_method; skipped")
                continue
            label = "default" if fmu_method is None else fmu_method
            for step in steps:
                over_budget = False
                for tolerance in sorted(set(tolerances) | {default_tolerance}, reverse=True):
                    if over_budget:  # tighter only costs more
                        add(_skipped(scene, "FMU", label, tolerance, step, stop_time))
                        continue
                    start_values = {"solver_tolerance": tolerance}
                    if fmu_method is not None:
                        start_values["solver_method"] = fmu_method
                    runs = []
                    while len(runs) < repeat and (not runs or runs[-1]["status"] == "ok"):
                        runs.append(common.run_fmu(fmu_dir, common.input_schedule(scene),
                                                   [(stop_time, step, True)], forces,
                                                   start_values, budget=budget))
                    result = sorted(runs, key=lambda r: r["wall"])[len(runs) // 2]
                    add(row("FMU", label, tolerance, step, result,
                                    default=fmu_method in (None, default_method)
                                    and tolerance == default_tolerance))
                    over_budget = result["status"] != "ok"
    for method in (m for m in methods if m != "fmu"):
        over_budget = False
        for tolerance in sorted(tolerances, reverse=True):
            if over_budget:
                add(_skipped(scene, "solve_ivp", method, tolerance, scipy_step, stop_time))
                continue
            result = common.run_scipy(scene, method, tolerance, stop_time, scipy_step, forces,
                                      budget=budget)
            add(row("solve_ivp", method, tolerance, scipy_step, result))
            over_budget = result["status"] != "ok"
    return rows


def _skipped(scene, integrator, method, tolerance, step, stop_time):
    return dict(scene=scene.name, integrator=integrator, method=method, tolerance=tolerance,
                default=False, comm_step=step, span_requested=stop_time, span_simulated=0.0,
                wall_s=math.nan, wall_per_sim_s=math.nan, startup_s=math.nan, error=math.nan,
                internal_steps="", steps_per_sim_s="",
                status="skipped: a looser tolerance exceeded the budget")


def measured(rows):
    return [r for r in rows if math.isfinite(r["error"]) and math.isfinite(r["wall_per_sim_s"])]


def cheapest(rows, error_limit):
    """The row of least wall time per simulated second with error <= error_limit, or None."""
    good = [r for r in measured(rows) if r["error"] <= error_limit]
    return min(good, key=lambda r: r["wall_per_sim_s"]) if good else None


def markdown_report(rows, reference_tolerance, command) -> str:
    lines = ["# Error against wall time: the gear FMU and scipy's solve_ivp", "",
             *common.machine_record(command), "",
             "Error: the largest |x − x_ref| of F_mesh and of every bearing reaction over the "
             f"communication points, relative to the static mesh force; x_ref from "
             f"`reference_simulate` at tolerance {reference_tolerance:g}. Wall time: stepping "
             "only, per simulated second. Start-up: instantiate + initialize in a fresh "
             "process, compiled code cached. The FMU runs through fmpy's FMU2Slave (inputs set "
             "and forces read at every communication point, one process per run, the median "
             "of `--repeat` runs); scipy runs "
             "`ScipyStepper` (restarts at every contact switch, like the reference) sampling "
             "its dense output: an offline run, scipy's cheapest way. `*`: stopped at the wall "
             "budget, figures over the span reached.", ""]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        lines += _scene_section([r for r in rows if r["scene"] == scene])
    return "\n".join(lines) + "\n"


def _scene_section(rows):
    fmu = [r for r in rows if r["integrator"] == "FMU"]
    scipy = [r for r in rows if r["integrator"] == "solve_ivp"]
    best_scipy = cheapest(scipy, common.ACCURACY_GOAL)
    span = max(r["span_requested"] for r in rows)
    lines = [f"## {rows[0]['scene']} ({span:g} s simulated)", ""]

    def mark(r):
        return "" if r["status"] == "ok" else "*"

    defaults = [r for r in fmu if r["default"]]
    if defaults:
        table = []
        for r in sorted(defaults, key=lambda r: r["comm_step"]):
            speedup = (best_scipy["wall_per_sim_s"] / r["wall_per_sim_s"]) if best_scipy \
                else math.nan
            goals = [f"error {'✓' if r['error'] <= common.ACCURACY_GOAL else '✗'}",
                     f"speed {'✓' if r['wall_per_sim_s'] <= common.SPEED_GOAL else '✗'}",
                     f"start-up {'✓' if r['startup_s'] < common.STARTUP_GOAL else '✗'}",
                     "50× " + ("—" if not math.isfinite(speedup)
                                else "✓" if speedup >= 50 else "✗")]
            table.append([f"{r['comm_step']:g}", f"{r['tolerance']:g}",
                          common.number(r["error"]) + mark(r),
                          common.number(r["wall_per_sim_s"]), common.number(r["startup_s"]),
                          common.number(r["steps_per_sim_s"] or None),
                          common.number(speedup), ", ".join(goals)])
        lines += ["The FMU at its default settings (goals: error ≤ 1e-6, ≤ 0.1 s per simulated "
                  "second, start-up < 1 s, ≥ 50× faster than the cheapest scipy run with "
                  "error ≤ 1e-6):", ""]
        lines += common.markdown_table(["comm. step s", "solver_tolerance", "error", "wall s/s",
                                        "start-up s", "internal steps/s",
                                        "speed-up over scipy", "goals"], table)
        lines.append("")

    table = []
    groups = {}
    for r in fmu:
        groups.setdefault((f"FMU {r['method']}", r["comm_step"]), []).append(r)
    for r in scipy:
        groups.setdefault((f"solve_ivp {r['method']}", None), []).append(r)
    for (name, _), group in groups.items():
        best = cheapest(group, common.ACCURACY_GOAL)
        if best is None:
            finest = min(measured(group), key=lambda r: r["error"], default=None)
            table.append([name, "—", f"{group[0]['comm_step']:g}", "not reached" + (
                f" (best {common.number(finest['error'])} at {finest['tolerance']:g})"
                if finest else f" ({group[0]['status']})"), "—", "—", "—"])
            continue
        table.append([name, f"{best['tolerance']:g}", f"{best['comm_step']:g}",
                      common.number(best["error"]) + mark(best),
                      common.number(best["wall_per_sim_s"]), common.number(best["startup_s"]),
                      common.number(best["steps_per_sim_s"] or None)])
    lines += [f"The cheapest configuration of each integrator reaching error ≤ "
              f"{common.ACCURACY_GOAL:g}:", ""]
    lines += common.markdown_table(["integrator", "tolerance", "comm. step s", "error",
                                    "wall s/s", "start-up s", "internal steps/s"], table)
    lines.append("")

    headline = next((r for r in defaults if r["comm_step"] == 1e-3), None)
    if headline and math.isfinite(headline["error"]):
        same = cheapest(scipy, headline["error"])
        lines.append(f"FMU at its defaults, communication step 1e-3 s: error "
                     f"{common.number(headline['error'])}, "
                     f"{common.number(headline['wall_per_sim_s'])} s/s. " + (
                         f"Cheapest scipy run at least as accurate: {same['method']} at "
                         f"{same['tolerance']:g}, error {common.number(same['error'])}, "
                         f"{common.number(same['wall_per_sim_s'])} s/s: the FMU is "
                         f"{common.number(same['wall_per_sim_s'] / headline['wall_per_sim_s'])}"
                         "× faster." if same else
                         "No scipy run was as accurate within its budget."))
        lines.append("")
    return lines


# The FMU's series: colour by communication step, marker and line by solver_method (the
# first method swept, solid circles; then dash-dotted squares, dotted diamonds)
FMU_MARKS = (("o", "-"), ("s", "-."), ("D", ":"))


def fmu_style(method_index, color) -> dict:
    """The plot style of the FMU's series for the `method_index`-th solver_method swept."""
    marker, linestyle = FMU_MARKS[method_index % len(FMU_MARKS)]
    return dict(color=color, marker=marker, linestyle=linestyle, linewidth=2.2, markersize=7,
                zorder=3)


def plot(rows, path) -> None:
    """Error against wall time per simulated second, one panel per scene."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    columns = min(2, len(scenes))
    figure, axes = plt.subplots((len(scenes) + columns - 1) // columns, columns,
                                figsize=(9.5 * columns, 5.5 * ((len(scenes) + columns - 1)
                                                             // columns)), squeeze=False)
    scipy_style = dict(zip(SCIPY_METHODS, zip(("tab:blue", "tab:green", "tab:purple",
                                               "tab:brown", "tab:gray"), "s^vDP")))
    floor = 1e-14  # an error of 0 (a run identical to the reference) still gets a point
    for axis, scene in zip(axes.flat, scenes):
        groups = {}
        for r in measured([r for r in rows if r["scene"] == scene]):
            key = (r["integrator"], r["method"], r["comm_step"])
            groups.setdefault(key, []).append(r)
        fmu_steps = sorted({key[2] for key in groups if key[0] == "FMU"})
        fmu_methods = list(dict.fromkeys(key[1] for key in groups if key[0] == "FMU"))
        shades = plt.cm.autumn([i / max(len(fmu_steps), 1) for i in range(len(fmu_steps))])
        for (integrator, method, step), group in groups.items():
            group.sort(key=lambda r: r["tolerance"], reverse=True)
            x = [r["wall_per_sim_s"] for r in group]
            y = [max(r["error"], floor) for r in group]
            if integrator == "FMU":
                color = shades[fmu_steps.index(step)]
                label = f"FMU{'' if method == 'default' else ' ' + method}, step {step:g} s"
                style = fmu_style(fmu_methods.index(method), color)
            else:
                color, marker = scipy_style.get(method, ("black", "x"))
                label = f"solve_ivp {method}, output every {step:g} s"
                style = dict(color=color, marker=marker, linewidth=1, linestyle="--",
                             markersize=6, zorder=2)
            axis.plot(x, y, label=label, **style)
            for r, xi, yi in zip(group, x, y):
                if r["status"] != "ok":  # stopped at the budget: an open marker
                    axis.plot([xi], [yi], marker="o", markersize=12, markerfacecolor="none",
                              color=color, zorder=4)
                if r["default"]:
                    axis.plot([xi], [yi], marker="*", markersize=16, color="black", zorder=5)
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.axhline(common.ACCURACY_GOAL, color="black", linewidth=0.8, linestyle=":")
        axis.axvline(common.SPEED_GOAL, color="black", linewidth=0.8, linestyle=":")
        axis.annotate(f"accuracy goal {common.ACCURACY_GOAL:g}", (0.01, common.ACCURACY_GOAL),
                      xycoords=("axes fraction", "data"), fontsize=8, va="bottom")
        axis.annotate(f"speed goal {common.SPEED_GOAL:g} s/s", (common.SPEED_GOAL, 0.01),
                      xycoords=("data", "axes fraction"), fontsize=8, rotation=90,
                      ha="right", va="bottom")
        axis.set_xlabel("wall time per simulated second [s]")
        axis.set_ylabel("max |ΔF| / static mesh force")
        span = max(r["span_requested"] for r in rows if r["scene"] == scene)
        axis.set_title(f"{scene}: {span:g} s simulated (★ FMU defaults, ○ stopped at budget)",
                       fontsize=10)
        axis.grid(True, which="major", alpha=0.3)
        axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    for axis in list(axes.flat)[len(scenes):]:
        axis.set_visible(False)
    figure.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    plt.close(figure)


def main(argv=None, prog="error_vs_runtime.py") -> int:
    """Exit code 0; 2, with one line on stderr, for a bad option (checked before any run).
    `prog`: the command as the user typed it, which usage and messages name."""
    from herringbone.arguments import (
        COMPILED_TOLERANCE_ARGUMENT,
        POSITIVE,
        REFERENCE_TOLERANCE_ARGUMENT,
        STOP_TIME,
        Argument,
        OneLineParser,
        Range,
        output_folder,
    )

    step = Argument("step", None, "seconds", POSITIVE).option_type
    budget = Argument("budget", None, "wall seconds", POSITIVE).option_type
    repeat = Argument("repeat", None, "runs", Range(1.0), whole=True).option_type
    parser = OneLineParser(prog=prog, description=__doc__.split("\n")[0],
                           help_command="herringbone benchmark error-vs-runtime --help",
                           epilog="Defaults: the shipped scenes (reference, torsional, "
                           "staggered, lead_error), 0.2 s, steps 1e-5 1e-4 1e-3 1e-2, "
                           "tolerances 1e-5 … 1e-10, all methods, budget 120 s. "
                           "--quick: reference, 0.01 s, steps 1e-4 1e-3, tolerances "
                           "1e-6 1e-8, fmu RK45 DOP853. Explicit options override both.")
    parser.add_argument("--scenes", nargs="+", help="scene names (models/NAME.toml), files or "
                        "globs")
    parser.add_argument("--stop-time", type=STOP_TIME.option_type,
                        help="simulated seconds per run")
    parser.add_argument("--steps", nargs="+", type=step, help="FMU communication steps [s]")
    parser.add_argument("--tolerances", nargs="+",
                        type=COMPILED_TOLERANCE_ARGUMENT.option_type,
                        help="solver tolerances (FMU solver_tolerance and scipy rtol; the FMU's "
                             "default is always added)")
    parser.add_argument("--methods", nargs="+", help=f"fmu and/or {' '.join(SCIPY_METHODS)}")
    parser.add_argument("--fmu-methods", nargs="+", default=None,
                        help="FMU solver_method values to sweep (only if the FMU declares "
                             "solver_method; default: the FMU's own default)")
    parser.add_argument("--scipy-step", type=step, default=1e-3,
                        help="output interval of the scipy runs [s] (default 1e-3)")
    parser.add_argument("--budget", type=budget,
                        help="wall seconds per configuration: a run stops there, tighter "
                             "tolerances of that method are skipped")
    parser.add_argument("--reference-tolerance",
                        type=REFERENCE_TOLERANCE_ARGUMENT.option_type, default=1e-12,
                        help="tolerance of the reference integration (default 1e-12)")
    parser.add_argument("--output-dir", type=output_folder, default=common.DEFAULT_OUTPUT_DIR,
                        help="where the CSV, PNG and markdown go (default results/benchmark; "
                             "FMUs and references are cached there whatever this says)")
    parser.add_argument("--repeat", type=repeat, default=3,
                        help="runs of each FMU configuration, the median wall time kept "
                             "(default 3)")
    parser.add_argument("--quick", action="store_true", help="a minute's check of the pipeline")
    args = parser.parse_args(argv)
    settings = QUICK if args.quick else FULL
    for name, value in settings.items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    unknown = set(args.methods) - {"fmu", *SCIPY_METHODS}
    if unknown:
        parser.error(f"unknown method {sorted(unknown)[0]}; allowed: fmu {' '.join(SCIPY_METHODS)}")
    if args.repeat < 1:
        parser.error(f"--repeat {args.repeat}: allowed: 1 or more")
    scenes = common.scene_paths(args.scenes, parser)
    command = common.command_line(__file__, sys.argv[1:] if argv is None else argv)

    from herringbone.integrate.compiled_stepper import DEFAULT_TOLERANCE

    fmu_runs = (len(args.fmu_methods or [None]) * len(args.steps)
                * len(set(args.tolerances) | {DEFAULT_TOLERANCE}) if "fmu" in args.methods else 0)
    scipy_runs = len([m for m in args.methods if m != "fmu"]) * len(args.tolerances)
    # configurations done and time left; the log lines go above the bar
    bar = tqdm(total=len(scenes) * (fmu_runs + scipy_runs), unit="run", desc="benchmark",
               file=sys.stderr, disable=not sys.stderr.isatty())
    rows = []
    for scene_path in scenes:
        rows += benchmark_scene(scene_path=scene_path, stop_time=args.stop_time,
                                steps=args.steps, tolerances=args.tolerances,
                                methods=args.methods, fmu_methods=args.fmu_methods or [None],
                                scipy_step=args.scipy_step, budget=args.budget,
                                reference_tolerance=args.reference_tolerance,
                                repeat=args.repeat, log=bar.write, done=bar.update)
    bar.close()
    output = Path(args.output_dir)
    common.write_csv(rows, output / "benchmark.csv")
    plot(rows, output / "error_vs_runtime.png")
    report = markdown_report(rows, args.reference_tolerance, command)
    (output / "benchmark.md").write_text(report, encoding="utf-8")
    print(report)
    print(f"written: {output / 'benchmark.csv'}, {output / 'error_vs_runtime.png'}, "
          f"{output / 'benchmark.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
