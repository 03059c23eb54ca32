"""A small fmpy host for tests: one FMU2Slave instance with its log captured; and fmpy's run
of an FMU in a process of its own."""
import shutil
import subprocess
import sys
from ctypes import byref

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    calloc,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    free,
)
from fmpy.logging import addLoggerProxy


class Instance:
    """Instantiate, set start values, initialize; then step, read outputs, save and restore."""

    def __init__(self, fmu_path, start_values=None, name="gear", start_time=0.0,
                 tolerance=None, initialize=True, categories=None, stop_time=None):
        self.description = read_model_description(str(fmu_path))
        self.variables = {v.name: v for v in self.description.modelVariables}
        self.unzipped = extract(str(fmu_path))
        self.messages = []  # (status, text) of every log message
        self.categories = []  # the category of each

        def on_log(environment, instance, status, category, message):
            self.messages.append((status, message.decode()))
            self.categories.append(category.decode() if category else None)

        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(on_log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))
        self.slave = FMU2Slave(guid=self.description.guid, unzipDirectory=self.unzipped,
                               modelIdentifier=self.description.coSimulation.modelIdentifier,
                               instanceName=name)
        self.slave.instantiate(callbacks=self.callbacks, loggingOn=True)
        if categories is not None:  # the log categories the host enables (all: none named)
            self.slave.setDebugLogging(True, categories)
        self.slave.setupExperiment(startTime=start_time, tolerance=tolerance, stopTime=stop_time)
        self.time = start_time
        if initialize:
            self.initialize(start_values)

    def initialize(self, start_values=None):
        self.slave.enterInitializationMode()
        self.set(**(start_values or {}))
        self.slave.exitInitializationMode()

    def set(self, **values):
        for name, value in values.items():
            variable = self.variables[name]
            setter = {"Real": self.slave.setReal, "Integer": self.slave.setInteger,
                      "Boolean": self.slave.setBoolean}[variable.type]
            setter([variable.valueReference], [value])

    def get(self, names):
        out = {}
        for name in names:
            variable = self.variables[name]
            getter = {"Real": self.slave.getReal, "Integer": self.slave.getInteger}[variable.type]
            out[name] = getter([variable.valueReference])[0]
        return out

    def step(self, size):
        self.slave.doStep(currentCommunicationPoint=self.time, communicationStepSize=size)
        self.time += size

    def free(self):
        self.slave.freeInstance()
        shutil.rmtree(self.unzipped, ignore_errors=True)


def structured_inputs(times, motor_torque, load_torque):
    """The input table fmpy.simulate_fmu takes."""
    table = np.zeros(len(times), dtype=[("time", float), ("M_motor", float), ("M_load", float)])
    table["time"], table["M_motor"], table["M_load"] = times, motor_torque, load_torque
    return table


def outputs_in_a_process(location, stop_time: float, step: float, outputs) -> np.ndarray:
    """fmpy.simulate_fmu of the FMU (or unpacked folder) `location` in a process of its own, as
    a host would run it (a crash there is its exit status, not the test's): a row per sample,
    the time and then `outputs` (names), every bit of each float."""
    program = ("import sys, fmpy; r = fmpy.simulate_fmu(sys.argv[1], stop_time=float(sys.argv[2]),"
               " output_interval=float(sys.argv[3]), output=sys.argv[4:]);"
               " print('\\n'.join(' '.join(float(x).hex() for x in row) for row in r))")
    run = subprocess.run([sys.executable, "-c", program, str(location), str(stop_time),
                          str(step), *outputs], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, f"{location}: exit {run.returncode}: {run.stderr[-2000:]}"
    return np.array([[float.fromhex(x) for x in line.split()]
                     for line in run.stdout.splitlines()])
