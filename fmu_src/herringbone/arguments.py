"""The allowed values of the run arguments: one home for the Python API, the command line and
(later) the FMU's solver settings.

Every argument is an `Argument`: its name in the API, its option on the command line, what is
allowed (a parameters.Range, or a list of choices) and what it means. `Argument.check(value)`
returns the value or raises ONE ValueError naming the argument and what is allowed
("stop_time is -1.0; allowed: > 0 (simulated seconds)"); `Argument.option_type` is the same check
as an argparse `type=`. `check_reference_run` and `check_compiled_run` check every argument of a
run at once, before any work; `OneLineParser` is an argparse parser whose errors are one line.
FMU_SOLVER_TOLERANCE, FMU_MAX_STEP and FMU_SOLVER_METHOD are the FMU's solver settings, for
the slave (fmu/slave.py) to check with.
"""
from __future__ import annotations

import argparse
import contextlib
import math
import numbers
import os
import re
import sys
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from .model.parameters import (
    FINITE,
    NON_NEGATIVE,
    POSITIVE,
    RPM_PER_RAD_S,
    Range,
    allowed_words,
    as_float,
    number_problem,
    outputs_of,
)
from .model.scene import Scene, SceneError
from .suggest import did_you_mean

# Below this the error control works on rounding noise (the FMU's bound; scipy itself raises
# an rtol below 100 machine epsilons, 2.2e-14, with a warning).
TIGHTEST_TOLERANCE = 1e-12
# The compiled integrator, as the FMU's solver_tolerance: its steps are bounded by stability
# (compiled_stepper.EXPLICIT_STEP_BOUND) and end at every contact switch, so even at 1e-2 it stays
# within 7e-4 of the mesh force (reference scene, 0.01 s, against the reference at 1e-10).
COMPILED_TOLERANCE = Range(TIGHTEST_TOLERANCE, 1e-2)
# The scipy reference: nothing bounds its steps but the tolerance, so coarse ones step over
# contact switches. Measured on the reference scene over 0.01 s against 1e-10: F_mesh 31 % off
# at 1e-4 (and n_contacts wrong), 5e-4 at 1e-5, 1e-6 at 1e-6.
REFERENCE_TOLERANCE = Range(TIGHTEST_TOLERANCE, 1e-5)
COMPILED_METHODS = ("auto", "dop853", "radau", "exponential")  # compiled_stepper.METHODS
REFERENCE_METHODS = ("DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA")  # scipy's solve_ivp
SWEEP_METHODS = ("shooting", "time")  # analysis.sweep.METHODS
# The defaults (here, so that the command line names them without loading the integrators).
# The compiled integrator's, the FMU's too: the error per step, relative to the static mesh
# force, that keeps every shipped scene within 1e-6 of it at communication steps from 1e-5 to
# 1e-2 s (docs/integrator.md has the figures).
COMPILED_DEFAULT_TOLERANCE = 1e-7
# The reference's, over the run (reference_simulate, `herringbone run --reference`)
REFERENCE_DEFAULT_TOLERANCE = 1e-10


@dataclass(frozen=True)
class Argument:
    """One argument: `name` in the API, `option` on the command line, the values allowed
    (`allowed`, or `choices` for names), `meaning` shown after what is allowed. `infinite`:
    +inf is allowed too (it means "no limit"); `zero`: 0 is allowed too (the same, where a
    start value cannot be inf)."""

    name: str
    option: str | None
    meaning: str
    allowed: Range = FINITE
    choices: tuple[str, ...] | None = None
    infinite: bool = False
    whole: bool = False
    zero: bool = False

    def describe(self) -> str:
        """What is allowed, in words: "> 0 and finite (simulated seconds)"."""
        if self.choices is not None:
            return f"{', '.join(repr(choice) for choice in self.choices)} ({self.meaning})"
        return allowed_words(self.allowed, whole=self.whole, infinite=self.infinite,
                             meaning=self.meaning, zero=self.zero)

    def problem(self, value) -> str | None:
        """Why `value` is not allowed ("is -1.0; allowed: …"), or None if it is."""
        if self.choices is not None:
            return None if isinstance(value, str) and value in self.choices \
                else f"is {value!r}; allowed: {self.describe()}{did_you_mean(value, self.choices)}"
        return number_problem(as_float(value) if isinstance(value, numbers.Real)
                              and not isinstance(value, bool) else value, self.allowed,
                              whole=self.whole, infinite=self.infinite, meaning=self.meaning,
                              zero=self.zero)

    def check(self, value):
        """`value` itself if it is allowed; else ValueError("<name> is …; allowed: …")."""
        problem = self.problem(value)
        if problem is not None:
            raise ValueError(f"{self.name} {problem}")
        return value

    def option_type(self, text: str):
        """argparse `type=`: the value of `text`, or ArgumentTypeError "TEXT: allowed: …"."""
        value: str | float
        if self.choices is not None:
            value = text
        else:
            try:
                value = float(text)
            except ValueError:
                raise argparse.ArgumentTypeError(f"{text}: not a number; "
                                                 f"allowed: {self.describe()}") from None
        if self.problem(value) is not None:
            raise argparse.ArgumentTypeError(f"{text}: allowed: {self.describe()}")
        return int(value) if self.whole else value


