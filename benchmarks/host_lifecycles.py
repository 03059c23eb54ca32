"""Every lifecycle a host puts the gear FMU through, each in a fresh process, counted.

A host process that aborts at exit now and then (a crash after the results are written) is as
bad as one that aborts every time: nobody can put it in a nightly run. This script runs each
lifecycle below N times in fresh processes, `--parallel` at a time, and prints the count of
non-zero exits per case; tests/fmu/test_host_lifecycles.py runs a few of each on every push.

    python benchmarks/host_lifecycles.py --runs 200 [--plain-runs 1000] [--cases plain fatal …]

Each case is a small Python program (or, for `c_host`, the C host of tests/fmu/c_host) that checks
its own results and exits 0; a non-zero exit is a failure whether the results were right or
not. The FMUs are built once into a temporary folder (or `--fmu-dir`).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
C_HOST = ROOT / "tests" / "fmu" / "c_host"
STOP, STEP = 0.005, 1e-3

# Shared prologue of the Python cases: the FMUs' paths (argv[1], JSON) and a stepping helper.
PROLOGUE = r"""
import json, sys, threading
import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

fmus = json.loads(sys.argv[1])
STOP, STEP = float(sys.argv[2]), float(sys.argv[3])


def open_slave(path, name, folder=None, logging=False):
    description = read_model_description(path)
    folder = folder or extract(path)
    slave = FMU2Slave(guid=description.guid, unzipDirectory=folder, instanceName=name,
                      modelIdentifier=description.coSimulation.modelIdentifier)
    slave.instantiate(loggingOn=logging)
    refs = {v.name: v.valueReference for v in description.modelVariables}
    return slave, refs, folder


def initialize(slave, **reals):
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for vr, value in reals.items():
        slave.setReal([vr], [value])
    slave.exitInitializationMode()


def run(slave, refs, steps=round(STOP / STEP)):
    t = 0.0
    for _ in range(steps):
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=STEP)
        t += STEP
    value = slave.getReal([refs["F_mesh"]])[0]
    assert np.isfinite(value) and value > 0.0, value
    return value
"""

CASES = {
    # what nearly every user does: one fmpy.simulate_fmu in a script
    "plain": r"""
import fmpy
r = fmpy.simulate_fmu(fmus["reference"], stop_time=STOP, output_interval=STEP)
assert abs(r["time"][-1] - STOP) < 1e-12 and (r["F_mesh"] > 0).all()
""",
    # three instances of one FMU alive together, stepped in turn: the same outputs
    "several_instances": r"""
slaves = [open_slave(fmus["reference"], f"gear{i}") for i in range(3)]
for slave, refs, _ in slaves:
    initialize(slave)
values = [run(slave, refs) for slave, refs, _ in slaves]
assert values[0] == values[1] == values[2], values
for slave, _, _ in slaves:
    slave.terminate()
    slave.freeInstance()
""",
    # a two-stage gearbox: the gear FMUs of two scenes in one process
    "two_scenes": r"""
first, refs1, _ = open_slave(fmus["reference"], "stage1")
second, refs2, _ = open_slave(fmus["torsional"], "stage2")
initialize(first)
initialize(second)
run(first, refs1)
run(second, refs2)
for slave in (first, second):
    slave.terminate()
    slave.freeInstance()
""",
    # instantiate, free, instantiate again, three times, the library loaded throughout
    "reinstantiate": r"""
slave, refs, folder = open_slave(fmus["reference"], "gear")
values = []
for i in range(3):
    if i:
        slave.instantiate(loggingOn=False)
    initialize(slave)
    values.append(run(slave, refs))
    slave.terminate()
    slave.fmi2FreeInstance(slave.component)
slave.freeLibrary()
assert values[0] == values[1] == values[2], values
""",
    # load the library, free it, load it again, as a simulator does on a re-run
    "reload_library": r"""
folder = extract(fmus["reference"])
values = []
for i in range(3):
    slave, refs, _ = open_slave(fmus["reference"], "gear", folder=folder)
    initialize(slave)
    values.append(run(slave, refs))
    slave.terminate()
    slave.freeInstance()  # fmi2FreeInstance, then the library is closed
