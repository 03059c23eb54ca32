"""`herringbone build-fmu [SCENE]`: the co-simulation FMU of a scene (FMI 2.0, or 3.0 with
--fmi 3), or the drive-train example FMUs (--examples DIR), or the drive train as an SSP
archive (--ssp FILE.ssp). `python build_fmu.py` in a checkout is the same command (`main`).

An FMU is named by its scene and FMI version unless -o says otherwise: dist/<scene>-fmi2.fmu,
dist/<scene>-fmi3.fmu, so that building another scene or version never replaces an FMU
silently; an existing file of the same name is replaced.
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from ..arguments import output_file, output_file_problem, output_folder
from ..fmu.builder import DEFAULT_SCENE, FMI_VERSIONS, default_fmu_name
from ..model.scene import scene_file_text, toml_value
from .common import (
    CommandParser,
    add_progress,
    add_scene,
    add_settings,
    changed_name,
    fail,
    say,
    scene_of,
)
from .common import execute as run_command

NAME = "build-fmu"
HELP = ("build the co-simulation FMU of a scene (FMI 2.0; --fmi 3: 3.0), named "
        "dist/<scene>-fmi<N>.fmu; or --examples DIR: the motor and fan FMUs; or --ssp: the "
        "drive train as an SSP archive")
DIST = Path("dist")
SIMULATED = Path("results") / "<scene>_fmu.csv"
# the FMU's count of its integrator's steps (a local variable, which fmpy records when named)
STEPS = "internal_steps"


def declare(parser, dist: Path = DIST) -> None:
    """The options of `build-fmu` (build_fmu.py's too, its FMUs in the checkout's dist/)."""
    add_scene(parser, optional_default=DEFAULT_SCENE)
    add_settings(parser)
    # one thing built: the FMU (-o names it), the example FMUs or the SSP
    built = parser.add_mutually_exclusive_group()
    built.add_argument("-o", "--output", type=output_file(".fmu"), metavar="FILE",
                        help=f"a .fmu file to write: the FMU; an existing file is replaced "
                             f"(default: {dist}/<scene>-fmi<N>.fmu, e.g. "
                             f"{dist / default_fmu_name('reference', 2)}: each scene and FMI "
                             "version its own file; with --set, "
                             f"{dist / default_fmu_name('reference+w0_pinion=450', 2)}, the "
                             "settings in its name)")
    parser.add_argument("--fmi", type=int, choices=FMI_VERSIONS, default=2,
                        help="FMI version of the FMU: 2 (FMI 2.0, pythonfmu; the default) or 3 "
                             "(FMI 3.0, pythonfmu3)")
    parser.add_argument("--simulate", action="store_true",
                        help=f"then simulate the scene through the FMU with fmpy: a summary, "
                             f"and the outputs in {SIMULATED} (replaced if it exists)")
    built.add_argument("--examples", type=output_folder, metavar="FOLDER",
                        help="build the example drive-train FMUs into FOLDER instead "
                             "(InductionMotor.fmu, FanLoad.fmu, replaced if they exist)")
    built.add_argument("--ssp", type=output_file(".ssp"), metavar="FILE",
                        help="build the drive train (SCENE's gear, the example motor and fan) "
                             "as an SSP archive, a .ssp file, instead (replaced if it exists): "
                             "FMI 2.0 FMUs, since libcosim, its host, reads FMI 2.0 only "
                             "(leave out --fmi 3); SCENE must have a motor and a load, which "
                             "the SSP connects")
    add_progress(parser, "no progress lines on stderr while the integrator compiles, the "
                         "first build on a machine (the notes before and after the compile "
                         "stay)")
    parser.set_defaults(dist=dist)


def check_together(args, parser) -> None:
    """One line and exit 2 for options that do not go together."""
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
    if args.examples is not None and args.settings:
        fail(parser, "--set with --examples: the example FMUs (a motor and a fan) have no "
                     "scene to change; allowed: --set with the gear FMU or --ssp")


def execute(args, parser) -> int:
    """Check the options, the scene and the outputs, then build what was asked; 2 with one
    line for a bad scene or a scene or --fmi that --ssp cannot pack. With --set, the FMU (or
    the SSP's) is built from the changed scene, written as a scene file of its own
    (`scene_text`)."""
    from ..fmu import builder

    check_together(args, parser)
    if args.examples is not None:
        for path in builder.build_example_fmus(output_dir=args.examples):
            print(path)
        return 0
    scene = scene_of(args, parser)  # a bad scene or setting is reported before any build
    results = Path(str(SIMULATED).replace("<scene>", changed_name(scene, args)))
    if args.simulate and output_file_problem(results) is not None:
        fail(parser, f"--simulate writes {results}: {output_file_problem(results)}; run it "
                     "from a folder you can write in")
    with tempfile.TemporaryDirectory(prefix="build_fmu_scene_") as folder:
        source = args.scene
        if args.settings:  # the changed scene as a file, named as the scene
            source = Path(folder) / f"{scene.name}.toml"
            source.write_text(scene_text(scene, args.settings), encoding="utf-8")
        if args.ssp is not None:
            return ssp_archive(args, parser, scene, source)
        output = args.output or args.dist / default_fmu_name(changed_name(scene, args),
                                                             args.fmi)
        problem = output_file_problem(output, (".fmu",))
        if problem is not None:
            fail(parser, f"cannot write {output}: {problem}; give -o FILE.fmu in a folder you "
                         "can write in")
        say(f"building {output}: the scene {scene.name} as an FMI {args.fmi}.0 FMU (the "
            "integrator compiled or loaded first, then packed and validated)")
        compile_first(source, not args.no_progress)
        print(f"built {builder.build_gear_fmu(scene=source, output=output, fmi_version=args.fmi)}")
        if len(scene.inputs.times) > 1:
            write_input_table(scene, output)
    if args.simulate:
        simulate(output, scene, results)
    return 0


def ssp_archive(args, parser, scene, source: Path) -> int:
    """--ssp: the drive train of `scene` (read from `source`) as an SSP archive."""
    from ..fmu.ssp import build_ssp, scene_problem

    problem = scene_problem(scene)
    if problem is not None:
        fail(parser, f"--ssp: {problem}")
    compile_first(source, not args.no_progress)
    print(f"built {build_ssp(scene=source, output=args.ssp)}")
    return 0


def write_input_table(scene, fmu: Path) -> Path:
    """A scene's torque table is not part of its FMU (a host drives the inputs): write it
    beside the FMU as fmpy's input file, `FMU-inputs.csv` (time, s; M_motor and M_load, N.m;
    each change as two rows at its time, held between), and say so. Returns the file."""
    from ..fmu.run import scene_inputs

    table = fmu.with_name(f"{fmu.stem}-inputs.csv")
    rows = scene_inputs(scene, scene.experiment.stop_time)
    lines = ["time,M_motor,M_load", *(",".join(map(repr, row)) for row in rows.tolist())]
    table.write_text("\n".join(lines) + "\n", encoding="utf-8")
    first = scene.inputs
    say(f"note: the scene's torque table is not part of the FMU, whose inputs start at its "
        f"first row (M_motor {first.M_motor[0]:g} N.m, M_load {first.M_load[0]:g} N.m) and "
        f"hold where a host sets nothing; {table} holds the table for a host: fmpy simulate "
        f"{fmu} --input-file {table}")
    return table


def compile_first(scene: Path, progress: bool) -> None:
    """Load the integrator as the FMU of `scene` runs it, or compile it (the first build on a
    machine, minutes), here before the build, which then finds it loaded: the note before and
    after a compile on stderr, and between them a line every 10 s with `progress`."""
    import threading

    from ..integrate.first_start import compile_for_scene

    compile_for_scene(scene, say=say, progress_every=10.0 if progress else threading.TIMEOUT_MAX)


def scene_text(scene, settings) -> str:
    """`scene` as a scene file, what an FMU built with --set carries: a header naming the scene
    and the `settings` ((name, value) pairs) it was changed by."""
    changes = " ".join(f"--set {name}={toml_value(value)}" for name, value in settings)
    return scene_file_text(scene, f"{scene.name} ({Path(scene.source).name}) with {changes}: "
                                  "written by herringbone build-fmu")


def simulate(fmu: Path, scene, csv_path: Path) -> None:
    """The scene through its FMU with fmpy: the summary (and `run`'s notes on what its samples
    miss and where it leaves the model), then the outputs as CSV, timed apart."""
    import time

    from ..analysis.run_report import summary
    from ..fmu.run import simulate_scene_fmu
    from .run import sampling_note, slip_notes, write_timed

    first_step: list[float] = []

    def step_finished(_time, _recorder) -> bool:
        if not first_step:
            first_step.append(time.perf_counter())
        return True

    started = time.perf_counter()
    results = simulate_scene_fmu(fmu_path=fmu, scene=scene, step_finished=step_finished,
                                 output=[*fmu_outputs(fmu), STEPS])
    wall = time.perf_counter() - started
    steps = int(results.pop(STEPS)[-1])
    # the first step's end: what fmpy does before it (the FMU unpacked and instantiated, its
    # model set up) would hide the stepping's rate under a fixed cost a hundred times its size
    start = first_step[0] - started if first_step else None
    print("\n".join([summary(scene, results, wall, f"its FMU {fmu}", start,
                             "the FMU unpacked, instantiated and set up, its first step",
                             steps),
                     *sampling_note(scene, results), *slip_notes(scene, results)]), flush=True)
    write_timed(results, csv_path, wall)


def fmu_outputs(fmu: Path) -> list[str]:
    """The names of the FMU's outputs, in its model description's order."""
    import fmpy

    return [variable.name for variable in fmpy.read_model_description(str(fmu)).modelVariables
            if variable.causality == "output"]


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