STOP_TIME = Argument("stop_time", "--stop-time", "simulated seconds", POSITIVE)
OUTPUT_INTERVAL = Argument("output_interval", "--output-interval",
                           "seconds between output samples, at most the stop time", POSITIVE)
REFERENCE_TOLERANCE_ARGUMENT = Argument(
    "tolerance", "--tolerance", "error in the forces over the run relative to the static mesh "
    "force, for the scipy reference", REFERENCE_TOLERANCE)
COMPILED_TOLERANCE_ARGUMENT = Argument(
    "tolerance", "--tolerance", "error per step relative to the static mesh force, for the "
    "compiled integrator", COMPILED_TOLERANCE)
REFERENCE_METHOD = Argument("method", None, "scipy's solve_ivp methods",
                            choices=REFERENCE_METHODS)
COMPILED_METHOD = Argument("method", None, "the compiled integrator's methods",
                           choices=COMPILED_METHODS)
# The shortest max_step: under a ten-thousandth of the shortest period a train may have
# (2π/1e8 rad/s = 63 ns, model/scene.py FASTEST_RING), and above the time's resolution of any
# run up to 4500 s (2.2e-16·t): below it a run fails at its first step ("the step size fell
# below the time's resolution").
SHORTEST_MAX_STEP = 1e-12
# Below this max_step (s) the steps' rounding adds more error than shorter steps remove:
# measured on the reference scene over 10 ms (against the reference at 1e-12), 1.9e-10 of the
# force at 1e-6 s, 2.4e-10 at 1e-7, 1.2e-9 at 1e-8 and 1.3e-8 at 1e-9, each decade ten times
# the time (the exponential method; DOP853 alike)
ROUNDING_MAX_STEP = 1e-7


class MaxStepWarning(UserWarning):
    """A max_step so short that its steps' rounding adds more error than they remove, at a
    cost of at least 1/max_step steps a simulated second (`max_step_note`)."""


def max_step_note(max_step: float) -> str | None:
    """What a max_step (s; 0 or inf: none) below ROUNDING_MAX_STEP costs and gives, or None."""
    if not 0.0 < max_step < ROUNDING_MAX_STEP:
        return None
    return (f"max_step {max_step:g} s takes at least {1.0 / max_step:.0e} steps a simulated "
            f"second, and below {ROUNDING_MAX_STEP:g} s their rounding adds more error than "
            "shorter steps remove (the reference scene over 10 ms: 1.9e-10 of the force at "
            "1e-6 s, 1.3e-8 at 1e-9 s, each decade ten times the time)")


MAX_STEP = Argument("max_step", None, "largest internal step, seconds; inf: no limit",
                    Range(SHORTEST_MAX_STEP, None), infinite=True)
# The FMU's solver settings, for fmu/core.py: the same ranges under the FMU's variable names.
# max_step's start value says "no limit" with 0 there (a start value in the model description
# cannot be inf); inf, the API's "no limit", is taken too; between them the API's range.
FMU_SOLVER_TOLERANCE = Argument("solver_tolerance", None, "error per step relative to the "
                                "static mesh force", COMPILED_TOLERANCE)
FMU_MAX_STEP = Argument("max_step", None, "largest internal step, seconds; 0 or inf: no "
                        "limit", MAX_STEP.allowed, infinite=True, zero=True)
FMU_SOLVER_METHOD = Argument("solver_method", None, "the compiled integrator's methods",
                             choices=COMPILED_METHODS)