assert values[0] == values[1] == values[2], values
""",
    # made on one thread, stepped on another (and the other way round)
    "other_thread": r"""
made = {}
def make():
    made["a"] = open_slave(fmus["reference"], "made_aside")
worker = threading.Thread(target=make)
worker.start(); worker.join()
slave_a, refs_a, _ = made["a"]
slave_b, refs_b, _ = open_slave(fmus["reference"], "made_here")
done = {}
def step_b():
    initialize(slave_b)
    done["b"] = run(slave_b, refs_b)
worker = threading.Thread(target=step_b)
worker.start()
initialize(slave_a)
done["a"] = run(slave_a, refs_a)
worker.join()
assert done["a"] == done["b"], done
for slave in (slave_a, slave_b):
    slave.terminate()
    slave.freeInstance()
""",
    # a Fatal call (a parameter out of range, logging off), then a good instance
    "fatal": r"""
from fmpy.fmi1 import FMICallException
slave, refs, folder = open_slave(fmus["reference"], "bad")
try:
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([refs["solver_tolerance"]], [-1.0])
    slave.exitInitializationMode()
except FMICallException:
    pass
else:
    raise AssertionError("a negative solver_tolerance was accepted")
slave.freeInstance()
good, refs, _ = open_slave(fmus["reference"], "good", folder=folder)
initialize(good)
run(good, refs)
good.terminate()
good.freeInstance()
""",
    # logging on (every message to fmpy's logger), switched off and on again
    "logging": r"""
import fmpy
seen = []
def logger(component, instance, status, category, message):
    seen.append(message)
r = fmpy.simulate_fmu(fmus["reference"], stop_time=STOP, output_interval=STEP,
                      debug_logging=True, logger=logger)
assert abs(r["time"][-1] - STOP) < 1e-12
slave, refs, _ = open_slave(fmus["reference"], "toggled", logging=True)
slave.setDebugLogging(False, [])
initialize(slave)
slave.setDebugLogging(True, [])
run(slave, refs)
slave.terminate()
slave.freeInstance()
""",
    # the FMI 3.0 FMU (pythonfmu3) through fmpy
    "fmi3": r"""
import fmpy
r = fmpy.simulate_fmu(fmus["reference_fmi3"], stop_time=STOP, output_interval=STEP)
assert abs(r["time"][-1] - STOP) < 1e-12 and (r["F_mesh"] > 0).all()
""",
    # libcosim (libcosimpy): the Open Simulation Platform's master
    "libcosim": r"""
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
log_output_level(CosimLogLevel.ERROR)
step_ns = round(STEP * 1e9)
execution = CosimExecution.from_step_size(step_size=step_ns)
index = execution.add_local_slave(CosimLocalSlave(fmu_path=fmus["reference"],
                                                  instance_name="gear"))
