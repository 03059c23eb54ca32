"""Command-line handlers of `herringbone sweep`, `herringbone campbell` and `run --plot`;
cli.py registers them (`register`). Bad arguments raise ValueError with one line naming the
argument and what is allowed; the handler prints `herringbone COMMAND: <message>` and returns 2.
"""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path

from ..model.scene import load_scene

RPM_PER_RAD_S = 30.0 / math.pi
SCENE_HELP = "scene file (TOML), or the name of a shipped scene (`herringbone scenes`)"


def register(commands) -> dict:
    """Add `sweep` and `campbell` to the subparsers and `--plot` to `run`; returns the
    handlers of the commands added, by name."""
    sweep = commands.add_parser("sweep", help="run a scene over a grid of speeds or "
                                "parameters (one or two), past its start-up transient: "
                                "K_v, bearing reactions, dte, contact loss, Floquet |λ|max per "
                                "point (CSV, resonance curve and waterfall PNGs)")
    sweep.add_argument("scene", type=Path, metavar="SCENE", help=SCENE_HELP)
    sweep.add_argument("--speeds", nargs=3, metavar=("LO", "HI", "N"),
                       help="pinion speeds w0_pinion, N from LO to HI, rad/s (rpm with --rpm)")
    sweep.add_argument("--rpm", action="store_true", help="--speeds are in rpm")
    sweep.add_argument("--param", nargs=4, action="append", default=[],
                       metavar=("NAME", "LO", "HI", "N"),
                       help="a parameter (or M_motor, M_load) from LO to HI in N values; "
                       "twice, or with --speeds, for a grid")
    sweep.add_argument("--settle-residual", type=float, default=1e-3,
                       help="settle until the least-damped mode has decayed to this fraction "
                       "(default 1e-3)")
    sweep.add_argument("--settle-time", type=float, help="settle this long instead, s")
    sweep.add_argument("--window-periods", type=int, default=50,
                       help="mesh periods recorded per point (default 50)")
    sweep.add_argument("--samples-per-period", type=int, default=64,
                       help="samples per mesh period (default 64)")
    sweep.add_argument("--tolerance", type=float, default=1e-7,
                       help="integrator tolerance relative to the static mesh force")
    sweep.add_argument("--no-floquet", action="store_true", help="skip the Floquet multiplier")
    sweep.add_argument("--workers", type=int, help="Dask LocalCluster worker processes "
                       "(default: one per core; 0: no Dask, run here one after the other)")
    sweep.add_argument("--scheduler", help="run on an existing Dask cluster, "
                       "e.g. tcp://HOST:8786 (its workers need herringbone installed)")
    sweep.add_argument("--through-fmu", type=Path, metavar="FMU",
                       help="run each point through this gear FMU with fmpy")
    sweep.add_argument("--no-progress", action="store_true", help="no progress bar")
    sweep.add_argument("-o", "--output-dir", type=Path, default=Path("results"))
    campbell = commands.add_parser("campbell", help="Campbell diagram: natural frequencies "
                                   "against speed with the mesh orders, crossings listed")
    campbell.add_argument("scene", type=Path, metavar="SCENE", help=SCENE_HELP)
    campbell.add_argument("--speeds", nargs=2, type=float, required=True, metavar=("LO", "HI"),
                          help="pinion speed range, rad/s (rpm with --rpm)")
    campbell.add_argument("--rpm", action="store_true", help="--speeds are in rpm")
    campbell.add_argument("-o", "--output", type=Path,
                          help="PNG to write (default results/<scene>_campbell.png)")
    run = commands.choices["run"]
    run.add_argument("--plot", action="store_true", help="also write PNGs: time histories "
                     "and amplitude spectra with mesh harmonics and natural frequencies")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    return {"sweep": _guarded("sweep", sweep_main), "campbell": _guarded("campbell",
                                                                          campbell_main)}


def _guarded(command, handler):
    def guarded(args) -> int:
        try:
            return handler(args)
        except ValueError as error:  # SceneError included
            print(f"herringbone {command}: {error}", file=sys.stderr)
            return 2
    return guarded


def _count(text, name) -> int:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (value >= 1 and value == int(value)):
        raise ValueError(f"{name} count {text!r}; allowed: a whole number >= 1")
    return int(value)