INITIAL_PINION_ANGLE = Argument("initial_pinion_angle", None, "pinion angle at t = 0, rad")
PINION_SPEED = Argument("pinion_speed", None, "pinion speed, rad/s", POSITIVE)
SPEED_COUNT = Argument("COUNT", None, "number of speeds", Range(2.0, None), whole=True)
# How each point of a sweep is run (analysis.sweep_point.Protocol)
SETTLE_RESIDUAL = Argument("settle_residual", "--settle-residual", "fraction of the "
                           "least-damped mode's start-up amplitude left when the window begins",
                           Range(0.0, 1.0, low_open=True, high_open=True))
SETTLE_TIME = Argument("settle_time", "--settle-time", "seconds settled before the window, "
                       "instead of the time derived from --settle-residual (and of the "
                       "windows recorded again where the first had not settled)", NON_NEGATIVE)
WINDOW_PERIODS = Argument("window_periods", "--window-periods", "mesh periods recorded per "
                          "point", Range(1.0, None), whole=True)
# the recorded window's sampling; the figures (K_v, peaks, rms) are taken from a whole multiple
# of it that resolves the train's fastest mode (analysis/sweep_point.figure_refinement)
SAMPLES_PER_PERIOD = Argument("samples_per_period", "--samples-per-period", "samples per mesh "
                              "period recorded for the spectra and waterfall, and the fewest "
                              "the figures take: they sample a whole multiple of it that gives "
                              "the fastest natural mode 32 a period, and each contact switch "
                              "finer", Range(4.0, None), whole=True)


def check_scene(scene) -> Scene:
    """`scene` if it is a Scene; else SceneError saying how to get one."""
    if not isinstance(scene, Scene):
        raise SceneError(f"scene must be a herringbone.Scene, got {type(scene).__name__} "
                         f"{scene!r}; load one with herringbone.load_scene(path) or build one "
                         "with herringbone.scene_from_dict(...)", key="scene")
    return scene


def check_run_times(scene, stop_time=None, output_interval=None, initial_pinion_angle=0.0):
    """Check the run's span and start (None: the scene's [experiment] value, itself checked
    when the scene was loaded); ValueError naming the first culprit."""
    check_scene(scene)
    stop = scene.experiment.stop_time if stop_time is None else STOP_TIME.check(stop_time)
    interval = scene.experiment.output_interval if output_interval is None \
        else OUTPUT_INTERVAL.check(output_interval)
    if interval > stop:
        raise ValueError(f"output_interval is {float(interval)!r}, longer than stop_time "
                         f"{float(stop)!r}; allowed: > 0 and <= stop_time (seconds between "
                         "output samples)")
    problem = samples_problem(scene, stop, interval)
    if problem is not None:
        raise ValueError(problem)
    INITIAL_PINION_ANGLE.check(initial_pinion_angle)


def physical_memory() -> int | None:
    """The machine's physical memory, bytes (os.sysconf on POSIX); None where it is unknown
    (Windows has no sysconf; a system may answer -1)."""
    try:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None
    return memory if memory > 0 else None


# A run holds its samples about twice as it ends: the compiled one samples every output into
# one array of rows (herringbone.integrate.contract.sampled_run) and copies each output's
# column out of it. So its samples may take at most this share of the machine's memory.
SAMPLES_SHARE_OF_MEMORY = 0.5


def samples_problem(scene, stop_time: float, output_interval: float,
                    names: tuple[str, str] = ("stop_time", "output_interval")) -> str | None:
    """Why a run of `scene` over `stop_time` sampled every `output_interval` (s) cannot hold its
    samples in this machine's memory, or None (also where the memory is unknown): the
    stop_time/output_interval + 1 samples of every output and the time, 8 bytes each, must take
    at most SAMPLES_SHARE_OF_MEMORY of physical_memory(). `names`: how the message names the
    two (the API's arguments, or the command line's options)."""
    memory = physical_memory()
    if memory is None:
        return None
    columns = len(outputs_of(scene.components)) + 1
    samples = float(stop_time) / float(output_interval) + 1.0  # inf past the largest float
    most = SAMPLES_SHARE_OF_MEMORY * memory / (8.0 * columns)
    if samples <= most:
        return None
    return (f"{names[0]} {float(stop_time):g} s with {names[1]} {float(output_interval):g} s "
            f"is {samples:.3g} samples of {columns} values (the outputs and the time), "
            f"{_bytes(8.0 * columns * samples)}; allowed: at most {most:.3g} samples of this "
            f"scene, within {SAMPLES_SHARE_OF_MEMORY:.0%} of this machine's {_bytes(memory)} of "
            f"memory (a longer {names[1]} or a shorter {names[0]})")