last = CosimObserver.create_last_value()
execution.add_observer(observer=last)
assert execution.simulate_until(target_time=round(STOP / STEP) * step_ns)
description = read_model_description(fmus["reference"])
vr = next(v.valueReference for v in description.modelVariables if v.name == "F_mesh")
assert last.last_real_values(index, [vr])[0] > 0.0
""",
}
C_CASE = "c_host"
ALL_CASES = (*CASES, C_CASE)


def build_fmus(folder: Path) -> dict[str, str]:
    """The FMUs the cases load: reference and torsional (FMI 2.0), reference (FMI 3.0)."""
    from herringbone.fmu import builder

    models = ROOT / "models"
    folder.mkdir(parents=True, exist_ok=True)
    built = {"reference": models / "reference.toml", "torsional": models / "torsional.toml"}
    fmus = {name: str(folder / f"{name}.fmu") for name in built}
    for name, scene in built.items():
        if not Path(fmus[name]).exists():
            builder.build_gear_fmu(scene, Path(fmus[name]))
    fmus["reference_fmi3"] = str(folder / "reference_fmi3.fmu")
    if not Path(fmus["reference_fmi3"]).exists():
        builder.build_gear_fmu(built["reference"], Path(fmus["reference_fmi3"]), fmi_version=3)
    return fmus


def c_host_command(fmus: dict[str, str], folder: Path) -> list[str]:
    """Compile tests/fmu/c_host/c_host.c (once) and unzip the reference FMU for it; the command
    that runs it through tests/fmu/c_host/run.sh."""
    import fmpy

    executable = folder / "c_host"
    unzipped = folder / "reference_unzipped"
    if not executable.exists():
        headers = Path(fmpy.__file__).parent / "c-code"
        subprocess.run(["cc", "-O2", "-I", str(headers), "-o", str(executable),
                        str(C_HOST / "c_host.c"), "-ldl"], check=True)
    if not unzipped.exists():
        fmpy.extract(fmus["reference"], str(unzipped))
    description = fmpy.read_model_description(fmus["reference"])
    vr = next(v.valueReference for v in description.modelVariables if v.name == "F_mesh")
    return [str(C_HOST / "run.sh"), sys.executable, str(executable), str(unzipped),
            description.coSimulation.modelIdentifier, description.guid, str(STOP), str(STEP),
            str(vr)]


def case_command(case: str, fmus: dict[str, str], folder: Path) -> list[str]:
    """The command line of one process of `case`."""
    if case == C_CASE:
        return c_host_command(fmus, folder)
    return [sys.executable, "-c", PROLOGUE + CASES[case], json.dumps(fmus), repr(STOP),
            repr(STEP)]


def run_case(case: str, fmus: dict[str, str], folder: Path, runs: int, parallel: int = 2,
             timeout: float = 300.0, on_progress=None) -> list[subprocess.CompletedProcess]:
    """`runs` fresh processes of `case`, `parallel` at a time; the failed ones (non-zero
    exit, or killed after `timeout` s). `on_progress(done, failed)` after each process."""
    command = case_command(case, fmus, folder)
    environment = {**os.environ, "PYTHONFAULTHANDLER": "1"}

    def one(_):
        try:
            return subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                                  env=environment)
        except subprocess.TimeoutExpired as expired:
            return subprocess.CompletedProcess(command, -9, expired.stdout or "",
                                               f"timed out after {timeout} s")

    failed = []
    with ThreadPoolExecutor(parallel) as pool:
        for number, run in enumerate(pool.map(one, range(runs)), start=1):
            if run.returncode != 0:
                failed.append(run)
            if on_progress is not None:
                on_progress(number, len(failed))
    return failed


def _report_every(count: int):
    """A progress callback that prints a line every `count` processes (to stderr)."""
    def report(done: int, failed: int) -> None:
        if done % count == 0:
            print(f"    {done} processes, {failed} non-zero", file=sys.stderr, flush=True)
    return report


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=200, help="processes per case (200)")
    parser.add_argument("--plain-runs", type=int, default=None,
                        help="processes of the plain case (default: --runs)")
    parser.add_argument("--parallel", type=int, default=2, help="processes at a time (2)")
    parser.add_argument("--cases", nargs="+", choices=ALL_CASES, default=list(ALL_CASES))
    parser.add_argument("--fmu-dir", type=Path, default=None,
                        help="where to build (or find) the FMUs; default a temporary folder")
    args = parser.parse_args(argv)
    folder = args.fmu_dir or Path(tempfile.mkdtemp(prefix="lifecycles-"))
    fmus = build_fmus(folder)
    print(f"{'case':<18} {'runs':>6} {'non-zero':>9} {'wall s':>8}")
    total = 0
    for case in args.cases:
        if case == C_CASE and not shutil.which("cc"):
            print(f"{case:<18} skipped: no C compiler")
            continue
        runs = args.plain_runs if case == "plain" and args.plain_runs else args.runs
        started = time.perf_counter()
        failed = run_case(case, fmus, folder, runs, args.parallel, on_progress=_report_every(50))
        total += len(failed)
        print(f"{case:<18} {runs:>6} {len(failed):>9} {time.perf_counter() - started:>8.0f}",
              flush=True)
        for run in failed[:3]:
            print(f"    exit {run.returncode}: {run.stderr.strip()[-600:]}")
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
