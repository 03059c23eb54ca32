"""What the benchmarks share: the scene's FMU, the cached reference, timed FMU and scipy runs,
the error measure and the machine record.

Timed FMU runs happen in a fresh Python process each (`python common.py worker SPEC.json`):
  - the start-up it measures (instantiate + initialize) is what a new host process pays once
    compiled code is cached on disk, not a re-instantiation in a warm interpreter;
  - the FMU's Python code is never mixed with the copy of `herringbone` this process imported
    for the reference (pythonfmu runs the slave inside the host's interpreter);
  - a crash of the FMU ends the worker, not the benchmark.
The worker imports fmpy and numpy only; everything from `herringbone` is imported lazily.
"""
from __future__ import annotations

import bisect
import csv
import datetime
import glob
import hashlib
import json
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from importlib import metadata
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
DEFAULT_OUTPUT_DIR = ROOT / "results" / "benchmark"
# What an FMU is built from: a change to any of these gives a new FMU (and a new file name).
FMU_SOURCES = sorted((ROOT / "fmu_src" / "herringbone").rglob("*.py"))  # slave, builder included
ACCURACY_GOAL = 1e-6  # error relative to the static mesh force (issue 4)
SPEED_GOAL = 0.1  # wall seconds per simulated second (issue 4)
STARTUP_GOAL = 1.0  # seconds for instantiate + initialize, compiled code cached (issue 4)
FORCE_OUTPUTS = ("F_mesh", "F_brg_pinion_left", "F_brg_pinion_right", "F_brg_wheel_left",
                 "F_brg_wheel_right")


def file_hash(*paths) -> str:
    digest = hashlib.sha256()
    for path in paths:
        digest.update(Path(path).read_bytes())
    return digest.hexdigest()[:12]


SCENES_ALLOWED = "scene names (models/NAME.toml), scene files or globs"


def scene_paths(patterns, parser, option="--scenes") -> list[Path]:
    """Scene files from names ("reference"), paths, or globs ("models/*.toml"); one that names
    no file stops the script through `parser` (its one-line error, exit code 2: before any
    run), naming `option` and the pattern, with the closest shipped name."""
    found = []
    for pattern in patterns:
        if any(c in pattern for c in "*?["):
            # relative to the working directory, else to the repository
            matches = [Path(m) for m in (sorted(glob.glob(pattern))
                                         or sorted(glob.glob(str(ROOT / pattern))))]
            if not matches:
                parser.error(f"{option} {pattern}: no scene file matches it; allowed: "
                             f"{SCENES_ALLOWED}")
        elif Path(pattern).suffix or Path(pattern).exists():
            matches = [Path(pattern)]
        else:
            matches = [MODELS / f"{pattern}.toml"]
        for match in matches:
            if not match.is_file():
                from herringbone.suggest import did_you_mean

                names = sorted(path.stem for path in MODELS.glob("*.toml"))
                parser.error(f"{option} {pattern}: no scene file {match}; allowed: "
                             f"{SCENES_ALLOWED}{did_you_mean(pattern, names)}")
            if match.resolve() not in found:
                found.append(match.resolve())
    return found


def force_outputs(scene) -> list[str]:
    """The forces the error is judged on: F_mesh and each bearing reaction the scene has."""
    from herringbone.model.assembly import output_names

    return [name for name in FORCE_OUTPUTS if name in output_names(scene)]


def force_scale(scene) -> float:
    from herringbone.model.assembly import GearTrainModel

    return GearTrainModel(scene).force_scale()


def force_error(times, values, reference, scale) -> float:
    """max over the forces of max |x − x_ref| at the common times, over the force scale. The
    reference is sampled at the same or an integer fraction of the interval."""
    if len(times) < 2:
        return math.nan
    ratio = round((times[1] - times[0]) / (reference["time"][1] - reference["time"][0]))
    ref_times = reference["time"][::ratio][:len(times)]
    count = min(len(times), len(ref_times))
    if not np.allclose(times[:count], ref_times[:count], rtol=0,
                       atol=1e-6 * (times[1] - times[0])):
        raise ValueError("benchmark: the run and the reference are not sampled at the same times")
    return max(float(np.max(np.abs(np.asarray(values[name][:count])
                                   - reference[name][::ratio][:count]))) for name in values) / scale


