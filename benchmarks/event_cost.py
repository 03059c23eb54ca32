"""What an event of an exact segment costs: the exponential method's loop beside what no event
can do without.

For each scene the exponential method's kernel runs --span simulated seconds in one call per
piece of the torque schedule (as herringbone.simulate drives it; best of --repeats, CPU time);
printed are its located events per simulated second, its CPU µs per event and exact
evaluations (accepted, rejected and trial steps) per event, and the µs per event that the
bar of issue 24 (0.01 CPU s per simulated s) allows. Beside them, in compiled loops from a
state inside an exact segment of that run (its points loaded or not, as the last column
says), the CPU µs of

- the opening aim from a new start (exponential.modal_phase_event_ahead: the product by L,
  and where the angle's modal solution leaves the contact interval, by Newton's method),
- the aim and the exact step just past the crossing it finds (exponential.step): the two
  computations an event of a phase switch cannot do without,
- an exact step from a start whose modal coordinates are kept (an event location's trial),
- the equations' rate (equations.derivative), and with the points' approach rates.

    python benchmarks/event_cost.py                          # high_speed, jump_resonance, reference
    python benchmarks/event_cost.py high_speed --span 0.2
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import common  # noqa: E402
from exponential import per_run  # noqa: E402

BAR = 0.01  # CPU s per simulated s (issue 24)


def loop_cost(scene, stepper, span, repeats):
    """(events per simulated s, CPU µs per event, exact evaluations per event) of the
    exponential method's run over `span` s, best of `repeats`."""
    from herringbone.integrate.contract import start_position

    start = start_position(stepper.model, scene.inputs.at(0.0)[0])
    rows = np.empty((int(round(span / 1e-3)), stepper.model.output_layout_size))
    per_run(stepper, scene, stepper.start(start), rows[:1], 1e-3)  # load the compiled code
    best = math.inf
    for _ in range(repeats):
        run, before = stepper.start(start), stepper.accepted_steps
        started = time.process_time()
        per_run(stepper, scene, run, rows, 1e-3)
        best = min(best, time.process_time() - started)
        evaluations = (stepper.accepted_steps - before + run.rejected_steps + run.trial_steps)
    events = max(run.events, 1)
    return events / span, best / events * 1e6, evaluations / events


def exact_state_inside(scene, stepper, span):
    """(state, exact form's index, interval length in rad, loaded sign: +1 or −1, contact
    interval) of the run at the first of a few times in `span` where its segment is exact."""
    from herringbone.integrate.compiled import exponential
    from herringbone.integrate.contract import start_position

    torques = scene.inputs.at(0.0)
    run = stepper.start(start_position(stepper.model, torques[0]))
    for time_ in np.linspace(0.3, 0.9, 7) * span:
        stepper.run_to(run, time_, torques)
        interval, count = int(run.place[0]), int(stepper.counts[int(run.place[0])])
        exact = exponential.variant_of(stepper.exact_buffers, interval, count, run.loaded,
                                       run.state)
        if exact >= 0:
            sign = 1.0 if run.loaded[0] > 0.0 else -1.0
            return run.state.copy(), exact, float(stepper.lengths[interval]), sign, interval
    raise SystemExit(f"no exact segment found in {span} s of the run")


