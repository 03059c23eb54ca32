"""What the commands of `herringbone` share: their parser (one-line errors, "did you mean"),
the options every command declares the same way (SCENE with --set, --speeds with --rpm,
-o/--output, --no-progress), and the error a command raises to stop with one line.

A command is a module of this package with `NAME`, `HELP`, `declare(parser)` (its options:
one declaration each, checked by their `type=` or action through herringbone.arguments before
any work) and `execute(args, parser)` (the work; returns the exit code).
"""
from __future__ import annotations

import argparse
import contextlib
import math
import signal
import sys
import warnings
from pathlib import Path
from typing import cast

from ..arguments import (
    FMU_MAX_STEP,
    FMU_SOLVER_METHOD,
    FMU_SOLVER_TOLERANCE,
    OneLineParser,
    SpeedSweep,
    name_problem,
    number,
    output_file,
    output_file_problem,
    output_folder,
    speed_sweep_problem,
    unit_hint,
)
from ..model.parameters import PINION_SPEED as W0_PINION_RANGE
from ..model.parameters import RPM_PER_RAD_S
from ..model.scene import SceneError, toml_value
from ..suggest import did_you_mean

SCENE_HELP = "scene file (TOML), or the name of a shipped scene (`herringbone scenes` lists them)"


class CommandError(Exception):
    """A command cannot go on: printed as one line, `herringbone COMMAND: <message>`, exit
    code 2."""


# what a command's work may raise that is the user's to fix, not a fault of the program: a bad
# scene or value, an integration that cannot go on (IntegrationError), a build that failed
# (RuntimeError), a missing optional dependency, a file that cannot be written
EXPECTED_ERRORS = (CommandError, SceneError, ValueError, RuntimeError, ImportError, OSError)
INTERRUPTED = 130  # the exit code of a command stopped by Ctrl-C: 128 + SIGINT
TERMINATED = 143  # and by SIGTERM (`timeout`, a batch scheduler, `kill`): 128 + SIGTERM


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the command is, so that it stops as Ctrl-C stops it: the default
    action ends the process on the spot and leaves a file being written as half a table."""


def execute(module, args, parser: argparse.ArgumentParser) -> int:
    """Run a command module's `execute`; an expected error becomes one line on stderr,
    `PROG: message`, and exit code 2; an interrupt (Ctrl-C) one line, `PROG: interrupted`,
    and exit code 130 (128 + SIGINT, as a shell reports it), SIGTERM `PROG: terminated` and
    143, the files it had not finished left as they were (files.replace_file)."""
    try:
        with _terminate_as_interrupt(), _warnings_said(parser.prog):
            return module.execute(args, parser)
    except BaseException as error:
        compiles_said()
        if interrupted(error):
            stop, code = (("terminated", TERMINATED) if interrupted(error, Terminated)
                          else ("interrupted", INTERRUPTED))
            print(f"{parser.prog}: {stop}; files not finished are left as they were",
                  file=sys.stderr)
            return code
        if isinstance(error, BrokenPipeError):
            return reader_gone()
        if not isinstance(error, EXPECTED_ERRORS):
            raise
        print(f"{parser.prog}: {one_line(error)}", file=sys.stderr)
        return 2


def compiles_said() -> None:
    """The end of a compile's announcement said now, where it is done (compiling/announce.py
    would say it a second later, or at exit: after the command's last line); none where no
    kernel was loaded (the module imports numba: not imported for that alone)."""
    announce = sys.modules.get(f"{__package__.rpartition('.')[0]}.compiling.announce")
    if announce is not None:
        announce.finish()


# the exit code where the reader of the output left before it was written (`| head`): a shell
# reports 128 + SIGPIPE for a command the pipe's signal ended
READER_GONE = 141


def reader_gone() -> int:
    """A command whose output's reader has gone (`herringbone scenes | head -2`) ends quietly,
    as a Unix tool does, not with "[Errno 32] Broken pipe": its stdout is pointed at the null
    device, so that the interpreter's flush at exit finds no pipe to fail on."""
    import os

    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, sys.stdout.fileno())
    os.close(null)
    return READER_GONE