# --- the reference, cached ------------------------------------------------------------------

_REFERENCE_SOURCES = []


def reference_source_hash() -> str:
    """The files of the herringbone modules the reference runs on (cache key): those a fresh
    interpreter loads for herringbone.integrate.reference, whatever else this process has
    imported."""
    if not _REFERENCE_SOURCES:
        listing = subprocess.run(
            [sys.executable, "-c", "import sys, herringbone.integrate.reference\n"
             "print('\\n'.join(m.__file__ for n, m in list(sys.modules.items())\n"
             "      if n.startswith('herringbone') and getattr(m, '__file__', None)))"],
            capture_output=True, text=True, check=True)
        _REFERENCE_SOURCES.extend(sorted(set(listing.stdout.split())))
    return file_hash(*_REFERENCE_SOURCES)


def cached_reference(scene_path, stop_time, output_interval, tolerance, cache_dir=None,
                     log=print) -> dict:
    """reference_simulate of a scene file over [0, stop_time] every output_interval, from the
    disk cache if an earlier run covered it (same scene file, model source and tolerance; a span
    at least as long; an interval dividing this one); {"time": …, output: …, "wall": seconds
    per simulated second it took}."""
    import herringbone

    cache_dir = Path(cache_dir or DEFAULT_OUTPUT_DIR / "reference_cache")
    scene_path = Path(scene_path)
    key = f"{scene_path.stem}-{file_hash(scene_path)}-{reference_source_hash()}-tol{tolerance:g}"
    for candidate in sorted(cache_dir.glob(f"{key}_dt*_T*.npz")):
        _, interval, span = candidate.stem.rsplit("_", 2)
        interval, span = float(interval[2:]), float(span[1:])
        ratio = output_interval / interval
        if span >= stop_time * (1 - 1e-12) and abs(ratio - round(ratio)) < 1e-9 * ratio:
            with np.load(candidate) as data:
                results = {name: data[name] for name in data.files}
            step = round(ratio)
            count = int(round(stop_time / output_interval)) + 1
            return {name: (values[::step][:count] if values.ndim else values)
                    for name, values in results.items()}
    scene = herringbone.load_scene(scene_path)
    log(f"  reference: {scene.name}, {stop_time:g} s every {output_interval:g} s at tolerance "
        f"{tolerance:g} (once; cached in {_relative(cache_dir)}) ...")
    started = time.perf_counter()
    results = herringbone.reference_simulate(scene, stop_time=stop_time,
                                             output_interval=output_interval, tolerance=tolerance)
    wall = (time.perf_counter() - started) / stop_time
    log(f"  reference: done in {wall * stop_time:.1f} s ({wall:.1f} s per simulated second)")
    results["wall"] = np.array(wall)
    cache_dir.mkdir(parents=True, exist_ok=True)
    target = cache_dir / f"{key}_dt{output_interval:.12g}_T{stop_time:.12g}.npz"
    with tempfile.NamedTemporaryFile(dir=cache_dir, suffix=".npz", delete=False) as staging:
        np.savez(staging, **results)
    os.chmod(staging.name, 0o644)
    os.replace(staging.name, target)
    return results


# --- the FMU --------------------------------------------------------------------------------

class BuildError(RuntimeError):
    """The FMU of a scene could not be built from the current sources."""


