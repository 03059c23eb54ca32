"""Co-simulate the drive train of `drivetrain.ssp` with libcosim and print its operating point.

    python -m herringbone.examples.cosimulate_drivetrain [SSP] [--stop-time T] [--step H]
    python examples/cosimulate_drivetrain.py [SSP] ...          (in a checkout)

Without SSP it first builds `dist/drivetrain.ssp` from `--scene` (`herringbone build-fmu --ssp`,
in a separate process).
libcosim (libcosimpy) loads the whole system, connections and parameter set included, in one
call (`CosimExecution.from_ssp_file`) and runs it at the SSD's fixed step (or `--step`) to its
stop time (or `--stop-time`), logging warnings and errors only.  The speeds and torques are
observed by name (value references from libcosim's variable list), averaged over the last
whole mesh periods, and printed beside the intersection of the motor's Kloss curve and the
fan curve through the gear ratio, computed from the parameters the SSP sets (the FMUs' start
values where it sets none).  The step must fit a whole number of times in the stop time and
at least once in the averaging window (five mesh periods at that intersection), which must
fit twice in the run.  A run whose means lie far from the intersection has diverged (a step
too long for the explicit coupling of motor and gear): it is said so, not tabled.  Exit
code 0; 1 if the co-simulation stopped early or diverged; 2 for a bad argument, an SSP that
cannot be read or loaded, or libcosimpy missing.  Needs the Python that runs it to have the
FMUs' dependencies and libcosimpy (`pip install libcosimpy`, or `pip install ".[cosim]"` in
herringbone's source): checked before anything is built, and said in one line where missing.
"""
import argparse
import importlib.util
import io
import math
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

if __package__:  # python -m herringbone.examples.cosimulate_drivetrain
    from .drivetrain_operating_point import operating_point
else:  # python examples/cosimulate_drivetrain.py: this folder is on sys.path
    from drivetrain_operating_point import operating_point

SIGNALS = {"w_motor": ("gear", "rad/s"), "w_load": ("gear", "rad/s"),
           "M_motor": ("motor", "N.m"), "M_load": ("fan", "N.m")}
WINDOW_MESH_PERIODS = 5  # the mesh ripples the speeds at z_pinion·w/2π: average it out
# A settled run lies within 1e-5 of the intersection (docs/ssp.md); a mean more than 50 % off
# it, or of the wrong sign, comes from a run that did not settle there.
DIVERGED = 0.5
# what runs the SSP, and the extra of herringbone that brings it
COSIMULATOR, COSIM_EXTRA = "libcosimpy", "cosim"
NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
      "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}


def missing_cosimulator():
    """What to say where libcosimpy is not installed (herringbone.optional's words for a
    missing extra, which this process may not import: the gear FMU imports its own copy of
    herringbone), or None; imports nothing."""
    if importlib.util.find_spec(COSIMULATOR) is not None:
        return None
    return (f"the co-simulation needs {COSIMULATOR}, which is not installed: pip install "
            f"{COSIMULATOR} (or every dependency of the {COSIM_EXTRA!r} extra: pip install "
            f"\".[{COSIM_EXTRA}]\" in herringbone's source folder)")


def read_ssp(path):
    """The SSD's experiment (stop time, base step) and each component's parameters: the FMU's
    numeric start values, overridden by the SSD's inline parameter set (parameter_value)."""
    with zipfile.ZipFile(path) as archive:
        root = ET.fromstring(archive.read("SystemStructure.ssd"))
        parameters = {}
        for component in root.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
            values = start_values(archive.read(component.get("source")))
            for parameter in component.iterfind(".//ssv:Parameter", NS):
                values[parameter.get("name")] = parameter_value(parameter)
            parameters[component.get("name")] = values
    experiment = root.find("ssd:DefaultExperiment", NS)
    step = experiment.find(".//osp:FixedStepAlgorithm", NS)
    return {"stop_time": float(experiment.get("stopTime")),
            "step": float(step.get("baseStepSize")) if step is not None else None,
            "parameters": parameters}