def interrupted(error: BaseException | None, kind: type = KeyboardInterrupt) -> bool:
    """Whether `error` is a KeyboardInterrupt (or the `kind` of it given) or was raised by
    one: numba hands an interrupt that comes inside a compiled function's call on as a
    SystemError caused by it."""
    while error is not None:
        if isinstance(error, kind):
            return True
        error = error.__cause__ or error.__context__
    return False


@contextlib.contextmanager
def _warnings_said(prog: str):
    """A warning of the library (a ReferenceAccuracyWarning, a ResourcePathWarning) as one line
    on stderr, `PROG: warning: message`, where Python would show its file, line and source."""
    def say_warning(message, category, filename, lineno, file=None, line=None):
        print(f"{prog}: warning: {message}", file=sys.stderr, flush=True)

    shown = warnings.showwarning
    warnings.showwarning = say_warning
    try:
        yield
    finally:
        warnings.showwarning = shown


@contextlib.contextmanager
def _terminate_as_interrupt():
    """SIGTERM raises Terminated while the block runs (the handler it had is put back after);
    nothing changes where the command does not run in the main thread, the only one a
    signal's handler may be set from."""
    def terminate(signal_number, frame):
        raise Terminated

    try:
        previous = signal.signal(signal.SIGTERM, terminate)
    except ValueError:
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def one_line(error: BaseException) -> str:
    """An error as one line: its message, or its type where it has none."""
    text = " ".join(str(error).split())
    if isinstance(error, OSError) and error.filename is not None:
        text = f"{error.filename}: {error.strerror}"
    return text or type(error).__name__


class CommandParser(OneLineParser):
    """A command's parser: one-line errors (OneLineParser) and close-match suggestions for an
    unknown option."""

    def error(self, message):
        """OneLineParser's one line; a flag given a value (`--no-progress=yes`, which argparse
        words "ignored explicit argument 'yes'") says that the flag takes none."""
        import re

        flag = re.fullmatch(r"argument (\S+): ignored explicit argument '(.*)'", message)
        if flag:
            option = flag[1].split("/")[-1]
            message = f"{option}={flag[2]}: takes no value; allowed: {option} alone"
        super().error(message)

    def unknown(self, extras: list[str]) -> None:
        """Stop on arguments the command does not take, suggesting the closest option."""
        options = [option for action in self._actions for option in action.option_strings]
        flagged = [extra for extra in extras if extra.startswith("-")]
        if flagged:
            word = flagged[0].split("=")[0]
            self.error(f"unknown option {word}{did_you_mean(word, options)}")
        self.error(f"unexpected argument {extras[0]!r}")


def fail(parser: argparse.ArgumentParser, message: str) -> None:
    """Stop the command with one line on stderr, `PROG: message`, exit code 2."""
    parser.error(message)


def add_scene(parser: argparse.ArgumentParser, optional_default: str | None = None) -> None:
    """The SCENE argument: a file or a shipped scene's name (optional with a default)."""
    if optional_default is None:
        parser.add_argument("scene", type=Path, metavar="SCENE", help=SCENE_HELP)
    else:
        parser.add_argument("scene", type=Path, nargs="?", default=Path(optional_default),
                            metavar="SCENE", help=f"{SCENE_HELP}; default: {optional_default}")


def add_settings(parser: argparse.ArgumentParser) -> None:
    """--set NAME=VALUE (repeatable): a parameter or an input torque of the scene changed for
    this command (`scene_of`)."""
    parser.add_argument("--set", dest="settings", action="append", default=[],
                        type=_setting, metavar="NAME=VALUE",
                        help="change a parameter or input torque of the scene for this "
                             "command, its value written as in a scene file (a number, true "
                             "or false); repeatable: --set w0_pinion=450 --set M_motor=800")


