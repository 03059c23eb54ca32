"""DOP853 against the exponential method, side by side, on every shipped scene in one run.

For each scene and method: the compiled kernel's CPU time per simulated second as the FMU
drives it ("step": run_to every output interval) and driven through the whole run in one call
per piece of the torque schedule ("run": CompiledStepper.sample, as herringbone.simulate
drives it: the exponential method takes the samples of its exact segments inside its steps),
best of --repeats rounds that alternate the two methods, each run after a warm-up that loads
the compiled code (CPU time of the process, which other work on a shared machine disturbs
less than wall time; the machine's pace comes and goes, and alternating lets a slow stretch
fall on both methods); for each drive its accepted steps per simulated second and its error
against the scipy reference (max over the forces, over the force scale); the seconds it takes
to set the stepper up (eigenvalues, step bound, the exponential method's modal forms); and how
many of the scene's contact sets (all points loaded) the exponential method takes exactly.

    python benchmarks/exponential.py                      # every shipped scene, 0.05 s each
    python benchmarks/exponential.py reference --span 1   # one scene, a simulated second

The reference runs (scipy's DOP853 at --reference-tolerance) are cached on disk as the other
benchmarks cache them (results/benchmark/reference_cache).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import common  # noqa: E402

METHODS = ("dop853", "exponential")


def per_step(stepper, scene, run, samples, output_interval):
    """The run as the FMU drives it: CompiledStepper.run_to to every output time, the torques
    of the scene's schedule at the step's start held over it; samples[k]: the outputs then."""
    for k in range(len(samples)):
        stepper.run_to(run, (k + 1) * output_interval, scene.inputs.at(k * output_interval))
        samples[k] = run.outputs


def per_run(stepper, scene, run, samples, output_interval):
    """The same run in one call of CompiledStepper.sample per piece of the torque schedule
    (split where its torques change, as herringbone.simulate splits it)."""
    import numpy as np

    times = (np.arange(len(samples)) + 1) * output_interval
    starts = np.arange(len(samples)) * output_interval  # of per_step's steps, as it reckons them
    edges = np.searchsorted(starts, scene.inputs.change_times(), side="left")
    for first, after in zip([0, *edges], [*edges, len(times)]):
        if first < after:
            stepper.sample(run, times[first:after], samples[first:after], times[after - 1],
                           scene.inputs.at(first * output_interval))


DRIVES = {"step": per_step, "run": per_run}


def kernel_run(scene, method, span, output_interval, tolerance, repeats):
    """The compiled kernel alone, driven as DRIVES says: (seconds to set the stepper up,
    {drive: best CPU s per simulated s of the stepping}, {drive: accepted steps per simulated
    s}, {drive: (trial steps, rejected steps) per located event}, {drive: the outputs at the
    output times after 0})."""
    import numpy as np

    from herringbone.integrate.compiled_stepper import CompiledStepper
    from herringbone.integrate.contract import start_position
    from herringbone.model.assembly import GearTrainModel

    model = GearTrainModel(scene)
    started = time.perf_counter()
    stepper = CompiledStepper(model, tolerance, method)
    setup = time.perf_counter() - started
    start = start_position(model, scene.inputs.at(0.0)[0])
    count = int(round(span / output_interval))
    best, samples, steps, per_event = {}, {}, {}, {}
    for drive, function in DRIVES.items():
        function(stepper, scene, stepper.start(start), np.empty((1, model.output_layout_size)),
                 output_interval)  # load the compiled code
        best[drive] = math.inf
        for _ in range(repeats):
            run = stepper.start(start)
            samples[drive] = np.empty((count, len(run.outputs)))
            before = stepper.accepted_steps
            started = time.process_time()
            function(stepper, scene, run, samples[drive], output_interval)
            best[drive] = min(best[drive], (time.process_time() - started) / span)
            steps[drive] = (stepper.accepted_steps - before) / span
            events = max(run.events, 1)
            per_event[drive] = (run.trial_steps / events, run.rejected_steps / events)
    outputs = {drive: {name: rows[:, i] for name, i in model.output_layout}
               for drive, rows in samples.items()}
    return setup, best, steps, per_event, outputs


def alternating_runs(scene, span, output_interval, tolerance, repeats):
    """kernel_run for each method in turn, `repeats` rounds of one run each (DOP853, the
    exponential method, DOP853, ...), so that a stretch in which the machine runs slow falls
    on both methods alike rather than on the one measured then: {method: kernel_run's
    result, each drive's CPU s per simulated s the best of the rounds, the setup's too}."""
    results = {}
    for _ in range(repeats):
        for method in METHODS:
            setup, seconds, steps, per_event, outputs = kernel_run(
                scene, method, span, output_interval, tolerance, 1)
            if method in results:
                setup = min(setup, results[method][0])
                seconds = {drive: min(value, results[method][1][drive])
                           for drive, value in seconds.items()}
            results[method] = (setup, seconds, steps, per_event, outputs)
    return results


def force_error(outputs, reference, names, scale):
    """max |x − x_ref| over the forces at the output times after 0, over the force scale."""
    count = len(outputs[names[0]])
    return max(float(abs(outputs[name] - reference[name][1:count + 1]).max())
               for name in names) / scale


def exact_sets(scene) -> str:
    """How many of the scene's contact sets (all points loaded) the exponential method
    propagates exactly."""
    from herringbone.integrate.compiled import exponential
    from herringbone.integrate.compiled_stepper import CompiledStepper
    from herringbone.model.assembly import GearTrainModel

    tables = CompiledStepper(GearTrainModel(scene), 1e-7, "exponential").exact_tables
    valid = tables.valid.reshape(-1, exponential.VARIANTS)[:, exponential.ALL_LOADED]
    return f"{int(valid.sum())}/{len(valid)}"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenes", nargs="*", default=["models/*.toml"])
    parser.add_argument("--span", type=float, default=0.05, help="simulated s per scene")
    parser.add_argument("--output-interval", type=float, default=1e-3)
    parser.add_argument("--tolerance", type=float, default=1e-7)
    parser.add_argument("--reference-tolerance", type=float, default=1e-10)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    import herringbone

    print(f"span {args.span:g} s, output every {args.output_interval:g} s, tolerance "
          f"{args.tolerance:g}; error against scipy's DOP853 at {args.reference_tolerance:g}, "
          f"over the force scale; s/s: CPU s of the compiled kernel's stepping per simulated "
          f"s, best of {args.repeats} rounds that alternate the methods, driven by a call "
          f"per output step (step) or per run "
          f"(run); setup: constructing the stepper; trials/event: trial steps (event "
          f"location, grazing probes) per located event, run drive; rejected/event: steps "
          f"rejected (error control; exact steps not certified) per located event, run drive; "
          f"speed-up: DOP853's s/s over the exponential method's, each drive")
    header = ["scene", "exact sets"] + [f"{m} {what} {drive}" for m in METHODS
                                        for what in ("s/s", "steps/s", "error")
                                        for drive in DRIVES] + [f"{m} setup s" for m in METHODS]
    header += [f"{m} {what}/event" for what in ("trials", "rejected") for m in METHODS]
    print(" | ".join(header + ["speed-up step", "speed-up run"]))
    for path in common.scene_paths(args.scenes, parser, "scene"):
        scene = herringbone.load_scene(path)
        reference = common.cached_reference(path, args.span, args.output_interval,
                                            args.reference_tolerance, log=lambda text: None)
        scale = common.force_scale(scene)
        names = common.force_outputs(scene)
        row, setups, trials, rejected, cpu = [path.stem, exact_sets(scene)], [], [], [], {}
        runs = alternating_runs(scene, args.span, args.output_interval, args.tolerance,
                                args.repeats)
        for method in METHODS:
            setup, seconds, steps, per_event, outputs = runs[method]
            cpu[method] = seconds
            row += [f"{seconds[drive]:.4f}" for drive in DRIVES]
            row += [f"{steps[drive]:.3g}" for drive in DRIVES]
            row += [f"{force_error(outputs[drive], reference, names, scale):.1e}"
                    for drive in DRIVES]
            setups.append(f"{setup:.3f}")
            trials.append(f"{per_event['run'][0]:.2f}")
            rejected.append(f"{per_event['run'][1]:.2f}")
        row += setups + trials + rejected
        row += [f"{cpu['dop853'][drive] / cpu['exponential'][drive]:.1f}x" for drive in DRIVES]
        print(" | ".join(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