def scene_fmu(scene_path, log=print) -> Path:
    """The scene's FMU, built from the current sources once (in results/benchmark/fmus/, like
    the references whatever the output directory), and extracted: returns the extracted
    directory (extraction is never timed; numba's cache, if the FMU uses one, lands there and
    is reused by every later run)."""
    import zipfile

    from herringbone.fmu import builder

    scene_path = Path(scene_path)
    fmu_dir = DEFAULT_OUTPUT_DIR / "fmus"
    name = f"{scene_path.stem}-{file_hash(scene_path, *FMU_SOURCES)}"
    unzipped = fmu_dir / name
    if not (unzipped / "modelDescription.xml").is_file():
        built_before = re.compile(re.escape(scene_path.stem) + r"-[0-9a-f]{12}(\.fmu)?")
        for outdated in fmu_dir.glob(f"{scene_path.stem}-*"):  # from older sources
            if built_before.fullmatch(outdated.name):
                shutil.rmtree(outdated) if outdated.is_dir() else outdated.unlink()
        log(f"  building the FMU of {scene_path.name} ...")
        try:
            fmu = builder.build_gear_fmu(scene=scene_path, output=fmu_dir / f"{name}.fmu")
        except RuntimeError as error:  # say why in one line; the caller goes on without it
            raise BuildError(f"{scene_path.name}: FMU build failed: "
                             f"{str(error).strip().splitlines()[-1]}") from None
        with zipfile.ZipFile(fmu) as archive:
            archive.extractall(unzipped)
    return unzipped


def fmu_variables(fmu_dir) -> dict:
    """Name → fmpy ScalarVariable (.type, .start, …) of the FMU's variables: solver_method and
    internal_steps are used only where the FMU declares them."""
    from fmpy import read_model_description

    return {v.name: v for v in read_model_description(str(fmu_dir)).modelVariables}


def input_schedule(scene) -> dict:
    inputs = scene.inputs
    return {"times": list(inputs.times), "M_motor": list(inputs.M_motor),
            "M_load": list(inputs.M_load)}


def run_fmu(fmu_dir, inputs, legs, record, start_values=None, budget=math.inf,
            timeout=None) -> dict:
    """Run the extracted FMU in a fresh process. legs: [(end time, communication step,
    record outputs?)], run one after the other from t = 0; inputs: {"times", "M_motor",
    "M_load"} (each row held until the next; set at every communication point); record: the
    outputs to read after every step of a recording leg. The run stops early (status "over
    budget") once its stepping has taken `budget` seconds of wall time.

    Returns {"time": …, name: …, "startup": s, "wall": s (stepping only), "reached": t,
    "internal_steps": n or None, "status": "ok" | "over budget" | "failed: …", "model_from":
    where the FMU's herringbone package was imported from}."""
    with tempfile.TemporaryDirectory(prefix="fmu_bench_") as tmp:
        spec = {"fmu_dir": str(fmu_dir), "inputs": inputs, "legs": [list(leg) for leg in legs],
                "record": list(record), "start_values": start_values or {},
                "budget": budget if math.isfinite(budget) else None,
                "output": str(Path(tmp) / "result.npz")}
        spec_path = Path(tmp) / "spec.json"
        spec_path.write_text(json.dumps(spec))
        run = subprocess.run([sys.executable, str(Path(__file__).resolve()), "worker",
                              str(spec_path)], capture_output=True, text=True, timeout=timeout)
        if not Path(spec["output"]).is_file():
            detail = (run.stderr.strip().splitlines() or [f"exit code {run.returncode}"])[-1]
            return {"status": f"failed: worker died ({detail})", "time": np.zeros(0),
                    "startup": math.nan, "wall": math.nan, "reached": 0.0,
                    "internal_steps": None, "model_from": ""}
        with np.load(spec["output"]) as data:
            result = {name: data[name] for name in data.files if name != "meta"}
            result.update(json.loads(str(data["meta"])))
    return result