def changed_name(scene, args) -> str:
    """The scene's name with the command's --set changes, "reference+w0_pinion=450": what its
    files are named by, so that a changed scene's results replace none of the scene's own
    (build-fmu's FMUs are named so too)."""
    return scene.name + "".join(f"+{name}={_short_value(value)}"
                                for name, value in getattr(args, "settings", []))


def _short_value(value) -> str:
    """A value as a file name gives it: as a scene file writes it (toml_value), but a number
    that it writes long in the shortest form that means the same float (1e9, not
    1000000000.0; 1e-5, not 1e-05)."""
    import numpy as np

    text = toml_value(value)
    if not isinstance(value, float) or not math.isfinite(value) or (
            "e" not in text and len(text) <= 8):
        return text
    short = np.format_float_scientific(value, unique=True, trim="-", exp_digits=1)
    short = short.replace("e+", "e")
    return short if len(short) < len(text) else text


# names --set refuses before their value is read (a value may be a word: method=radau): what
# each is, and where it is set instead
_SET_ELSEWHERE = {
    **dict.fromkeys((FMU_SOLVER_TOLERANCE.name, FMU_MAX_STEP.name, FMU_SOLVER_METHOD.name),
                    "a solver setting of the FMU, not a parameter; allowed: a host sets it on "
                    "the FMU (`herringbone run` takes --tolerance and --method)"),
    **{name: f"the integrator's, not a parameter; allowed: --{name} where the command takes it"
       for name in ("tolerance", "method")}}


def _setting(text: str) -> tuple[str, object]:
    """NAME=VALUE as (name, value), the value read as a TOML value (tomllib: 450, 4.5e2,
    true); argparse's one-line error where it is not one, or where NAME is the integrator's
    (tolerance, method) or one of the FMU's solver settings (a value may be a word there:
    method=radau)."""
    import tomllib

    name, equals, value = text.partition("=")
    if not equals or not name.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: allowed: NAME=VALUE, e.g. w0_pinion=450")
    if name.strip() in _SET_ELSEWHERE:
        raise argparse.ArgumentTypeError(f"{text}: {name.strip()} is "
                                         f"{_SET_ELSEWHERE[name.strip()]}")
    try:
        return name.strip(), tomllib.loads(f"value = {value.strip()}")["value"]
    except tomllib.TOMLDecodeError:
        from ..model.parameters import unit_of

        raise argparse.ArgumentTypeError(
            f"{text!r}: the value {value.strip()!r} is not a number, true or false"
            f"{unit_hint(value, unit_of(name.strip()))}") from None


def scene_of(args, parser: argparse.ArgumentParser):
    """The command's scene: SCENE (a file or a shipped scene's name) with --set's changes, an
    input torque by Scene.with_inputs, a parameter by Scene.with_parameters; one line naming
    the setting where one is refused (`_setting_refused`), or saying what SCENE is where it
    is there but is no file to read (shipped.unreadable: a device, a pipe, a link to nothing,
    a name too long). The changes are said in a line on stdout first."""
    from ..model.parameters import INPUTS, unit_of, with_unit
    from ..model.scene import load_scene
    from ..shipped import unreadable

    problem = unreadable(Path(args.scene))
    if problem is not None:
        fail(parser, f"{args.scene}: {problem}; allowed: a scene file (TOML) or the name of a "
                     "shipped scene (`herringbone scenes`)")
    scene = load_scene(args.scene)
    settings = getattr(args, "settings", [])
    names = [name for name, _ in settings]
    for name, value in settings:
        refused = _setting_refused(name, value, names.count(name), scene)
        if refused is not None:
            fail(parser, refused)
        try:
            scene = (scene.with_inputs(**{name: value}) if name in INPUTS
                     else scene.with_parameters(**{name: value}))
        except (SceneError, TypeError) as error:
            problem = error.problem if isinstance(error, SceneError) else str(error)
            fail(parser, f"--set {name}={toml_value(value)}: {problem}")
    if settings:
        changes = ", ".join(f"{name} = {with_unit(toml_value(value), unit_of(name))}"
                            for name, value in settings)
        print(f"scene {scene.name} with {changes} (--set)")
    return scene