def parameter_value(parameter):
    """An ssv:Parameter's value: a Real's or an Integer's as a float (z_wheel is one), a
    Boolean's as a bool, a String's as it is.  KeyError for a parameter of none of these
    types, ValueError for a number that is none."""
    for kind, convert in (("Real", float), ("Integer", float),
                          ("Boolean", lambda text: text.strip() in ("true", "1")),
                          ("String", str)):
        node = parameter.find(f"ssv:{kind}", NS)
        if node is not None:
            return convert(node.get("value"))
    raise KeyError(f"parameter {parameter.get('name')} has no ssv:Real, ssv:Integer, "
                   "ssv:Boolean or ssv:String")


def start_values(fmu_bytes):
    """An FMU's numeric start values by name."""
    from fmpy import read_model_description

    description = read_model_description(io.BytesIO(fmu_bytes))
    return {v.name: float(v.start) for v in description.modelVariables
            if v.start is not None and v.type in ("Real", "Integer")}


def cosimulate(ssp, stop_time, step):
    """Run the SSP in libcosim; every signal after every step, by name, and the wall time."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)  # libcosim's default prints every FMU message
    step_ns, steps = round(step * 1e9), round(stop_time / step)  # libcosim counts integer ns
    started = time.perf_counter()
    try:
        execution = CosimExecution.from_ssp_file(str(ssp), step_size=step_ns)
    except AssertionError:  # libcosimpy's answer to a NULL execution; libcosim logged why
        print(f"{ssp}: libcosim could not load it (see its message above)", file=sys.stderr)
        sys.exit(2)
    index = {info.name.decode(): info.index for info in execution.slave_infos()}
    refs = {name: {v.name.decode(): v.reference for v in execution.slave_variables(i)}
            for name, i in index.items()}
    series = CosimObserver.create_time_series(buffer_size=steps + 10)
    execution.add_observer(observer=series)
    for signal, (component, _) in SIGNALS.items():
        series.start_time_series(index[component], refs[component][signal], CosimVariableType.REAL)
    completed = execution.simulate_until(target_time=steps * step_ns)
    samples = {}
    for signal, (component, _) in SIGNALS.items():
        # step 0 is the initial sample: from step 1, one sample after every step
        _, _, values = series.time_series_real_samples(index[component], refs[component][signal],
                                                       from_step=1, sample_count=steps)
        samples[signal] = list(values)
    return completed, execution.status().current_time / 1e9, samples, time.perf_counter() - started


def window_means(samples, size):
    """Means of each signal over the last `size` samples and over the `size` before them."""
    last = {s: sum(v[-size:]) / size for s, v in samples.items()}
    before = {s: sum(v[-2 * size:-size]) / size for s, v in samples.items()}
    return last, before


def argument_problem(stop_time, step, window):
    """Why the run cannot give two averaging windows of `window` s (one line), or None."""
    steps = stop_time / step
    if abs(steps - round(steps)) > 1e-9 * steps:
        return (f"--stop-time {stop_time:g} s is {steps:.4g} steps of {step:g} s; allowed: a "
                "whole number of steps")
    if abs(step * 1e9 - round(step * 1e9)) > 1e-6 * step * 1e9:  # libcosim counts integer ns
        return f"--step {step:g} s; allowed: a whole number of nanoseconds"
    if step > window:
        return (f"--step {step:g} s; allowed: at most {window:.4g} s, the averaging window "
                f"({WINDOW_MESH_PERIODS} mesh periods at the analytic operating point)")
    two_windows = 2 * round(window / step) * step
    if stop_time < two_windows:
        return (f"--stop-time {stop_time:g} s; allowed: at least two averaging windows, "
                f"{two_windows:.4g} s at --step {step:g} s")
    return None


def diverged(last, expected):
    """The first signal whose mean is off the analytic point by more than DIVERGED, or None."""
    for signal in SIGNALS:
        if not abs(last[signal] / expected[signal] - 1) <= DIVERGED:  # NaN too
            return signal
    return None


def report(ssp, experiment, expected, completed, end_time, samples, wall, step):
    """Print the run and the operating point table; returns the exit code."""
    print(f"{ssp}: libcosim, {end_time:g} s simulated at {step:g} s steps in {wall:.1f} s"
          + ("" if completed else f" -- STOPPED EARLY (asked for {experiment['stop_time']:g} s)"))
    size = round(WINDOW_MESH_PERIODS * expected["mesh_period"] / step)
    if len(samples["w_motor"]) < 2 * size:
        print(f"too few samples for two windows of {size}: give a longer --stop-time")
        return 1
    last, before = window_means(samples, size)
    signal = diverged(last, expected)
    if signal is not None:
        unit = SIGNALS[signal][1]
        print(f"{ssp}: the co-simulation diverged: {signal} averages {last[signal]:g} {unit} "
              f"over the last window, {expected[signal]:g} {unit} at the operating point; give "
              f"a shorter --step (this one: {step:g} s)", file=sys.stderr)
        return 1
    print(f"operating point: means over the last {WINDOW_MESH_PERIODS} mesh periods "
          f"({size} steps) and the {WINDOW_MESH_PERIODS} before them; analytic: Kloss curve "
          f"= fan curve through the gear ratio {expected['ratio']:g}")
    print(f"{'signal':8} {'unit':6} {'last window':>14} {'window before':>14} {'analytic':>14} "
          f"{'rel. diff':>10}")
    for signal, (_, unit) in SIGNALS.items():
        print(f"{signal:8} {unit:6} {last[signal]:14.6f} {before[signal]:14.6f} "
              f"{expected[signal]:14.6f} {last[signal] / expected[signal] - 1:+10.2e}")
    return 0 if completed else 1


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ssp", nargs="?", type=Path,
                        help="the .ssp to run (default: build dist/drivetrain.ssp first)")
    parser.add_argument("--scene",
                        help="scene of the gear FMU when building, without SSP: a file or a "
                             "shipped scene's name (default: reference)")
    parser.add_argument("--stop-time", type=float, help="s (default: the SSD's stopTime)")
    parser.add_argument("--step", type=float, help="s (default: the SSD's baseStepSize)")
    args = parser.parse_args(argv)
    for name in ("stop_time", "step"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value > 0):
            parser.error(f"--{name.replace('_', '-')} {value}: allowed: finite and > 0")
    if args.ssp is not None and args.scene is not None:
        parser.error(f"--scene {args.scene}: the SSP {args.ssp} carries its own gear FMU; "
                     "allowed: --scene without SSP (it builds dist/drivetrain.ssp)")
    missing = missing_cosimulator()
    if missing is not None:  # before a build that could not be used
        parser.exit(2, f"{parser.prog}: {missing}\n")
    ssp = args.ssp
    if ssp is None:
        ssp = Path("dist") / "drivetrain.ssp"
        replacing = " (replacing the one there)" if ssp.exists() else ""
        print(f"{parser.prog}: building {ssp} from the scene {args.scene or 'reference'}"
              f"{replacing}", file=sys.stderr, flush=True)
        # another process: this one must not import herringbone (the gear FMU imports its own)
        subprocess.run([sys.executable, "-m", "herringbone.cli", "build-fmu", "--ssp", str(ssp),
                        str(args.scene or "reference")], check=True)
    try:
        experiment = read_ssp(ssp)
    except (OSError, KeyError, ValueError, zipfile.BadZipFile, ET.ParseError) as error:
        parser.exit(2, f"{parser.prog}: {ssp} is no readable drive-train SSP: {error}\n")
    step = args.step or experiment["step"]
    stop_time = args.stop_time or experiment["stop_time"]
    if step is None or step > stop_time:
        parser.error(f"step {step} s, stop time {stop_time} s: allowed: 0 < step <= stop time "
                     "(give --step where the SSD has no fixed-step annotation)")
    p = experiment["parameters"]
    try:
        expected = operating_point(p["motor"]["M_breakdown"], p["motor"]["s_breakdown"],
                                   p["motor"]["w_sync"], p["fan"]["k_fan"],
                                   p["gear"]["z_pinion"], p["gear"]["z_wheel"])
    except (ValueError, ZeroDivisionError) as error:  # an SSP not made by herringbone's builder
        parser.error(f"{ssp}: its parameters give no operating point: {error}")
    problem = argument_problem(stop_time, step, WINDOW_MESH_PERIODS * expected["mesh_period"])
    if problem is not None:
        parser.error(problem)
    completed, end_time, samples, wall = cosimulate(ssp, stop_time, step)
    return report(ssp, {**experiment, "stop_time": stop_time}, expected, completed, end_time,
                  samples, wall, step)


if __name__ == "__main__":
    sys.exit(main())