def _worker(spec_path) -> None:
    """The timed host loop (fmpy's FMU2Slave, its raw FMI calls on preallocated arrays, so the
    host adds as little as a compiled master would)."""
    import ctypes

    from fmpy import read_model_description
    from fmpy.fmi2 import (
        FMU2Slave,
        calloc,
        fmi2CallbackAllocateMemoryTYPE,
        fmi2CallbackFreeMemoryTYPE,
        fmi2CallbackFunctions,
        fmi2CallbackLoggerTYPE,
        fmi2True,
        free,
    )
    from fmpy.logging import addLoggerProxy

    spec = json.loads(Path(spec_path).read_text())
    description = read_model_description(spec["fmu_dir"])
    variables = {v.name: v for v in description.modelVariables}
    messages = []

    def on_log(environment, instance, status, category, message):
        messages.append(message.decode(errors="replace"))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(on_log)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    addLoggerProxy(ctypes.byref(callbacks))
    slave = FMU2Slave(guid=description.guid, unzipDirectory=spec["fmu_dir"],
                      modelIdentifier=description.coSimulation.modelIdentifier,
                      instanceName="gear")
    inputs = spec["inputs"]

    def torques_at(t, step):
        # the row in force at t (a change time on the grid counts, whatever the rounding)
        row = max(bisect.bisect_right(inputs["times"], t + 1e-9 * step) - 1, 0)
        return inputs["M_motor"][row], inputs["M_load"][row]

    input_refs = (ctypes.c_uint * 2)(variables["M_motor"].valueReference,
                                     variables["M_load"].valueReference)
    input_values = (ctypes.c_double * 2)()
    record = spec["record"]
    output_refs = (ctypes.c_uint * len(record))(*(variables[n].valueReference for n in record))
    output_values = (ctypes.c_double * len(record))()
    samples, sample_times = [], []
    meta = {"status": "ok", "startup": math.nan, "wall": math.nan, "reached": 0.0,
            "internal_steps": None}
    time_now = 0.0
    stepping_started = None
    try:
        started = time.perf_counter()
        slave.instantiate(callbacks=callbacks, loggingOn=True)
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        for name, value in spec["start_values"].items():
            setter = {"Real": slave.setReal, "Integer": slave.setInteger,
                      "Boolean": slave.setBoolean, "String": slave.setString}
            setter[variables[name].type]([variables[name].valueReference],
                                         [value])
        input_values[0], input_values[1] = torques_at(0.0, 1.0)
        slave.fmi2SetReal(slave.component, input_refs, 2, input_values)
        slave.exitInitializationMode()
        meta["startup"] = time.perf_counter() - started
        model = sys.modules.get("herringbone")
        meta["model_from"] = str(Path(model.__file__).parent) if model else ""
        if record:
            slave.fmi2GetReal(slave.component, output_refs, len(record), output_values)
            samples.append(list(output_values))
            sample_times.append(0.0)

        budget = spec["budget"] or math.inf
        started = stepping_started = time.perf_counter()
        leg_start = 0.0
        for end, step, recording in spec["legs"]:
            if end <= leg_start:
                continue
            count = max(int(math.ceil((end - leg_start) / step * (1 - 1e-12))), 1)
            for k in range(count):
                t_next = end if k == count - 1 else leg_start + (k + 1) * step
                input_values[0], input_values[1] = torques_at(time_now, step)
                slave.fmi2SetReal(slave.component, input_refs, 2, input_values)
                slave.fmi2DoStep(slave.component, time_now, t_next - time_now, fmi2True)
                time_now = t_next
                if recording and record:
                    slave.fmi2GetReal(slave.component, output_refs, len(record), output_values)
                    samples.append(list(output_values))
                    sample_times.append(time_now)
                if time.perf_counter() - started > budget:
                    meta["status"] = "over budget"
                    break
            if meta["status"] != "ok":
                break
            leg_start = end
        meta["wall"] = time.perf_counter() - started
        if "internal_steps" in variables:
            meta["internal_steps"] = slave.getInteger(
                [variables["internal_steps"].valueReference])[0]
        slave.terminate()
    except Exception as error:  # the FMU refused a call: report it with its own message
        meta["status"] = f"failed at t = {time_now:g} s: " + (
            messages[-1] if messages else str(error))
        if stepping_started is not None:
            meta["wall"] = time.perf_counter() - stepping_started
    meta["reached"] = time_now
    values = np.array(samples, dtype=float).reshape(len(samples), len(record))
    np.savez(spec["output"], time=np.array(sample_times), meta=json.dumps(meta),
             **{name: values[:, i] for i, name in enumerate(record)})