def _setting_refused(name: str, value, count: int, scene) -> str | None:
    """The line that refuses --set NAME=VALUE (`name` given `count` times) on `scene` before
    its value is tried, or None: a name given twice, the experiment's keys (options of their
    own), a component, a torque of a scene whose torques are a table."""
    from ..model.parameters import COMPONENTS, INPUTS

    given = f"--set {name}={toml_value(value)}"
    if count > 1:
        return f"--set {name} is given {count} times; allowed: each name once"
    if name in ("stop_time", "output_interval"):
        return (f"--set {name}: {name} is of the scene's [experiment], not a parameter; "
                f"allowed: --{name.replace('_', '-')} where the command takes it")
    if name in COMPONENTS:
        return (f"{given}: {name} is a component, not a parameter; allowed: a scene file's "
                "[components] sets it")
    if name in INPUTS and len(scene.inputs.times) > 1:
        return (f"{given}: the scene's torques are a table of {len(scene.inputs.times)} rows; "
                "allowed: --set of a torque on a scene with constant torques")
    return None


# The most pinion speeds --speeds takes: a stability chart of 100 000 takes minutes (a few ms
# a speed), a sweep by shooting about as long; a few more digits of COUNT (a typo, 99999999999)
# ended in numpy's "Unable to allocate 745 GiB" and a traceback.
MOST_SPEEDS = 100_000
# the fastest pinion speed, rad/s: the scene's w0_pinion takes none faster (parameters.py)
FASTEST_SPEED = float(cast(float, W0_PINION_RANGE.high))
SPEEDS_ALLOWED = (f"0 < FROM < TO <= {FASTEST_SPEED:g} rad/s "
                  f"({FASTEST_SPEED * RPM_PER_RAD_S:.0f} rpm with --rpm), COUNT >= 2 speeds, "
                  f"at most {MOST_SPEEDS}")


class _SpeedsAction(argparse.Action):
    """Checks FROM TO COUNT at once (arguments.speed_sweep_problem, and COUNT at most
    MOST_SPEEDS); TO against FASTEST_SPEED once --rpm is known (speeds_of)."""

    def __call__(self, parser, namespace, values, option_string=None):
        low, high, count = values
        problem = speed_sweep_problem(low, high, count)
        if problem is None and count > MOST_SPEEDS:
            problem = f"COUNT {count:g} is more than {MOST_SPEEDS} speeds"
        if problem is not None:
            raise argparse.ArgumentError(self, f"{low:g} {high:g} {count:g}: {problem}; "
                                               f"allowed: {SPEEDS_ALLOWED}")
        setattr(namespace, self.dest, SpeedSweep(low, high, int(count)))


def add_speeds(parser: argparse.ArgumentParser, default: tuple[float, float, int] | None,
               what: str) -> None:
    """--speeds FROM TO COUNT (checked as a whole) and --rpm, the same in every command."""
    shown = "" if default is None else f" (default: {' '.join(f'{v:g}' for v in default)})"
    # the default apart, in rad/s: --rpm applies to the speeds given, and alone is refused
    parser.set_defaults(default_speeds=None if default is None else SpeedSweep(*default))
    parser.add_argument("--speeds", type=number, nargs=3, action=_SpeedsAction, default=None,
                        metavar=("FROM", "TO", "COUNT"),
                        help=f"{what}: COUNT pinion speeds from FROM to TO, rad/s (rpm with "
                             f"--rpm): 0 < FROM < TO <= {FASTEST_SPEED:g} "
                             f"({FASTEST_SPEED * RPM_PER_RAD_S:.0f} with --rpm), COUNT from 2 "
                             f"to {MOST_SPEEDS}{shown}")
    parser.add_argument("--rpm", action="store_true", help="FROM and TO of --speeds are in rpm")