def call_costs(scene, stepper, span, calls):
    """{what: CPU µs a call} of the compiled loops (_kernels) from a state of the run, and
    whether its points are loaded there."""
    from herringbone.integrate.compiled import exponential

    state, exact, length, sign, interval = exact_state_inside(scene, stepper, span)
    system, buffers = stepper.model.system, stepper.exact_buffers
    train = exponential.exact_train(system)
    motor, load = scene.inputs.at(0.0)
    points, count = stepper.tables[interval], int(stepper.counts[interval])
    loaded = np.full(count, 1.0 if sign > 0.0 else 0.0)
    out, rate, slopes = np.empty_like(state), np.empty_like(state), np.empty(points.shape[1])
    aim, exact_steps, rates = _kernels()
    stepping = (train, buffers, exact, state, motor, load, length, bool(system.contact_loss),
                sign, out)
    cases = {"aim": (aim, (train, buffers, exact, state, motor, load, length)),
             "aim and step": (exact_steps, (*stepping, True)),
             "step, kept start": (exact_steps, (*stepping, False)),
             "rate": (rates, (system, points, count, loaded, motor, load, state, rate, slopes,
                              False)),
             "rate and approach rates": (rates, (system, points, count, loaded, motor, load,
                                                 state, rate, slopes, True))}
    costs = {}
    for label, (kernel, arguments) in cases.items():
        kernel(*arguments, 2)
        best = math.inf
        for _ in range(3):
            started = time.process_time()
            kernel(*arguments, calls)
            best = min(best, time.process_time() - started)
        costs[label] = best / calls * 1e6
    return costs, sign > 0.0


def _kernels():
    """call_costs' compiled loops (compiled here, when asked for)."""
    from numba import njit

    from herringbone.integrate.compiled import exponential
    from herringbone.model import equations

    @njit
    def aim(train, buffers, exact, state, motor, load, length, count):
        total = 0.0
        for _ in range(count):
            state[0] += 1e-15  # a new start
            total += exponential.modal_phase_event_ahead(train, buffers, exact, state, motor,
                                                         load, length, 1.0)[0]
        return total

    @njit
    def exact_steps(train, buffers, exact, state, motor, load, length, contact_loss, sign,
                    out, aimed, count):
        total = 0.0
        for k in range(count):
            if aimed:  # from a new start, aimed just past the crossing
                state[0] += 1e-15
                ahead = exponential.modal_phase_event_ahead(train, buffers, exact, state,
                                                            motor, load, length, 1.0)[0]
                h = ahead * (1.0 + 1e-12) if math.isfinite(ahead) else 1e-5
            else:  # the start kept, the time new
                h = 1e-5 * (1.0 + 1e-3 * (k & 7))
            total += exponential.step(train, buffers, exact, state, motor, load, h,
                                      contact_loss, sign, length, out) + out[0]
        return total

    @njit
    def rates(system, points, count, loaded, motor, load, state, rate, slopes, approach,
              calls):
        total = 0.0
        for _ in range(calls):
            state[0] += 1e-15
            equations.derivative(system, points, count, loaded, motor, load, state, rate)
            if approach:
                equations.approach_rates(system, points, count, state, rate, slopes)
            total += rate[1] + slopes[0]
        return total

    return aim, exact_steps, rates


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenes", nargs="*", default=["high_speed", "jump_resonance",
                                                      "reference"])
    parser.add_argument("--span", type=float, default=0.05, help="simulated s per scene")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--calls", type=int, default=200_000, help="calls per compiled loop")
    args = parser.parse_args(argv)
    import herringbone
    from herringbone.integrate.compiled_stepper import CompiledStepper
    from herringbone.model.assembly import GearTrainModel

    columns = ["events/s", "loop µs/event", "evaluations/event", "bar µs/event", "aim µs",
               "aim and step µs", "step, kept start µs", "rate µs", "rate and approach rates µs",
               "points there"]
    print("scene | " + " | ".join(columns), flush=True)
    for name in args.scenes:
        scene = herringbone.load_scene(common.MODELS / f"{name}.toml")
        stepper = CompiledStepper(GearTrainModel(scene), 1e-7, "exponential")
        events, per_event, evaluations = loop_cost(scene, stepper, args.span, args.repeats)
        costs, loaded = call_costs(scene, stepper, args.span, args.calls)
        cells = [f"{events:.3g}", f"{per_event:.2f}", f"{evaluations:.2f}",
                 f"{BAR / events * 1e6:.2f}", *(f"{value:.3f}" for value in costs.values()),
                 "loaded" if loaded else "unloaded"]
        print(f"{name} | " + " | ".join(cells), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
