"""`herringbone build-fmu [SCENE]`: the co-simulation FMU of a scene (FMI 2.0, or 3.0 with
--fmi 3), or the drive-train example FMUs (--examples DIR), or the drive train as an SSP
archive (--ssp FILE.ssp). `python build_fmu.py` in a checkout is the same command (`main`).

An FMU is named by its scene and FMI version unless -o says otherwise: dist/<scene>-fmi2.fmu,
dist/<scene>-fmi3.fmu, so that building another scene or version never replaces an FMU
silently; an existing file of the same name is replaced.
"""
from __future__ import annotations

import sys
from pathlib import Path

from ..arguments import output_file, output_file_problem, output_folder
from ..fmu.builder import DEFAULT_SCENE, FMI_VERSIONS, default_fmu_name
from .common import CommandParser, add_scene, fail, say
from .common import execute as run_command

NAME = "build-fmu"
HELP = ("build the co-simulation FMU of a scene (FMI 2.0; --fmi 3: 3.0), named "
        "dist/<scene>-fmi<N>.fmu; or --examples DIR: the motor and fan FMUs; or --ssp: the "
        "drive train as an SSP archive")
DIST = Path("dist")
SIMULATED = Path("results") / "<scene>_fmu.csv"


def declare(parser, dist: Path = DIST) -> None:
    """The options of `build-fmu` (build_fmu.py's too, its FMUs in the checkout's dist/)."""
    add_scene(parser, optional_default=DEFAULT_SCENE)
    # one thing built: the FMU (-o names it), the example FMUs or the SSP
    built = parser.add_mutually_exclusive_group()
    built.add_argument("-o", "--output", type=output_file(".fmu"), metavar="FILE",
                        help=f"a .fmu file to write: the FMU; an existing file is replaced "
                             f"(default: {dist}/<scene>-fmi<N>.fmu, e.g. "
                             f"{dist / default_fmu_name('reference', 2)}: each scene and FMI "
                             "version its own file)")
    parser.add_argument("--fmi", type=int, choices=FMI_VERSIONS, default=2,
                        help="FMI version of the FMU: 2 (FMI 2.0, pythonfmu; the default) or 3 "
                             "(FMI 3.0, pythonfmu3)")
    parser.add_argument("--simulate", action="store_true",
                        help=f"then simulate the scene through the FMU with fmpy: a summary, "
                             f"and the outputs in {SIMULATED} (replaced if it exists)")
    built.add_argument("--examples", type=output_folder, metavar="DIR",
                        help="build the example drive-train FMUs into the folder DIR instead "
                             "(InductionMotor.fmu, FanLoad.fmu, replaced if they exist)")
    built.add_argument("--ssp", type=output_file(".ssp"), metavar="FILE",
                        help="build the drive train (SCENE's gear, the example motor and fan) "
                             "as an SSP archive, a .ssp file, instead (replaced if it exists): "
                             "FMI 2.0 FMUs, since libcosim, its host, reads FMI 2.0 only "
                             "(leave out --fmi 3); SCENE must have a motor and a load, which "
                             "the SSP connects")
    parser.set_defaults(dist=dist)


def execute(args, parser) -> int:
    """Check the options, the scene and the outputs, then build what was asked; 2 with one
    line for a bad scene or a scene or --fmi that --ssp cannot pack."""
    from ..fmu import builder
    from ..model.scene import load_scene

    if args.ssp is not None and args.fmi != 2:
        fail(parser, f"--fmi {args.fmi} with --ssp: the SSP packs FMI 2.0 FMUs (libcosim, "
                     f"its host, reads FMI 2.0 only); allowed: --fmi 2, the default: leave out "
                     f"--fmi {args.fmi}")
    other = "--examples" if args.examples is not None else "--ssp" if args.ssp else None
    if other is not None and args.simulate:
        fail(parser, f"--simulate with {other}: it simulates the gear FMU that build-fmu "
                     f"builds without {other}; allowed: one of the two")
    if args.examples is not None and args.fmi != 2:
        fail(parser, f"--fmi {args.fmi} with --examples: the example FMUs are FMI 2.0 "
                     "(pythonfmu); allowed: leave out --fmi")
    if args.examples is not None:
        for path in builder.build_example_fmus(output_dir=args.examples):
            print(path)
        return 0
    scene = load_scene(args.scene)  # a bad scene is reported before any build
    results = Path(str(SIMULATED).replace("<scene>", scene.name))
    if args.simulate and output_file_problem(results) is not None:
        fail(parser, f"--simulate writes {results}: {output_file_problem(results)}; run it "
                     "from a folder you can write in")
    if args.ssp is not None:
        from ..fmu.ssp import build_ssp, scene_problem

        problem = scene_problem(scene)
        if problem is not None:
            fail(parser, f"--ssp: {problem}")
        print(f"built {build_ssp(scene=args.scene, output=args.ssp)}")
        return 0
    output = args.output or args.dist / default_fmu_name(scene.name, args.fmi)
    problem = output_file_problem(output, (".fmu",))
    if problem is not None:
        fail(parser, f"cannot write {output}: {problem}; give -o FILE.fmu in a folder you can "
                     "write in")
    say(f"building {output}: the scene {scene.name} as an FMI {args.fmi}.0 FMU (the integrator "
        "compiled or loaded first, then packed and validated)")
    print(f"built {builder.build_gear_fmu(scene=args.scene, output=output, fmi_version=args.fmi)}")
    if args.simulate:
        simulate(output, scene, results)
    return 0


def simulate(fmu: Path, scene, csv_path: Path) -> None:
    """The scene through its FMU with fmpy: the summary, and the outputs as CSV."""
    import time

    from ..analysis.run_report import summary, write_csv
    from ..fmu.run import simulate_scene_fmu

    started = time.perf_counter()
    results = simulate_scene_fmu(fmu_path=fmu, scene=scene)
    wall = time.perf_counter() - started
    write_csv(results, csv_path)
    print(summary(scene, results, wall, f"its FMU {fmu}"))
    print(f"outputs written to {csv_path}")


def main(argv: list[str] | None = None, prog: str = "herringbone build-fmu",
         help_command: str | None = None, dist: Path = DIST) -> int:
    """The command on its own (build_fmu.py's entry point, with its name and dist folder);
    the exit code."""
    parser = CommandParser(prog=prog, description=HELP, help_command=help_command)
    declare(parser, dist)
    try:  # argparse ends --help and its one-line errors with SystemExit
        args, extras = parser.parse_known_args(argv)
        if extras:
            parser.unknown(extras)
        return run_command(sys.modules[__name__], args, parser)
    except SystemExit as stop:
        return stop.code if isinstance(stop.code, int) else 2
