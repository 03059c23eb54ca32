"""Bad input: every way to hand the train something it cannot run gets ONE clear message
that names the culprit (and, for a value, what is allowed), through the Python API, through the
FMU and through the command line; nothing crashes and nothing prints a traceback.

CASES is the table: one row per bad input, with the words its message must contain. The rows of
every parameter come from herringbone.parameters.PARAMETERS itself (below its minimum, at an
open bound, above its maximum, NaN, +inf, -inf, a string, a boolean, a non-integer for the
integers, a number for the flags), so a parameter added there is tested here.

Routes (a row takes every route that can carry its value):
- api:  scene_from_dict, Scene.with_parameters / Scene.with_inputs and load_scene of a file
        holding the row must raise herringbone.SceneError with a one-line message;
- fmu:  the value set on the reference FMU (tests/helpers/fmu_host.py, FMU2Slave in this
  process) as a
        start value, or for an input also before a later doStep: an error-status log message
        naming the culprit, the same message every time, and doStep ends in fmi2Discard (the
        host lives on). FMI can carry only Real values into a Real variable and whole numbers
        into an Integer one, so strings, booleans, fractions and NaN of integers go by the api;
- cli:  `herringbone run FILE` (and for some rows `herringbone info FILE` and
        `python build_fmu.py FILE`) exits with code 2 and one line on stderr, no traceback;
- call: a run argument handed to the API functions the row names (simulate,
        reference_simulate, simulate_with, stability_chart, monodromy, sweep,
        continue_in_parameter) raises ValueError
        (SceneError for the scene) with a one-line message, before any model is built;
- argv: a command line with a bad option or argument (`herringbone run|info|
        stability|benchmark`, `python build_fmu.py`) exits with code 2, nothing on stdout,
        one line on stderr naming the option and what is allowed, and writes nothing.
"""
import math
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from helpers import MODELS
from helpers.fmu_host import Instance

import herringbone
from herringbone import SceneError, arguments
from herringbone.model.parameters import INPUTS, PARAMETERS

NAN, INF = float("nan"), float("inf")
DISCARD, ERROR, FATAL = 2, 3, 4  # fmi2Status
ROOT = MODELS.parent
REFERENCE_TEXT = (MODELS / "reference.toml").read_text()


def allowed_words(argument: arguments.Argument) -> tuple[str, ...]:
    """What a message about `argument` must say is allowed, read from herringbone.arguments
    (the one home of the ranges): each choice quoted, or the range in words ("[1e-12, 0.01]")."""
    if argument.choices is not None:
        return tuple(repr(choice) for choice in argument.choices)
    return (("0, " if argument.zero else "") + argument.allowed.describe()
            + (" or inf" if argument.infinite else ""),)


# The FMU's own settings: name -> what its message must say is allowed.
SOLVER_SETTINGS = {argument.name: allowed_words(argument) for argument in (
    arguments.FMU_SOLVER_TOLERANCE, arguments.FMU_MAX_STEP, arguments.FMU_SOLVER_METHOD)}


@dataclass(frozen=True)
class Case:
    id: str
    kind: str  # "parameter", "input", "solver", "experiment", "table", "file"
    name: str  # the culprit: the variable or key, or for a file the problem
    value: object = None  # the bad value; for "file" the file's text (None: no file at all)
    words: tuple = ()  # what the message must contain (besides the file, for files)
    routes: tuple = ("api",)
    # for "file": which command lines to try
    commands: tuple = field(default=())


def _fmu_can_carry(parameter, value):
    """Whether FMI 2.0 can set `value` on the variable of `parameter`."""
    if parameter.kind is bool or isinstance(value, (bool, str)):
        return False
    if parameter.kind is int:
        return isinstance(value, int)
    return isinstance(value, (int, float))


def _parameter_cases():
    cases = []
    for name, p in PARAMETERS.items():
        if p.kind is bool:
            for label, value in (("number", 1), ("string", "yes"), ("nan", NAN)):
                cases.append(Case(f"{name}-{label}", "parameter", name, value,
                                  (name, "true or false")))
            continue
        allowed = p.allowed.describe()
        values = []
        r = p.allowed
        if r.low is not None:
            if r.low_open:
                values.append(("at-open-minimum", p.kind(r.low)))
            values.append(("below-minimum", p.kind(r.low - 1) if p.kind is int
                           else r.low - 0.25 - abs(r.low)))
        if r.high is not None:
            if r.high_open:
                values.append(("at-open-maximum", r.high))
            values.append(("above-maximum", r.high + 0.5))
        values += [("nan", NAN), ("plus-inf", INF), ("minus-inf", -INF)]
        for label, value in values:
            cases.append(Case(f"{name}-{label}", "parameter", name, value, (name, allowed),
                              ("api", "fmu") if _fmu_can_carry(p, value) else ("api",)))
        cases.append(Case(f"{name}-string", "parameter", name, "4 mm", (name, "must be a number")))
        cases.append(Case(f"{name}-boolean", "parameter", name, True, (name, "must be a number")))
        if p.kind is int:
            cases.append(Case(f"{name}-fraction", "parameter", name, 2.5, (name, "whole number")))
    return cases


def _solver_cases():
    non_finite = [("nan", NAN), ("plus-inf", INF), ("minus-inf", -INF)]
    values = {"solver_tolerance": [("below-minimum", 1e-13), ("zero", 0.0), ("negative", -1e-7),
                                   ("above-maximum", 0.5)] + non_finite,
              # inf is allowed: no limit, as 0 (test_fmi_contract runs it); between 0 and the
              # API's shortest max_step a run would fail at its first step
              "max_step": [("below-minimum", -1e-3), ("nan", NAN), ("minus-inf", -INF),
                           ("tiny", 1e-300)],
              "solver_method": [("unknown", "rk4"), ("empty", ""), ("capitals", "DOP853")]}
    return [Case(f"{name}-{label}", "solver", name, value, (name, *allowed), ("fmu",))
            for name, allowed in SOLVER_SETTINGS.items() for label, value in values[name]]


def _input_cases():
    cases = []
    for name in INPUTS:
        for label, value in (("nan", NAN), ("plus-inf", INF), ("minus-inf", -INF)):
            cases.append(Case(f"{name}-{label}", "input", name, value, (name, "finite"),
                              ("api", "fmu")))
        cases.append(Case(f"{name}-string", "input", name, "500 N.m", (name, "must be a number")))
    for label, row in (("nan-torque", [0.0, NAN, 1800.0]), ("inf-torque", [0.0, 500.0, INF]),
                       ("nan-time", [NAN, 500.0, 1800.0])):
        cases.append(Case(f"table-{label}", "table", "table", [row],
                          ("table row 0", "three finite numbers")))
    return cases