def _bytes(size: float) -> str:
    """A size in bytes as messages write it: "7.28 TiB"."""
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if size < 1024.0 or unit == "PiB":
            return f"{size:.3g} {unit}"
        size /= 1024.0
    return f"{size:.3g} PiB"


def check_reference_run(scene, stop_time=None, output_interval=None, tolerance=1e-10,
                        method="DOP853", initial_pinion_angle=0.0) -> None:
    """Every argument of reference.reference_simulate; ValueError (SceneError for the scene)
    naming the first culprit and what is allowed."""
    check_run_times(scene, stop_time, output_interval, initial_pinion_angle)
    REFERENCE_TOLERANCE_ARGUMENT.check(tolerance)
    REFERENCE_METHOD.check(method)


def check_compiled_run(scene, stop_time=None, output_interval=None, tolerance=1e-7,
                       method="auto", max_step=math.inf) -> None:
    """Every argument of herringbone.simulate; ValueError (SceneError for the scene) naming the
    first culprit and what is allowed."""
    check_run_times(scene, stop_time, output_interval)
    COMPILED_TOLERANCE_ARGUMENT.check(tolerance)
    COMPILED_METHOD.check(method)
    MAX_STEP.check(max_step)
    note = max_step_note(max_step)
    if note is not None:
        warnings.warn(MaxStepWarning(note), stacklevel=3)


def check_speeds(speeds, name="speeds"):
    """A non-empty array of pinion speeds (of their own shape), each finite and > 0 rad/s;
    else ValueError."""
    return _numbers(speeds, name, PINION_SPEED.describe(),
                    lambda values: (values > 0.0) & (values < float("inf")))


SWEPT_VALUES = "one or more finite numbers, in the quantity's unit"


def check_values(values, name):
    """A non-empty one-dimensional array of finite numbers (what a quantity `name` is swept or
    continued over); else ValueError naming `name`."""
    import numpy as np

    array = np.atleast_1d(_numbers(values, name, SWEPT_VALUES, np.isfinite))
    if array.ndim != 1:
        raise ValueError(f"{name} has the shape {array.shape}; allowed: {SWEPT_VALUES}")
    return array


def _numbers(values, name, allowed, admissible):
    """`values` as an array of floats of its own shape, not empty and each `admissible` (an
    elementwise test of the array); else ValueError naming `name` and what is `allowed`."""
    import numpy as np

    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be numbers, got {values!r}; allowed: {allowed}") from None
    bad = array[~admissible(array)]
    if array.size == 0 or bad.size:
        what = "is empty" if array.size == 0 else f"holds {float(bad.flat[0])!r}"
        raise ValueError(f"{name} {what}; allowed: {allowed}")
    return array


class SpeedSweep(NamedTuple):
    """`--speeds FROM TO COUNT`: COUNT evenly spaced pinion speeds from FROM to TO, in rad/s
    (or rpm, `in_rpm`)."""

    low: float
    high: float
    size: int
    in_rpm: bool = False

    def speeds(self):
        """The speeds, rad/s (numpy array)."""
        import numpy as np

        scale = 1.0 / RPM_PER_RAD_S if self.in_rpm else 1.0
        return np.linspace(self.low, self.high, self.size) * scale


# what `--speeds FROM TO COUNT` allows, in words (every command's message says it so)
SPEED_SWEEP_ALLOWED = "0 < FROM < TO (rad/s, or rpm with --rpm), COUNT >= 2 speeds"


def speed_sweep_problem(low: float, high: float, count: float) -> str | None:
    """Why FROM TO COUNT of `--speeds` (every command that takes speeds) is not allowed, or
    None."""
    for label, value in (("FROM", low), ("TO", high)):
        if PINION_SPEED.problem(value) is not None:
            return f"{label} {value:g} is not a finite speed > 0"
    if not low < high:
        return f"FROM {low:g} is not below TO {high:g}"
    if SPEED_COUNT.problem(count) is not None:
        return (f"COUNT {count:g} is not a whole number" if count != int(count)
                else f"COUNT {count:g} is fewer than 2 speeds")
    return None