def speeds_of(args, parser) -> SpeedSweep | None:
    """--speeds with --rpm applied, else the command's default speeds (rad/s; None without
    one); --rpm without --speeds is refused (it says what --speeds' FROM and TO are in), and
    so is a TO faster than FASTEST_SPEED."""
    if args.speeds is not None:
        sweep = args.speeds._replace(in_rpm=args.rpm)
        if sweep.speeds()[-1] > FASTEST_SPEED:
            low, high, count = sweep.low, sweep.high, sweep.size
            fail(parser, f"--speeds {low:g} {high:g} {count}: TO {high:g} "
                         f"{'rpm' if args.rpm else 'rad/s'} is faster than any pinion speed "
                         f"a scene takes ({FASTEST_SPEED:g} rad/s, "
                         f"{FASTEST_SPEED * RPM_PER_RAD_S:.0f} rpm); allowed: {SPEEDS_ALLOWED}")
        return sweep
    if args.rpm and getattr(args, "speed", None) is None:
        fail(parser, "--rpm without --speeds; allowed: --rpm with --speeds FROM TO COUNT "
                     "(FROM and TO in rpm)")
    return args.default_speeds


def add_output(parser: argparse.ArgumentParser, what: str, default: str,
               suffixes: tuple[str, ...] = (), folder: bool = False) -> None:
    """-o/--output: a file ending in one of `suffixes`, or a folder (`folder`), checked as it is
    parsed (writable, the right kind); `what` says what is written there and what replaced."""
    kind = "a folder" if folder else f"a {' or '.join(suffixes)} file" if suffixes else "a file"
    parser.add_argument("-o", "--output", type=output_folder if folder else output_file(*suffixes),
                        metavar="FOLDER" if folder else "FILE",
                        help=f"{kind} to write: {what} (default: {default})")


def default_output(parser: argparse.ArgumentParser, given: Path | None, default: Path,
                   suffixes: tuple[str, ...] = (), folder: bool = False) -> Path:
    """The output to write: `given` (checked when parsed) or `default`, checked here, before any
    work."""
    if given is not None:
        return given
    problem = name_problem(default)
    if problem is None:
        problem = (f"{default} is a file" if folder and default.exists() and not default.is_dir()
                   else output_file_problem(default / "file" if folder else default, suffixes))
    if problem is not None:
        fail(parser, f"cannot write {default}: {problem}; give -o "
                     f"{'FOLDER' if folder else 'FILE'} in a folder you can write in")
    return default


# what --no-progress does on a command that shows no bar: a script may pass it to every
# command that takes a SCENE
NO_BAR = "accepted, as every command that takes a SCENE accepts it: this one shows no bar"


def add_progress(parser: argparse.ArgumentParser, what: str = "no progress bar on stderr"
                 ) -> None:
    """--no-progress: no progress bar on stderr (`what` it leaves out, where not a bar)."""
    parser.add_argument("--no-progress", action="store_true", help=what)


def progress_of(args) -> bool:
    """Whether the work about to begin shows its progress bar: not with --no-progress, nor
    where tqdm (the `analysis` extra) is not installed, which one line on stderr says then
    (the work goes on without a bar). Called as the work begins, after every check, so that
    a refused command still says one line."""
    from ..optional import EXTRAS, MissingDependency, require

    if args.no_progress:
        return False
    try:
        require("tqdm", "the progress bar")
    except MissingDependency:
        say(f"no progress bar: tqdm is not installed; pip install tqdm brings it (or every "
            f"dependency of the {EXTRAS['tqdm']!r} extra: pip install \".[{EXTRAS['tqdm']}]\" "
            "in herringbone's source folder), and --no-progress leaves out this line")
        return False
    return True


def say(message: str) -> None:
    """A note on stderr (compiling, progress), apart from the results on stdout."""
    print(message, file=sys.stderr, flush=True)