def _experiment_cases():
    cases = []
    for name in ("stop_time", "output_interval"):
        for label, value in (("zero", 0.0), ("negative", -0.1), ("nan", NAN), ("plus-inf", INF),
                             ("string", "1 s")):
            cases.append(Case(f"{name}-{label}", "experiment", name, value, (name, "> 0")))
    return cases


def _cut_in_a_key(text, fraction):
    """`text` cut in the middle of the key of the key line nearest `fraction` of the file."""
    offsets, position = [], 0
    for line in text.splitlines(keepends=True):
        if "=" in line and not line.lstrip().startswith("#"):
            offsets.append((position, len(line.split("=")[0].strip())))
        position += len(line)
    start, length = offsets[min(int(fraction * len(offsets)), len(offsets) - 1)]
    return text[:start + max(1, length // 2)]


def _cut_after(text, marker, keep):
    return text[:text.index(marker) + keep]


ALL_COMMANDS = ("run", "info", "build_fmu")
FILE_CASES = [
    Case("missing-file", "file", "no such scene file", None, ("no such scene file",),
         ("api", "cli"), ALL_COMMANDS),
    Case("malformed-toml", "file", "not a valid TOML file", "[parameters\nbeta = 0.3\n",
         ("not a valid TOML file", "line 1"), ("api", "cli"), ALL_COMMANDS),
    Case("malformed-value", "file", "not a valid TOML file", "[parameters]\nbeta = 0.3.1\n",
         ("not a valid TOML file", "line 2"), ("api", "cli"), ("run",)),
    Case("not-utf8", "file", "not a valid TOML file", b"[parameters]\nbeta = 0.3 # \xff\xfe\n",
         ("not a valid TOML file",), ("api", "cli"), ("run",)),
    Case("truncated-mid-key", "file", "not a valid TOML file",
         _cut_in_a_key(REFERENCE_TEXT, 0.5), ("not a valid TOML file",), ("api", "cli"),
         ALL_COMMANDS),
    Case("truncated-mid-table-name", "file", "not a valid TOML file",
         _cut_after(REFERENCE_TEXT, "[experiment]", 6), ("not a valid TOML file",),
         ("api", "cli"), ("run",)),
    Case("truncated-mid-input-table", "file", "not a valid TOML file",
         "[inputs]\ntable = [[0.0, 500.0, 1800.0], [0.05, 10",
         ("not a valid TOML file",), ("api", "cli"), ("run",)),
    Case("unknown-parameter", "file", "module", "[parameters]\nmodule = 0.004\n",
         ("module", "unknown parameter"), ("api", "cli"), ("run",)),
    # tomllib names the line of a key given twice, not the key: the line is shown
    Case("duplicate-key", "file", "z_pinion", "[parameters]\nz_pinion = 10\nz_pinion = 12\n",
         ("not a valid TOML file", "line 3", "`z_pinion = 12` (a key given twice?)"),
         ("api", "cli"), ("run",)),
    Case("table-in-parameters", "file", "gear", "[parameters.gear]\nz = 3\n",
         ("unknown parameter 'gear'", "[parameters.gear] is a table", "no tables in it"),
         ("api", "cli"), ("run",)),
    Case("output-interval-over-stop-time", "file", "output_interval",
         "[experiment]\nstop_time = 1e-3\noutput_interval = 2e-3\n",
         ("output_interval 0.002 s exceeds stop_time 0.001 s",
          "allowed: output_interval <= stop_time"), ("api", "cli"), ("run",)),
    Case("unknown-experiment-key", "file", "duration", "[experiment]\nduration = 1.0\n",
         ("duration", "stop_time, output_interval"), ("api", "cli"), ("run",)),
    Case("misspelt-component", "file", "bearing", "[components]\nbearing = false\n",
         ("unknown component 'bearing'", "did you mean 'bearings'"), ("api", "cli"), ("run",)),
    Case("misspelt-experiment-key", "file", "stoptime", "[experiment]\nstoptime = 0.01\n",
         ("stoptime", "did you mean 'stop_time'"), ("api", "cli"), ("run",)),
    Case("table-times-falling", "file", "table",
         "[inputs]\ntable = [[0.0, 500.0, 1800.0], [0.05, 500.0, 1800.0], "
         "[0.02, 500.0, 1800.0]]\n",
         ("table row 2 is at time 0.02 s, not after row 1's 0.05 s", "increase strictly"),
         ("api", "cli"), ("run",)),
    Case("unknown-input-key", "file", "torque", "[inputs]\ntorque = 500.0\n",
         ("torque", "M_motor, M_load, table"), ("api", "cli"), ("run",)),
    Case("unknown-table", "file", "solver", "[solver]\nrtol = 1e-6\n",
         ("[solver]", "[parameters]", "[experiment]"), ("api", "cli"), ("run",)),
    Case("misspelt-table", "file", "parameter", "[parameter]\nbeta = 0.3\n",
         ("[parameter]", "[parameters]"), ("api", "cli"), ("run",)),
    Case("key-outside-any-table", "file", "beta", "beta = 0.3\n",
         ("beta", "[parameters]"), ("api", "cli"), ("run",)),
    # a key in the wrong table: say where it belongs, as an input in [parameters] already does
    Case("input-in-parameters", "file", "M_motor", "[parameters]\nM_motor = 500.0\n",
         ("M_motor", "[inputs]"), ("api", "cli"), ("run",)),
    Case("parameter-in-experiment", "file", "beta", "[experiment]\nbeta = 0.3\n",
         ("beta", "[parameters]"), ("api", "cli"), ("run",)),
    Case("parameter-in-inputs", "file", "stagger", "[inputs]\nstagger = 0.5\n",
         ("stagger", "[parameters]"), ("api", "cli"), ("run",)),
    Case("table-not-a-table", "file", "parameters", "parameters = 5\n",
         ("parameters", "table"), ("api", "cli"), ("run",)),
    Case("parameter-of-a-left-out-component", "file", "c_brg_wheel_left",
         "[components]\nbearings = false\n[parameters]\nc_brg_wheel_left = 1e9\n",
         ("c_brg_wheel_left", "bearings = false"), ("api", "cli"), ("run",)),
    # bad values written in a file reach the command line as one line too
    Case("file-value-out-of-range", "file", "m_pinion", "[parameters]\nm_pinion = -1.0\n",
         ("m_pinion", "[1e-09, 1e+07]"), ("api", "cli"), ("run", "build_fmu")),
    Case("file-integer-nan", "file", "z_pinion", "[parameters]\nz_pinion = nan\n",
         ("z_pinion", "a whole number [1, 1000]"), ("api", "cli"), ("run", "build_fmu")),
]


# Run arguments: "call" rows hand `value` (keyword arguments) to each API function in
# `commands`, which must raise ValueError (SceneError for the scene) before any work; "argv"
# rows run a command line, `value` its arguments ({scene}: models/reference.toml, {file}: a
# plain file, so "{file}/x" lies in no folder), `commands` the program: herringbone or build_fmu.
COMPILED_TOL = ("tolerance", *allowed_words(arguments.COMPILED_TOLERANCE_ARGUMENT))
REFERENCE_TOL = ("tolerance", *allowed_words(arguments.REFERENCE_TOLERANCE_ARGUMENT))
RUNS = ("simulate", "reference_simulate")
SPANS = RUNS + ("simulate_with",)


def _call_cases():
    rows = []  # (id, culprit, keyword arguments, words, functions)
    for label, value in (("negative", -1), ("zero", 0.0), ("nan", NAN), ("plus-inf", INF),
                         ("string", "1 s"), ("boolean", True)):
        rows.append((f"stop_time-{label}", "stop_time", {"stop_time": value},
                     ("stop_time", "> 0"), SPANS))
    for label, value in (("zero", 0.0), ("negative", -1e-4), ("nan", NAN), ("plus-inf", INF)):
        rows.append((f"output_interval-{label}", "output_interval", {"output_interval": value},
                     ("output_interval", "> 0"), SPANS))
    rows.append(("output_interval-longer-than-stop_time", "output_interval",
                 {"stop_time": 1e-3, "output_interval": 1e-2},
                 ("output_interval", "<= stop_time"), SPANS))
    for label, value in (("zero", 0.0), ("negative", -1e-7), ("below-minimum", 1e-13),
                         ("above-maximum", 0.5), ("one", 1.0), ("nan", NAN)):
        rows.append((f"compiled-tolerance-{label}", "tolerance", {"tolerance": value},
                     COMPILED_TOL, ("simulate",)))
    for label, value in (("zero", 0.0), ("below-minimum", 1e-13), ("above-maximum", 1e-4),
                         ("one", 1.0), ("nan", NAN)):
        rows.append((f"reference-tolerance-{label}", "tolerance", {"tolerance": value},
                     REFERENCE_TOL, ("reference_simulate",)))
    for label, value in (("unknown", "rk4"), ("capitals", "DOP853"), ("none", None)):
        rows.append((f"compiled-method-{label}", "method", {"method": value},
                     ("method", "'auto'", "'dop853'", "'radau'"), ("simulate",)))
    for label, value in (("unknown", "rk4"), ("lower-case", "dop853")):
        rows.append((f"reference-method-{label}", "method", {"method": value},
                     ("method", "'DOP853'", "'Radau'"), ("reference_simulate",)))
    for label, value in (("zero", 0.0), ("negative", -1e-3), ("nan", NAN)):
        rows.append((f"max_step-{label}", "max_step", {"max_step": value},
                     ("max_step", *allowed_words(arguments.MAX_STEP)), ("simulate",)))
    for label, value in (("nan", NAN), ("plus-inf", INF), ("string", "0")):
        rows.append((f"initial_pinion_angle-{label}", "initial_pinion_angle",
                     {"initial_pinion_angle": value}, ("initial_pinion_angle", "finite"),
                     ("reference_simulate", "simulate_with")))
    for label, kwargs, functions in (("", {}, SPANS), ("-chart", {"speeds": [100.0]},
                                                       ("stability_chart",)),
                                     ("-monodromy", {"pinion_speed": 100.0}, ("monodromy",))):
        rows.append((f"scene-a-path{label}", "scene", {"scene": "models/reference.toml", **kwargs},
                     ("scene", "herringbone.Scene", "load_scene"), functions))
    for label, value in (("negative", [100.0, -1.0]), ("zero", [0.0, 100.0]),
                         ("nan", [NAN]), ("plus-inf", [100.0, INF]), ("empty", [])):
        rows.append((f"speeds-{label}", "speeds", {"speeds": value}, ("speeds", "> 0"),
                     ("stability_chart", "sweep")))
    for label, value in (("empty", []), ("nan", [0.02, NAN]), ("minus-inf", [-INF]),
                         ("string", ["low"]), ("a-table", [[0.02, 0.03]])):
        swept = ("zeta_mesh", "one or more finite numbers")
        rows.append((f"swept-values-{label}", "zeta_mesh", {"params": {"zeta_mesh": value}},
                     swept, ("sweep",)))
        rows.append((f"continued-values-{label}", "zeta_mesh",
                     {"name": "zeta_mesh", "values": value}, swept, ("continue_in_parameter",)))
    for label, value in (("zero", 0.0), ("negative", -5.0), ("plus-inf", INF),
                         ("string", "fast")):
        rows.append((f"pinion_speed-{label}", "pinion_speed", {"pinion_speed": value},
                     ("pinion_speed", "> 0"), ("monodromy",)))
    for name, value, words in (("settle_residual", 1.0, ("(0, 1)",)),
                               ("settle_time", -1.0, (">= 0",)),
                               ("window_periods", 2.5, ("whole number >= 1",)),
                               ("samples_per_period", 3, ("whole number >= 4",)),
                               ("tolerance", 0.5, COMPILED_TOL[1:])):
        rows.append((f"protocol-{name}", name, {name: value}, (name, *words), ("Protocol",)))
    return [Case(f"call-{id}", "argument", name, kwargs, words, ("call",), functions)
            for id, name, kwargs, words, functions in rows]


RUN = ("run", "{scene}")
STABILITY = ("stability", "{scene}")
RUN_TOL = ("--tolerance", *allowed_words(arguments.COMPILED_TOLERANCE_ARGUMENT))
SWEEP_RUN = ("sweep", "{scene}", "--speeds", "100", "200", "2")
SWEEP = ("--speeds", "0 < FROM < TO")
OPTION_ROWS = [  # (id, culprit, arguments, words, program)
    ("run-stop-time-negative", "--stop-time", RUN + ("--stop-time", "-1"),
     ("--stop-time -1", "> 0"), "herringbone"),
    ("run-stop-time-nan", "--stop-time", RUN + ("--stop-time", "nan"),
     ("--stop-time nan", "> 0"), "herringbone"),
    ("run-stop-time-not-a-number", "--stop-time", RUN + ("--stop-time", "1s"),
     ("--stop-time 1s", "not a number", "> 0"), "herringbone"),
    ("run-output-interval-zero", "--output-interval", RUN + ("--output-interval", "0"),
     ("--output-interval 0", "> 0"), "herringbone"),
    ("run-output-interval-inf", "--output-interval", RUN + ("--output-interval", "inf"),
     ("--output-interval inf", "> 0"), "herringbone"),
    ("run-output-interval-longer-than-stop-time", "--output-interval",
     RUN + ("--stop-time", "1e-3", "--output-interval", "1e-2"),
     ("--output-interval", "<= the stop time"), "herringbone"),
    # the scene's own output interval (1e-4 s) outlasts a stop time shorter than it
    ("run-stop-time-below-the-scenes-interval", "--output-interval",
     RUN + ("--stop-time", "1e-5"), ("--output-interval", "<= the stop time"), "herringbone"),
    ("run-tolerance-zero", "--tolerance", RUN + ("--tolerance", "0"), RUN_TOL, "herringbone"),
    ("run-tolerance-one", "--tolerance", RUN + ("--tolerance", "1"), RUN_TOL, "herringbone"),
    # (argparse before Python 3.13 took a negative number with an exponent for an option)
    ("run-tolerance-negative-exponent", "--tolerance", RUN + ("--tolerance", "-1e-7"),
     ("--tolerance -1e-07", *RUN_TOL[1:]), "herringbone"),
    ("run-tolerance-too-tight", "--tolerance", RUN + ("--tolerance", "1e-13"), RUN_TOL,
     "herringbone"),
    ("run-reference-tolerance-above-maximum", "--tolerance",
     RUN + ("--reference", "--tolerance", "1e-4"),
     ("--tolerance", *allowed_words(arguments.REFERENCE_TOLERANCE_ARGUMENT)), "herringbone"),
    ("run-unknown-option", "--bogus", RUN + ("--bogus",), ("--bogus", "--help"), "herringbone"),
    ("run-missing-scene", "SCENE", ("run",), ("SCENE", "required"), "herringbone"),
    ("run-output-in-no-folder", "--output", RUN + ("-o", "{file}/out.csv"),
     ("--output", "is a file, not a folder", "folder"), "herringbone"),
    ("run-output-a-folder", "--output", RUN + ("-o", "{tmp}"), ("--output", "is a folder"),
     "herringbone"),
    # without -o it writes results/<scene>.csv: here "results" is a file
    ("run-default-output-in-no-folder", "results", RUN, ("results", "-o FILE"),
     "herringbone"),
    # a name over the file system's 255 bytes: Path.is_dir() raised "File name too long"
    ("run-output-name-too-long", "--output", RUN + ("-o", "{tmp}/" + "a" * 300 + ".csv"),
     ("--output", "File name too long", "allowed: a .csv file"), "herringbone"),
    ("run-method-unknown", "--method", RUN + ("--method", "rk4"),
     ("--method 'rk4'", *allowed_words(arguments.COMPILED_METHOD)), "herringbone"),
    ("run-method-with-reference", "--method", RUN + ("--reference", "--method", "dop853"),
     ("--method dop853 with --reference", "allowed: --method without --reference"),
     "herringbone"),
    # a number written with its unit: the unit to give it in, rpm converted
    ("run-set-a-speed-in-rpm", "--set", RUN + ("--set", "w0_pinion=1500rpm"),
     ("'1500rpm'", "allowed: a number in rad/s", "1500 rpm is 157.08 rad/s"), "herringbone"),
    ("run-set-a-length-with-its-unit", "--set", RUN + ("--set", "b_left=40 mm"),
     ("'40 mm'", "allowed: the number alone, in m"), "herringbone"),
    ("sweep-speed-in-rpm", "--speed", ("sweep", "{scene}", "--param", "zeta_mesh", "0.02",
                                       "0.1", "3", "--speed", "1500rpm"),
     ("--speed 1500rpm", "with --rpm"), "herringbone"),
    ("campbell-speeds-short", "--speeds", ("campbell", "{scene}", "--speeds", "50", "3000"),
     ("--speeds expected 3 arguments", "allowed: --speeds FROM TO COUNT"), "herringbone"),
    ("run-flag-with-a-value", "--plot", RUN + ("--plot=yes",),
     ("--plot=yes", "takes no value", "allowed: --plot alone"), "herringbone"),
    ("info-missing-scene", "SCENE", ("info",), ("SCENE", "required"), "herringbone"),
    ("info-set-out-of-range", "--set", ("info", "{scene}", "--set", "zeta_mesh=-1"),
     ("--set zeta_mesh=-1", "zeta_mesh is -1", "[0, 10]"), "herringbone"),
    ("run-set-not-a-value", "--set", RUN + ("--set", "beta=abc"),
     ("--set 'beta=abc'", "not a number, true or false"), "herringbone"),
    ("info-unknown-option", "--bogus", ("info", "{scene}", "--bogus"), ("--bogus",),
     "herringbone"),
    ("stability-speeds-descending", "--speeds", STABILITY + ("--speeds", "100", "50", "3"),
     SWEEP + ("FROM 100 is not below TO 50",), "herringbone"),
    ("stability-speeds-zero", "--speeds", STABILITY + ("--speeds", "0", "50", "3"),
     SWEEP + ("FROM 0",), "herringbone"),
    ("stability-speeds-one-count", "--speeds", STABILITY + ("--speeds", "10", "50", "1"),
     SWEEP + ("COUNT 1", "COUNT >= 2"), "herringbone"),
    ("stability-speeds-fraction-count", "--speeds", STABILITY + ("--speeds", "10", "50", "2.5"),
     SWEEP + ("COUNT 2.5", "whole number"), "herringbone"),
    ("stability-speeds-nan", "--speeds", STABILITY + ("--speeds", "nan", "50", "3"),
     SWEEP + ("FROM nan",), "herringbone"),
    ("stability-speeds-two-values", "--speeds", STABILITY + ("--speeds", "10", "50"),
     ("--speeds", "3 arguments"), "herringbone"),
    # numpy's "Unable to allocate 745 GiB" and a traceback
    ("stability-speeds-too-many", "--speeds",
     STABILITY + ("--speeds", "10", "1e5", "99999999999"),
     SWEEP + ("COUNT 1e+11 is more than 100000 speeds", "at most 100000"), "herringbone"),
    ("stability-rpm-without-speeds", "--rpm", STABILITY + ("--rpm",),
     ("--rpm without --speeds", "allowed: --rpm with --speeds FROM TO COUNT"), "herringbone"),
    ("campbell-rpm-without-speeds", "--rpm", ("campbell", "{scene}", "--rpm"),
     ("--rpm without --speeds", "allowed: --rpm with --speeds FROM TO COUNT"), "herringbone"),
    # an output in a folder still to be made, then a refusal: the folder is not left behind
    ("run-tolerance-after-an-output-in-a-new-folder", "--tolerance",
     RUN + ("-o", "{tmp}/new/deeper/run.csv", "--tolerance", "0"),
     ("--tolerance 0", "allowed: [1e-12, 0.01]"), "herringbone"),
    ("stability-output-in-no-folder", "--output", STABILITY + ("-o", "{file}/chart.png"),
     ("--output", "is a file, not a folder"), "herringbone"),
    ("sweep-speed-negative", "--speed",
     ("sweep", "{scene}", "--param", "zeta_mesh", "0.02", "0.1", "3", "--speed", "-5"),
     ("--speed -5", "> 0"), "herringbone"),
    ("sweep-speed-with-speeds", "--speed", SWEEP_RUN + ("--param", "zeta_mesh", "0.02", "0.1",
                                                        "3", "--speed", "500"),
     ("--speed 500", "without --speeds"), "herringbone"),
    ("sweep-settle-residual-one", "--settle-residual", SWEEP_RUN + ("--settle-residual", "1"),
     ("--settle-residual 1", *allowed_words(arguments.SETTLE_RESIDUAL)), "herringbone"),
    ("sweep-settle-time-negative", "--settle-time", SWEEP_RUN + ("--settle-time", "-1"),
     ("--settle-time -1", ">= 0"), "herringbone"),
    ("sweep-window-periods-fraction", "--window-periods",
     SWEEP_RUN + ("--window-periods", "2.5"), ("--window-periods 2.5", "whole number >= 1"),
     "herringbone"),
    ("sweep-samples-per-period-two", "--samples-per-period",
     SWEEP_RUN + ("--samples-per-period", "2"), ("--samples-per-period 2", "whole number >= 4"),
     "herringbone"),
    ("sweep-tolerance-one", "--tolerance", SWEEP_RUN + ("--tolerance", "1"), RUN_TOL,
     "herringbone"),
    ("sweep-workers-negative", "--workers", SWEEP_RUN + ("--workers", "-1"),
     ("--workers -1", "whole number >= 0"), "herringbone"),
    ("sweep-through-fmu-missing", "--through-fmu",
     SWEEP_RUN + ("--through-fmu", "{tmp}/missing.fmu"), ("--through-fmu", "no such FMU file"),
     "herringbone"),
    ("sweep-output-a-file", "--output", SWEEP_RUN + ("-o", "{file}"),
     ("--output", "is a file", "folder"), "herringbone"),
    ("sweep-no-period-doubling-by-time", "--no-period-doubling",
     SWEEP_RUN + ("--method", "time", "--no-period-doubling", "-o", "{tmp}"),
     ("--no-period-doubling", "only with a sweep by --method shooting"), "herringbone"),
    ("campbell-speeds-descending", "--speeds", ("campbell", "{scene}", "--speeds", "500", "400",
                                                "2"), SWEEP + ("FROM 500 is not below TO 400",),
     "herringbone"),
    # taken before, though no scene takes a speed past 1e5 rad/s (w0_pinion's range)
    ("campbell-speeds-too-fast", "--speeds", ("campbell", "{scene}", "--speeds", "10", "1e300",
                                              "5"),
     SWEEP + ("TO 1e+300 rad/s is faster", "TO <= 100000 rad/s"), "herringbone"),
    ("campbell-speeds-too-fast-in-rpm", "--speeds",
     ("campbell", "{scene}", "--speeds", "10", "1e6", "5", "--rpm"),
     SWEEP + ("TO 1e+06 rpm is faster", "954930 rpm with --rpm"), "herringbone"),
    ("sweep-output-name-too-long", "--output", SWEEP_RUN + ("-o", "{tmp}/" + "a" * 300),
     ("--output", "File name too long", "allowed: a folder"), "herringbone"),
    ("campbell-output-not-a-picture", "--output", ("campbell", "{scene}", "-o", "{tmp}/c.csv"),
     ("--output", "not a .png"), "herringbone"),
    ("unknown-command", "COMMAND", ("frob",), ("COMMAND 'frob'", "'run'", "'stability'"),
     "herringbone"),
    ("no-command", "COMMAND", (), ("COMMAND", "required"), "herringbone"),
    ("benchmark-unknown", "bogus", ("benchmark", "bogus"),
     ("'bogus'", "error-vs-runtime, extreme-scenes"), "herringbone"),
    ("benchmark-tolerance-one", "--tolerances", ("benchmark", "--tolerances", "1e-6", "1"),
     ("--tolerances 1", *allowed_words(arguments.COMPILED_TOLERANCE_ARGUMENT)), "herringbone"),
    ("benchmark-repeat-zero", "--repeat", ("benchmark", "--repeat", "0"),
     ("--repeat 0", "whole number >= 1"), "herringbone"),
    ("benchmark-periods-negative", "--periods",
     ("benchmark", "extreme-scenes", "--periods", "-1"), ("--periods -1", ">= 0"),
     "herringbone"),
    ("build_fmu-unknown-option", "--bogus", ("--bogus",), ("--bogus", "build_fmu.py --help"),
     "build_fmu"),
    ("build_fmu-output-in-no-folder", "--output", ("{scene}", "-o", "{file}/x.fmu"),
     ("--output", "is a file, not a folder"), "build_fmu"),
    ("build_fmu-examples-a-file", "--examples", ("--examples", "{file}"),
     ("--examples", "is a file", "folder"), "build_fmu"),
    ("build_fmu-fmi-four", "--fmi", ("--fmi", "4"), ("--fmi 4", "allowed: 2, 3"), "build_fmu"),
    ("build_fmu-ssp-in-no-folder", "--ssp", ("--ssp", "{file}/x.ssp"),
     ("--ssp", "is a file, not a folder"), "build_fmu"),
    ("build_fmu-ssp-fmi-three", "--fmi", ("{scene}", "--fmi", "3", "--ssp", "{tmp}/x.ssp"),
     ("--fmi 3 with --ssp", "FMI 2.0", "libcosim", "leave out --fmi 3"), "build_fmu"),
    ("build_fmu-ssp-scene-without-motor-and-load", "--ssp",
     ("jump_resonance", "--ssp", "{tmp}/x.ssp"),
     ("--ssp", "jump_resonance has neither", "[components]", "allowed: a scene with motor and "
      "load"), "build_fmu"),
    ("build_fmu-examples-and-output", "--output",
     ("--examples", "{tmp}/ex", "-o", "{tmp}/x.fmu"),
     ("--output not allowed with argument --examples",), "build_fmu"),
    ("build_fmu-ssp-and-examples", "--ssp",
     ("{scene}", "--ssp", "{tmp}/x.ssp", "--examples", "{tmp}"),
     ("--examples not allowed with argument --ssp",), "build_fmu"),
    ("build_fmu-examples-simulate", "--simulate", ("--examples", "{tmp}/ex", "--simulate"),
     ("--simulate with --examples", "allowed: one of the two"), "build_fmu"),
    ("build_fmu-examples-fmi-three", "--fmi", ("--examples", "{tmp}/ex", "--fmi", "3"),
     ("--fmi 3 with --examples", "FMI 2.0", "leave out --fmi"), "build_fmu"),
    ("build_fmu-set-out-of-range", "--set", ("{scene}", "--set", "zeta_mesh=-1"),
     ("--set zeta_mesh=-1", "zeta_mesh is -1",
      f"allowed: {PARAMETERS['zeta_mesh'].allowed.describe()}"), "build_fmu"),
    ("build_fmu-set-with-examples", "--set",
     ("--examples", "{tmp}/ex", "--set", "zeta_mesh=0.1"),
     ("--set with --examples", "allowed: --set with the gear FMU or --ssp"), "build_fmu"),
    ("build_fmu-no-progress-with-a-value", "--no-progress", ("--no-progress=yes",),
     ("--no-progress=yes", "takes no value", "allowed: --no-progress alone"), "build_fmu"),
    ("build_fmu-ssp-name-too-long", "--ssp", ("--ssp", "{tmp}/" + "a" * 300 + ".ssp"),
     ("--ssp", "File name too long", "allowed: a .ssp file"), "build_fmu"),
]
OPTION_CASES = [Case(f"argv-{id}", "option", name, arguments, words, ("argv",), (program,))
                for id, name, arguments, words, program in OPTION_ROWS]

CASES = (_parameter_cases() + _solver_cases() + _input_cases() + _experiment_cases()
         + FILE_CASES + _call_cases() + OPTION_CASES)


def _cases(route):
    return [pytest.param(case, id=case.id) for case in CASES if route in case.routes]


def test_the_table_covers_every_parameter_and_input():
    culprits = {case.name for case in CASES}
    assert set(PARAMETERS) | set(INPUTS) | set(SOLVER_SETTINGS) <= culprits
    assert len({case.id for case in CASES}) == len(CASES)


# --- the Python API -----------------------------------------------------------------------------

def _toml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else "inf" if value == INF else "-inf" \
            if value == -INF else repr(value)
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def _file_text(case):
    if case.kind == "file":
        return case.value
    table = {"parameter": "parameters", "experiment": "experiment", "input": "inputs",
             "table": "inputs"}[case.kind]
    return f"[{table}]\n{case.name} = {_toml_value(case.value)}\n"


def _routes(case, tmp_path):
    """(route name, function raising the error) for every API route of a case."""
    path = tmp_path / "bad.toml"
    text = _file_text(case)
    if text is not None:
        (path.write_bytes if isinstance(text, bytes) else path.write_text)(text)
    routes = [("load_scene", lambda: herringbone.load_scene(path))]
    base = herringbone.scene_from_dict({})
    if case.kind == "parameter":
        routes += [("scene_from_dict", lambda: herringbone.scene_from_dict(
                        {"parameters": {case.name: case.value}})),
                   ("Scene.with_parameters", lambda: base.with_parameters(
                       **{case.name: case.value}))]
    elif case.kind == "input":
        routes += [("scene_from_dict", lambda: herringbone.scene_from_dict(
                        {"inputs": {case.name: case.value}})),
                   ("Scene.with_inputs", lambda: base.with_inputs(**{case.name: case.value}))]
    elif case.kind == "table":
        routes += [("Scene.with_inputs", lambda: base.with_inputs(table=case.value))]
    elif case.kind == "experiment":
        routes += [("scene_from_dict", lambda: herringbone.scene_from_dict(
            {"experiment": {case.name: case.value}}))]
    return path, routes


def assert_one_clear_message(message, words, where):
    assert message.strip() and "\n" not in message.strip(), f"{where}: not one line: {message!r}"
    assert "Traceback" not in message, f"{where}: a traceback: {message!r}"
    missing = [w for w in words if w not in message]
    assert not missing, f"{where}: {message!r} does not say {missing}"


@pytest.mark.parametrize("case", _cases("api"))
def test_api_raises_one_scene_error_naming_the_culprit(case, tmp_path):
    path, routes = _routes(case, tmp_path)
    if case.kind == "file" and case.value is None:
        path = tmp_path / "absent" / "missing.toml"
        routes = [("load_scene", lambda: herringbone.load_scene(path))]
    problems = []
    for route, provoke in routes:
        try:
            provoke()
        except SceneError as error:
            message = str(error)
            words = case.words + ((str(path),) if route == "load_scene" else ())
            try:
                assert_one_clear_message(message, words, route)
            except AssertionError as failure:
                problems.append(str(failure))
        except Exception as error:  # anything but a SceneError is a defect
            problems.append(f"{route}: raised {type(error).__name__}: {error}")
        else:
            problems.append(f"{route}: accepted {case.value!r}")
    assert not problems, "\n".join(problems)


# Scene.with_inputs' keywords that a scene file cannot give it: a misspelt one, a parameter, and
# constants beside a table (the table would win without a word)
WITH_INPUTS = [
    ("misspelt", {"M_motr": 1.0}, ("unknown key 'M_motr'", "M_motor, M_load, table",
                                   "did you mean 'M_motor'")),
    ("parameter", {"beta": 0.3}, ("'beta'", "[parameters]")),
    ("constants-and-table", {"M_motor": 1.0, "table": [[0.0, 1.0, 2.0]]},
     ("constants (M_motor, M_load) or a table, not both",)),
]


@pytest.mark.parametrize("given, words", [pytest.param(g, w, id=i) for i, g, w in WITH_INPUTS])
def test_with_inputs_refuses_a_keyword_it_cannot_take_by_name(given, words):
    with pytest.raises(SceneError) as raised:
        herringbone.scene_from_dict({}).with_inputs(**given)
    assert_one_clear_message(str(raised.value), ("with_inputs",) + words, "Scene.with_inputs")


# --- the FMU ------------------------------------------------------------------------------------

class Gear(Instance):
    """fmu_host.Instance that can also set String variables (solver_method)."""

    def set(self, **values):
        for name, value in values.items():
            if self.variables[name].type == "String":
                self.slave.setString([self.variables[name].valueReference], [value])
            else:
                super().set(**{name: value})


def test_the_table_covers_every_parameter_and_input_of_the_fmu(scene_fmu):
    """Every variable a master can set on the FMU has a row that goes through the FMU (but the
    Boolean contact_loss: FMI can only hand it true or false)."""
    import fmpy

    variables = fmpy.read_model_description(str(scene_fmu("reference"))).modelVariables
    settable = {v.name for v in variables
                if v.causality in ("parameter", "input") and v.type != "Boolean"}
    assert settable <= {case.name for case in CASES if "fmu" in case.routes}


def _fmu_messages(gear):
    errors = [text for status, text in gear.messages if status == ERROR]
    fatal = [text for status, text in gear.messages if status == FATAL]
    return errors, fatal


def _discarded_with_one_message(gear, case):
    with pytest.raises(FMICallException) as error:
        gear.step(1e-4)
    assert error.value.status == DISCARD, f"doStep returned status {error.value.status}"
    errors, fatal = _fmu_messages(gear)
    assert not fatal, fatal
    assert errors, f"no error-status message; the log: {gear.messages}"
    assert len(set(errors)) == 1, f"more than one message: {sorted(set(errors))}"
    assert_one_clear_message(errors[0], case.words, "FMU log")
    with pytest.raises(FMICallException):  # it stays stopped
        gear.step(1e-4)


@pytest.mark.parametrize("case", _cases("fmu"))
def test_fmu_start_value_is_discarded_with_one_message(scene_fmu, case):
    gear = Gear(scene_fmu("reference"), {case.name: case.value})
    try:
        _discarded_with_one_message(gear, case)
    finally:
        gear.free()


@pytest.mark.parametrize("case", [pytest.param(case, id=case.id) for case in CASES
                                  if "fmu" in case.routes and case.kind == "input"])
def test_fmu_input_set_mid_run_is_discarded_with_one_message(scene_fmu, case):
    gear = Gear(scene_fmu("reference"))
    try:
        for _ in range(3):
            gear.step(1e-4)
        assert not _fmu_messages(gear)[0]
        gear.set(**{case.name: case.value})
        _discarded_with_one_message(gear, case)
    finally:
        gear.free()


# FMI calls a master may get wrong, after initialization (each through the FMU, in this
# process): (id, the call on a Gear, the words its one message must contain). pythonfmu has no
# fmi2Error to answer with, so each is refused with a message and answered fmi2OK, and the
# instance steps on as if the call had not been made (tests/fmu/test_fmi_contract.py checks the
# values such calls return).
FMI_CALL_CASES = [
    ("set-an-output", lambda g: g.slave.setReal([g.variables["F_mesh"].valueReference], [5.0]),
     ("F_mesh", "output", "cannot be set")),
    ("set-a-fixed-parameter-after-initialization",
     lambda g: g.slave.setReal([g.variables["m_pinion"].valueReference], [2.0]),
     ("m_pinion", "fixed parameter", "before exitInitializationMode")),
    ("read-an-integer-as-real",
     lambda g: g.slave.getReal([g.variables["n_contacts"].valueReference]),
     ("n_contacts", "fmi2GetInteger")),
    ("read-a-real-as-integer",
     lambda g: g.slave.getInteger([g.variables["F_mesh"].valueReference]),
     ("F_mesh", "fmi2GetReal")),
    ("read-an-unknown-value-reference", lambda g: g.slave.getReal([100_000]),
     ("value reference 100000",)),
    ("set-a-local", lambda g: g.slave.setReal([g.variables["internal_steps"].valueReference],
                                              [1.0]),
     ("internal_steps",)),
]


@pytest.mark.parametrize("call, words", [pytest.param(call, words, id=case_id)
                                         for case_id, call, words in FMI_CALL_CASES])
def test_fmi_call_a_master_gets_wrong_is_refused_with_one_message(scene_fmu, call, words):
    gear = Gear(scene_fmu("reference"))
    try:
        gear.step(1e-4)
        call(gear)
        errors, fatal = _fmu_messages(gear)
        assert not fatal, fatal
        assert len(errors) == 1, f"not one message: {errors}"
        assert_one_clear_message(errors[0], words, "FMU log")
        gear.step(1e-4)  # and the instance goes on
    finally:
        gear.free()


def test_fmpy_simulate_stops_at_a_nan_input_with_the_message(scene_fmu):
    """The same through fmpy's own master loop: the run ends at the step that sees the NaN."""
    import fmpy

    received = []
    times = np.array([0.0, 5e-4, 1e-3])
    table = np.array([(t, 500.0, 1800.0 if t < 5e-4 else NAN) for t in times],
                     dtype=[("time", float), ("M_motor", float), ("M_load", float)])
    result = fmpy.simulate_fmu(str(scene_fmu("reference")), stop_time=1e-3, output_interval=1e-4,
                               input=table, debug_logging=True,
                               logger=lambda *args: received.append(args[-1].decode()))
    assert result["time"][-1] < 1e-3
    assert np.all(np.isfinite(result["F_mesh"]))
    assert any("M_load" in m and "finite" in m for m in received), received


# --- the command line ---------------------------------------------------------------------------

def _command(which, path, tmp_path):
    if which == "run":
        return [str(Path(sys.executable).parent / "herringbone"), "run", str(path),
                "--stop-time", "1e-3", "-o", str(tmp_path / "out.csv")]
    if which == "info":
        return [str(Path(sys.executable).parent / "herringbone"), "info", str(path)]
    return [sys.executable, str(ROOT / "build_fmu.py"), str(path), "-o", str(tmp_path / "x.fmu")]


@pytest.mark.parametrize("which, case", [
    pytest.param(which, case, id=f"{which}-{case.id}")
    for case in CASES if "cli" in case.routes for which in case.commands])
def test_command_line_exits_2_with_one_line(which, case, tmp_path):
    if case.value is None:
        path = tmp_path / "missing.toml"
    else:
        path = tmp_path / "bad.toml"
        (path.write_bytes if isinstance(case.value, bytes) else path.write_text)(case.value)
    run = subprocess.run(_command(which, path, tmp_path), capture_output=True, text=True,
                         cwd=tmp_path, timeout=120)
    assert run.returncode == 2, f"exit code {run.returncode}; stderr: {run.stderr}"
    assert run.stdout == ""
    assert_one_clear_message(run.stderr, case.words + (str(path),), f"{which} stderr")
    assert not (tmp_path / "x.fmu").exists()


# --- run arguments through the API and the command line ----------------------------------------

class Untouchable:
    """A stepper for simulate_with that fails the test if the run begins."""

    def __getattr__(self, name):
        raise AssertionError(f"the run began (stepper.{name}) before its arguments were checked")


def _refuse_work(*args, **kwargs):
    raise AssertionError("the model was built before the arguments were checked")


@pytest.fixture
def no_work(monkeypatch):
    """Building a model is the first work of every run and chart: make it fail the test."""
    import importlib

    for module in ("integrate.reference", "integrate.compiled_stepper", "analysis.stability"):
        monkeypatch.setattr(importlib.import_module(f"herringbone.{module}"), "GearTrainModel",
                            _refuse_work)


def _api_function(name):
    from herringbone.analysis.continuation import continue_in_parameter
    from herringbone.analysis.stability import monodromy, stability_chart
    from herringbone.analysis.sweep_point import Protocol
    from herringbone.integrate.contract import simulate_with

    return {"simulate": herringbone.simulate,
            "reference_simulate": herringbone.reference_simulate,
            "simulate_with": lambda scene, **kwargs: simulate_with(Untouchable(), scene, **kwargs),
            "stability_chart": stability_chart, "monodromy": monodromy,
            "Protocol": lambda scene, **kwargs: Protocol(**kwargs),
            "sweep": lambda scene, **kwargs: herringbone.sweep(scene, workers=0, progress=False,
                                                               **kwargs),
            "continue_in_parameter": continue_in_parameter}[name]


@pytest.mark.parametrize("function, case", [
    pytest.param(function, case, id=f"{function}-{case.id}")
    for case in CASES if "call" in case.routes for function in case.commands])
def test_api_refuses_a_bad_argument_before_any_work(function, case, reference_scene, no_work):
    arguments = dict(case.value)
    scene = arguments.pop("scene", reference_scene)
    expected = SceneError if case.name == "scene" else ValueError
    with pytest.raises(expected) as error:
        _api_function(function)(scene, **arguments)
    assert_one_clear_message(str(error.value), case.words, function)


def test_the_api_accepts_the_bounds_of_its_ranges(reference_scene):
    """The allowed ranges are closed where they say so: a run at each bound goes through."""
    span = dict(stop_time=2e-5, output_interval=2e-5)
    for tolerance in (1e-12, 1e-2):
        assert len(herringbone.simulate(reference_scene, **span, tolerance=tolerance)["time"]) == 2
    result = herringbone.reference_simulate(reference_scene, **span, tolerance=1e-5)
    assert np.isfinite(result["F_mesh"]).all()


ARGV_CASES = [case for case in CASES if "argv" in case.routes]


def _argv(case, folder):
    a_file = folder / "plain.txt"
    a_file.write_text("not a folder\n")
    (folder / "results").write_text("a file where the default output folder would be\n")
    values = [v.format(scene=MODELS / "reference.toml", file=a_file, tmp=folder)
              for v in case.value]
    if case.commands == ("build_fmu",):
        return [sys.executable, str(ROOT / "build_fmu.py"), *values]
    return [str(Path(sys.executable).parent / "herringbone"), *values]


def typed_command(case):
    """The command as the user typed it, which the message must begin with: `herringbone` for
    a command line it cannot read a command from, `herringbone COMMAND` for the rest,
    `herringbone benchmark NAME` for a benchmark's own options (the default benchmark's where
    none is named), `build_fmu` for build_fmu.py."""
    from herringbone.cli import benchmark, parser

    if case.commands == ("build_fmu",):
        return "build_fmu: "
    command, rest = (case.value[0], case.value[1:]) if case.value else ("", ())
    if command not in parser()[1]:
        return "herringbone: "
    unknown = rest and not rest[0].startswith("-") and rest[0] not in benchmark.SCRIPTS
    if command == benchmark.NAME and not unknown:
        name = rest[0] if rest and rest[0] in benchmark.SCRIPTS else benchmark.DEFAULT
        return f"herringbone benchmark {name}: "
    return f"herringbone {command}: "


@pytest.fixture(scope="module")
def command_line_runs(tmp_path_factory):
    """Every argv row run at once, one process per core (a process start costs about a
    second): {case id: (finished process, the folder it ran in)}."""
    import os
    from concurrent.futures import ThreadPoolExecutor

    def run(case):
        folder = tmp_path_factory.mktemp(case.id)
        return case.id, (subprocess.run(_argv(case, folder), capture_output=True, text=True,
                                        cwd=folder, timeout=60), folder)

    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        return dict(pool.map(run, ARGV_CASES))


@pytest.mark.parametrize("case", [pytest.param(case, id=case.id) for case in ARGV_CASES])
def test_a_bad_command_line_argument_exits_2_with_one_line(case, command_line_runs):
    run, folder = command_line_runs[case.id]
    assert run.returncode == 2, f"exit code {run.returncode}; stderr: {run.stderr}"
    assert run.stdout == ""
    assert_one_clear_message(run.stderr, case.words, "stderr")
    assert run.stderr.startswith(typed_command(case)), run.stderr  # the command as typed
    assert sorted(p.name for p in folder.iterdir()) == ["plain.txt", "results"]  # nothing written


def test_the_table_covers_every_option_and_run_argument():
    """A checked option or API argument added without a row here fails this test."""
    from herringbone import arguments
    from herringbone.cli import parser

    _, commands = parser()
    options = {action.option_strings[-1] for parser in commands.values()
               for action in parser._actions if action.option_strings and action.type}
    assert options <= {case.name for case in CASES if "argv" in case.routes}
    names = {value.name for value in vars(arguments).values()
             if isinstance(value, arguments.Argument)}
    # COUNT: by the --speeds rows; the FMU's solver settings: by the "solver" rows; the sweep's
    # protocol: by the "call" rows of Protocol
    assert names - {"COUNT"} <= {case.name for case in CASES}