def number(text: str) -> float:
    """argparse `type=` for a plain number: float(text), or ArgumentTypeError "TEXT: …",
    which says how to give a number written with its unit (`1500rpm`)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text}: not a number{unit_hint(text)}") from None


def unit_hint(text: str, unit: str | None = None) -> str:
    """"; allowed: …" for `text` that is a number followed by a unit ("1500rpm", "4 mm"),
    for a value whose unit is `unit` (None: an option's, which its --help gives; "" or "1":
    none); "" for other text. rpm, the unit a speed is most often written in, gets --rpm or
    its value in rad/s."""
    given = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s].*?)\s*",
                         text)
    if given is None:
        return ""
    value, written = float(given[1]), given[2]
    if unit is None:
        return ("; allowed: the number alone, with --rpm where the command takes rpm"
                if written.lower() == "rpm" else
                "; allowed: the number alone, in the unit --help gives")
    if written.lower() == "rpm" and unit == "rad/s":
        return (f"; allowed: a number in rad/s ({value:g} rpm is "
                f"{value / RPM_PER_RAD_S:.6g} rad/s)")
    return f"; allowed: the number alone{'' if unit in ('', '1') else f', in {unit}'}"


def output_path_problem(path: Path) -> str | None:
    """Why a file cannot be written at `path`, or None: the nearest existing ancestor must be
    a folder we may write in, and `path` no folder; the folder of `path` is made here and a
    file written in it, so that no long run ends on an output it cannot write, and both are
    removed again (the writer makes the folder), so that a command refused after its options
    were read leaves nothing behind."""
    path = Path(path)
    unusable = name_problem(path)
    if unusable is not None:
        return unusable
    if path.is_dir():
        return f"{path} is a folder"
    ancestor = path.parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        return f"{ancestor} is a file, not a folder"
    if not os.access(ancestor, os.W_OK | os.X_OK):
        return f"the folder {ancestor} is not writable"
    # where access() cannot tell (root, /proc, a read-only mount): make the folder and a file
    made = [folder for folder in (path.parent, *path.parent.parents) if not folder.exists()]
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path.parent):
            pass
    except OSError as error:
        return f"cannot write in {path.parent}: {error.strerror}"
    finally:
        for folder in made:  # deepest first
            with contextlib.suppress(OSError):
                folder.rmdir()
    return None


def name_problem(path: Path) -> str | None:
    """Why the file system cannot even look `path` up ("File name too long": a name over its
    255 bytes, which Path.is_dir() and exists() raise as OSError rather than answer), or
    None."""
    try:
        Path(path).exists()
    except OSError as error:
        return f"the file system cannot look it up: {error.strerror or error}"
    return None


def output_file_problem(path: Path, suffixes: tuple[str, ...] = ()) -> str | None:
    """Why the file `path` cannot be written (see output_path_problem) or does not end in one
    of `suffixes` (any, when empty); None if it can."""
    unusable = name_problem(Path(path))
    if unusable is not None:
        return unusable
    if suffixes and not Path(path).is_dir() and Path(path).suffix.lower() not in suffixes:
        return f"not a {' or '.join(suffixes)} file"
    return output_path_problem(Path(path))


def output_file(*suffixes: str):
    """argparse `type=` for a file to write ending in one of `suffixes`: returns the check,
    which gives the Path or raises ArgumentTypeError saying why not and what is allowed."""
    def checked(text: str) -> Path:
        problem = output_file_problem(Path(text), suffixes)
        if problem is not None:
            kind = f"a {' or '.join(suffixes)} file" if suffixes else "a file"
            raise argparse.ArgumentTypeError(f"{text}: cannot write there: {problem}; allowed: "
                                             f"{kind} in a folder that exists or can be made "
                                             "and that you can write in")
        return Path(text)

    return checked


# where a gear FMU carries its scene: the file in its resources (fmu/builder.build_gear_fmu
# puts it there, fmu/core.py loads it), and that file in the FMU's archive
FMU_SCENE_FILE = "scene.toml"
FMU_SCENE_MEMBER = f"resources/{FMU_SCENE_FILE}"
GEAR_FMU_ALLOWED = "the path of a gear FMU (herringbone build-fmu SCENE builds one)"


def gear_fmu_problem(path: Path) -> str | None:
    """Why `path` is not a gear FMU to read, or None: an existing .fmu file, a zip archive
    that carries its scene (FMU_SCENE_MEMBER)."""
    import zipfile

    path = Path(path)
    unusable = name_problem(path)
    if unusable is not None:
        return unusable
    if not path.is_file():
        return "no such FMU file" if not path.exists() else "a folder, not an FMU file"
    if path.suffix.lower() != ".fmu":
        return f"not an FMU file (its suffix is {path.suffix or 'none'}, not .fmu)"
    try:
        with zipfile.ZipFile(path) as archive:
            members = archive.namelist()
    except (zipfile.BadZipFile, OSError):
        return "not an FMU (an FMU is a zip archive; this file is none)"
    if FMU_SCENE_MEMBER not in members:
        return f"not a gear FMU (it carries no {FMU_SCENE_MEMBER})"
    return None


def existing_fmu(text: str) -> Path:
    """argparse `type=` for a gear FMU to read: the Path (gear_fmu_problem), or
    ArgumentTypeError saying why not."""
    problem = gear_fmu_problem(Path(text))
    if problem is not None:
        raise argparse.ArgumentTypeError(f"{text}: {problem}; allowed: {GEAR_FMU_ALLOWED}")
    return Path(text)


def output_path(text: str) -> Path:
    """argparse `type=` for a file to write: the Path, or ArgumentTypeError saying why not."""
    problem = output_path_problem(Path(text))
    if problem is not None:
        raise argparse.ArgumentTypeError(f"{text}: cannot write there: {problem}; allowed: a "
                                         "file in a folder that exists or can be made and "
                                         "that you can write in")
    return Path(text)


def output_folder(text: str) -> Path:
    """argparse `type=` for a folder to write files in: the Path, or ArgumentTypeError."""
    path = Path(text)
    problem = name_problem(path)
    if problem is None:
        problem = (f"{path} is a file" if path.exists() and not path.is_dir()
                   else output_path_problem(path / "file"))
    if problem is not None:
        raise argparse.ArgumentTypeError(f"{text}: cannot write there: {problem}; allowed: a "
                                         "folder that exists or can be made and that you can "
                                         "write in")
    return path


# a negative number as an argument, exponent included (Python 3.13's argparse reads it so)
NEGATIVE_NUMBER = re.compile(r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$")


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line on stderr, "PROG: --option VALUE: allowed: …",
    and exit code 2: no usage block (`PROG --help` shows it, and the line says so).
    help_command: how to ask for that help, if not `PROG --help`."""

    def __init__(self, *args, help_command: str | None = None, **kwargs):
        super().__init__(*args, **kwargs)
        self.help_command = help_command or f"{self.prog} --help"
        # argparse before Python 3.13 takes `-1e-7` for an option ("expected one argument"),
        # where its checks would say what is allowed; no option of ours looks like a number
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message):
        """One line on stderr naming the option and what is allowed, then exit code 2."""
        # argparse says "argument --stop-time: -1: allowed …": drop the word, keep the option
        if message.startswith("argument "):
            option, _, rest = message[len("argument "):].partition(": ")
            choice = re.fullmatch(r"invalid choice: (.*) \(choose from (.*)\)", rest)
            if choice:
                given, allowed = choice[1].strip("'"), re.findall(r"'([^']*)'", choice[2])
                rest = f"{choice[1]}: allowed: {choice[2]}{did_you_mean(given, allowed)}"
            elif re.fullmatch(r"expected (one|\d+) arguments?", rest):
                rest = f"{rest}; allowed: {option.split('/')[-1]} {self._values_of(option)}"
            message = f"{option.split('/')[-1]} {rest}"
        print(f"{self.prog}: {message}; see `{self.help_command}`", file=sys.stderr)
        sys.exit(2)

    def _values_of(self, option: str) -> str:
        """The values `option` (as argparse names it: "--speeds" or "-o/--output") takes, as
        its metavar names them ("FROM TO COUNT")."""
        for action in self._actions:
            if "/".join(action.option_strings) == option or option in action.option_strings:
                metavar = action.metavar or action.dest.upper()
                return " ".join(metavar) if isinstance(metavar, tuple) else str(metavar)
        return "VALUE"
