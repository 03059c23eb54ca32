"""What a communication step of the gear FMU costs a host, and how much of it is the integrator.

For each scene and communication step h: the FMU (FMI 2.0, built from the current sources once,
as the other benchmarks build it) driven by fmpy's FMU2Slave in this process, µs of wall time a
step for `doStep` alone and for `doStep` followed by `getReal` of every real output (what a
master does at each communication point), best of --repeats rounds of --span simulated seconds;
and beside it the FMU's own integrator (CompiledStepper at the FMU's defaults: "auto", the
default tolerance) driven by `run_to` every h in this process: what of the step is the
integration, the rest being the slave's Python, pythonfmu's bridge and fmpy's ctypes.

    python benchmarks/step_cost.py                          # reference, steps of 1e-3 and 1e-4 s
    python benchmarks/step_cost.py high_speed --steps 1e-4 --span 0.05
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import common  # noqa: E402


def fmu_step_cost(fmu_dir, span, step, repeats) -> tuple[float, float]:
    """(µs a doStep, µs a doStep and getReal of every real output) of the extracted FMU, best
    of `repeats` rounds of `span` s at communication steps of `step` s, each round on a fresh
    instance after one step that loads its compiled code."""
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    description = read_model_description(str(fmu_dir))
    outputs = [variable.valueReference for variable in description.modelVariables
               if variable.causality == "output" and variable.type == "Real"]
    count = int(round(span / step))
    best = {False: float("inf"), True: float("inf")}
    for _ in range(repeats):
        for read in (False, True):
            slave = FMU2Slave(guid=description.guid, unzipDirectory=str(fmu_dir),
                              modelIdentifier=description.coSimulation.modelIdentifier,
                              instanceName="gear")
            slave.instantiate(loggingOn=False)
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=step)
            started = time.perf_counter()
            for k in range(1, count + 1):
                slave.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
                if read:
                    slave.getReal(outputs)
            best[read] = min(best[read], (time.perf_counter() - started) / count * 1e6)
            slave.terminate()
            slave.freeInstance()
    return best[False], best[True]


def integrator_step_cost(scene, span, step, repeats) -> float:
    """µs a call of the FMU's integrator's run_to every `step` s, best of `repeats` runs of
    `span` s after one that loads its compiled code."""
    from herringbone.integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper
    from herringbone.integrate.contract import start_position
    from herringbone.model.assembly import GearTrainModel

    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, DEFAULT_TOLERANCE, "auto")
    torques = scene.inputs.at(0.0)
    count = int(round(span / step))
    best = float("inf")
    for _ in range(repeats + 1):
        run = stepper.start(start_position(model, torques[0]))
        started = time.perf_counter()
        for k in range(1, count + 1):
            stepper.run_to(run, k * step, torques)
        best = min(best, (time.perf_counter() - started) / count * 1e6)
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenes", nargs="*", default=["reference"])
    parser.add_argument("--steps", type=float, nargs="+", default=[1e-3, 1e-4],
                        help="communication steps, s (1e-3 1e-4)")
    parser.add_argument("--span", type=float, default=0.02, help="simulated s a round (0.02)")
    parser.add_argument("--repeats", type=int, default=5, help="rounds, the best kept (5)")
    args = parser.parse_args(argv)
    import herringbone

    print("\n".join(common.machine_record(common.command_line(__file__, argv or sys.argv[1:]))))
    print("scene | step s | doStep µs | doStep + getReal µs | s/s | integrator run_to µs")
    for name in args.scenes:
        path = common.MODELS / f"{name}.toml"
        fmu_dir, scene = common.scene_fmu(path), herringbone.load_scene(path)
        for step in args.steps:
            alone, read = fmu_step_cost(fmu_dir, args.span, step, args.repeats)
            integrator = integrator_step_cost(scene, args.span, step, args.repeats)
            print(f"{name} | {step:g} | {alone:.2f} | {read:.2f} | {read * 1e-6 / step:.4f} | "
                  f"{integrator:.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