def _number(text, name) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise ValueError(f"{name} {text!r}; allowed: a finite number")
    return value


def sweep_axes_from(args) -> tuple:
    """(speeds in rad/s or None, {parameter: values}) from --speeds/--rpm and --param."""
    import numpy as np

    speeds = None
    if args.speeds:
        low, high = (_number(v, "--speeds") for v in args.speeds[:2])
        count = _count(args.speeds[2], "--speeds")
        if not 0.0 < low <= high or (count > 1 and low == high):
            raise ValueError(f"--speeds {low:g} {high:g} {count}; allowed: 0 < LO < HI "
                             "(LO = HI with N = 1)")
        speeds = np.linspace(low, high, count) / (RPM_PER_RAD_S if args.rpm else 1.0)
    elif args.rpm:
        raise ValueError("--rpm without --speeds; allowed: --rpm with --speeds LO HI N")
    params = {}
    for name, low, high, count in args.param:
        params[name] = np.linspace(_number(low, f"--param {name}"),
                                   _number(high, f"--param {name}"),
                                   _count(count, f"--param {name}"))
    return speeds, params


def sweep_main(args) -> int:
    """`herringbone sweep`: run the speed sweep of a scene and write its table and pictures;
    the exit code."""
    from .sweep import run_sweep
    from .sweep_point import Protocol
    from .sweep_report import describe, write_outputs

    speeds, params = sweep_axes_from(args)
    protocol = Protocol(settle_residual=args.settle_residual, settle_time=args.settle_time,
                        window_periods=args.window_periods,
                        samples_per_period=args.samples_per_period, tolerance=args.tolerance,
                        floquet=not args.no_floquet)
    scene = load_scene(args.scene)
    started = time.perf_counter()
    table, series = run_sweep(scene, speeds, params, protocol, workers=args.workers,
                              scheduler=args.scheduler, fmu=args.through_fmu,
                              progress=not args.no_progress)
    wall = time.perf_counter() - started
    written = write_outputs(scene, table, series, args.output_dir)
    print(describe(scene, table, wall, args))
    for path in written:
        print(f"written: {path}")
    return 0


def campbell_main(args) -> int:
    """`herringbone campbell`: draw the Campbell diagram of a scene; the exit code."""
    from .campbell import check_speed_range, plot_campbell

    scale = 1.0 / RPM_PER_RAD_S if args.rpm else 1.0
    low, high = (v * scale for v in args.speeds)
    check_speed_range(low, high)
    scene = load_scene(args.scene)
    output = args.output or Path("results") / f"{scene.name}_campbell.png"
    output.parent.mkdir(parents=True, exist_ok=True)
    found = plot_campbell(scene, low, high, output, f"{scene.name}: Campbell diagram")
    print(f"crossings k·f_mesh = f_n between {low * RPM_PER_RAD_S:.0f} and "
          f"{high * RPM_PER_RAD_S:.0f} rpm ({low:g}-{high:g} rad/s):")
    for c in found:
        print(f"  {c.speed * RPM_PER_RAD_S:8.0f} rpm ({c.speed:8.1f} rad/s)  k = {c.order}  "
              f"f_n = {c.frequency:9.2f} Hz")
    if not found:
        print("  none")
    print(f"diagram written to {output}")
    return 0


def plot_run(scene, results, csv_path: Path) -> list[Path]:
    """`run --plot`: time histories and spectra beside the run's CSV."""
    from .campbell import elastic_frequencies
    from .plots import plot_spectra, plot_time_histories

    stem = csv_path.with_suffix("")
    histories, spectra = Path(f"{stem}_time.png"), Path(f"{stem}_spectrum.png")
    speed = abs(scene.parameters["w0_pinion"])
    plot_time_histories(results, histories, f"{scene.name}: time histories "
                        f"(w0 {speed * RPM_PER_RAD_S:.0f} rpm)")
    mesh_frequency = speed * scene.parameters["z_pinion"] / (2.0 * math.pi)
    plot_spectra(results, spectra, mesh_frequency, elastic_frequencies(scene),
                 f"{scene.name}: amplitude spectra, second half of the run "
                 f"(f_mesh {mesh_frequency:.1f} Hz)", skip=0.5 * results["time"][-1])
    return [histories, spectra]
