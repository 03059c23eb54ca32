"""The FMU in a Python host (fmpy, in its own process): pythonfmu 0.7's C++ side releases Python
references it does not own (fmu/pythonfmu_references.py); the slave gives them back, so
repeated instances and Fatal calls leave every reference count as the garbage collector
counts it, and the process exits cleanly instead of aborting on a corrupted heap."""
import subprocess
import sys

import pytest

# Instantiates the FMU (argv[1]) three times in one process, each time either initializing it
# or making exitInitializationMode Fatal (argv[2] == "fatal": the gear's solver tolerance
# negative, with logging off so the slave raises), then frees it. Prints, after each instance,
# how far the reference counts of the slave module's dictionary and of the slave class (module
# argv[3], class argv[4]) fall short of the references the garbage collector finds (an offset
# the same for every object counted alike).
HOST = r"""
import gc, sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

path, mode, module_name, class_name = sys.argv[1:5]
description = read_model_description(path)
tolerance = next((v.valueReference for v in description.modelVariables
                  if v.name == "solver_tolerance"), None)
folder = extract(path)


def shortfall(target):
    found = 0
    for holder in gc.get_referrers(target):
        if holder is sys._getframe():
            continue
        if isinstance(holder, dict):
            found += sum(value is target for value in holder.values())
        elif isinstance(holder, (list, tuple)):
            found += sum(value is target for value in holder)
        else:
            found += 1
    return found - (sys.getrefcount(target) - 2)


for i in range(3):
    fmu = FMU2Slave(guid=description.guid, unzipDirectory=folder, instanceName=f"gear{i}",
                    modelIdentifier=description.coSimulation.modelIdentifier)
    fmu.instantiate(loggingOn=False)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    if mode == "fatal":
        fmu.setReal([tolerance], [-1.0])
    try:
        fmu.exitInitializationMode()
    except Exception as error:
        assert mode == "fatal", error
    else:
        assert mode != "fatal"
    fmu.fmi2FreeInstance(fmu.component)
    module = sys.modules[module_name]
    print(shortfall(module.__dict__), shortfall(getattr(module, class_name)), flush=True)
"""


SLAVES = {"reference": ("herringbone_gear_fmu", "HerringboneGear"),
          "motor": ("induction_motor", "InductionMotor"), "fan": ("fan_load", "FanLoad")}


@pytest.mark.parametrize("fmu, mode", [("reference", "initialize"), ("reference", "fatal"),
                                       ("motor", "initialize"), ("fan", "initialize")])
def test_repeated_instances_leave_the_slaves_references_balanced(built_fmus, fmu, mode):
    run = subprocess.run([sys.executable, "-c", HOST, str(built_fmus[fmu]), mode, *SLAVES[fmu]],
                         capture_output=True, text=True, timeout=300)
    # an over-released object is freed while still in use: at the latest the interpreter's
    # teardown frees it again, which glibc aborts on (-6) in some runs
    assert run.returncode == 0, run.stderr[-2000:]
    shortfalls = [tuple(map(int, line.split())) for line in run.stdout.split("\n") if line]
    assert len(shortfalls) == 3
    # pythonfmu 0.7 alone: the module's dictionary one further short with every instance,
    # the class with every Fatal
    assert shortfalls[0] == shortfalls[1] == shortfalls[2], shortfalls