# --- scipy's solve_ivp on the same model, the same restarts ---------------------------------

class _OverBudget(Exception):
    pass


def run_scipy(scene, method, tolerance, stop_time, output_interval, record, budget=math.inf):
    """herringbone's ScipyStepper (a scipy OdeSolver restarted at every contact switch, as the
    reference) sampling its dense output every output_interval, through the package's one run
    loop (herringbone.integrate.contract.simulate_with): an offline run, which is scipy's
    cheapest way through (no restart per communication step). Same result layout as run_fmu;
    stops at the first sample past `budget` seconds of wall time."""
    from herringbone.integrate.contract import output_times, simulate_with
    from herringbone.integrate.stepping import ScipyStepper
    from herringbone.model.assembly import GearTrainModel

    started = time.perf_counter()
    stepper = ScipyStepper(GearTrainModel(scene), tolerance, method)
    startup = time.perf_counter() - started
    times = output_times(stop_time, output_interval)
    samples = {name: [] for name in record}
    result = {"status": "ok", "startup": startup, "internal_steps": None, "model_from": ""}

    def watch(t, outputs):
        for name in record:
            samples[name].append(outputs[name])
        if time.perf_counter() - started > budget:
            raise _OverBudget

    started = time.perf_counter()
    try:
        with np.errstate(over="ignore", invalid="ignore"):
            simulate_with(stepper, scene, stop_time, output_interval, on_sample=watch)
    except _OverBudget:
        result["status"] = "over budget"
    except Exception as error:
        result["status"] = f"failed: {error}"
    result["wall"] = time.perf_counter() - started
    count = min(len(samples[name]) for name in record)
    result["time"] = times[:count]
    result["reached"] = float(times[count - 1]) if count else 0.0
    result.update({name: np.array(samples[name][:count]) for name in record})
    return result


# --- reports --------------------------------------------------------------------------------

def machine_record(command) -> list[str]:
    """Markdown lines: when, where, with what, and how (the exact command)."""
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = ", ".join(f"{package} {_version(package)}" for package in
                         ("numpy", "scipy", "numba", "fmpy", "pythonfmu", "matplotlib"))
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    git = _git("rev-parse", "--short", "HEAD")
    if git and _git("status", "--porcelain"):
        git += " with uncommitted changes"
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    return [f"- date: {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}",
            f"- machine: {platform.platform()}; {cpu}; {os.cpu_count()} cores "
            f"({usable} usable); load average at start {load}",
            f"- Python {platform.python_version()}; {versions}",
            f"- source: {git or 'not a git checkout'}",
            f"- command: `{command}`"]


def _version(package):
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "not installed"


def _git(*arguments):
    try:
        return subprocess.run(["git", "-C", str(ROOT), *arguments], capture_output=True,
                              text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""


def write_csv(rows: list[dict], path) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    columns = list(dict.fromkeys(key for row in rows for key in row))
    with open(path, "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=columns)
        writer.writeheader()
        for row in rows:
            writer.writerow({key: (f"{value:.6g}" if isinstance(value, float) else value)
                             for key, value in row.items()})


def markdown_table(header: list[str], rows: list[list]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return lines


def number(value, digits=3) -> str:
    """A figure for a table: `digits` significant digits, '—' for none."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    return f"{value:.{digits}g}"


def _relative(path):
    try:
        return str(Path(path).resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def command_line(script, argv) -> str:
    return " ".join([f"python {_relative(script)}", *argv])


if __name__ == "__main__" and sys.argv[1:2] == ["worker"]:
    _worker(sys.argv[2])
