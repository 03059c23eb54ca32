"""Would an exponential integrator pay on the segments the exponential method cannot take
exactly? Steps of Lawson Runge-Kutta schemes against DOP853's over whole segments, and the
compiled cost of what a Lawson stage adds to a DOP853 stage.

Steps. On each scene the compiled DOP853 stepper runs to --warm s, then on to just past each of
the next --segments switches; from there (the vibration the switch set off ringing) each
segment, its set and loaded points fixed, is integrated over the time its pinion angle takes to
reach the set's end, at the stepper's own tolerances, by (tests/helpers/lawson.py):
    DOP853 with the stepper's step bound, and without it;
    Lawson-DOP853 on the set's linear system frozen where it begins (what tables per contact
    set would hold), and on the Jacobian at each step's start (the limit of any finer table);
    Lawson-DOPRI5 (order 5, 7 stages) on the same two.
It prints accepted and rejected steps, summed over the segments, and how far each end state is
from the bounded DOP853's, in units of the absolute tolerance.

Held speed (--held-speed): each segment run with its points moved at the train's rigid
speed from the set's start (a linear time-varying system, whose transition over the set could
be made once per set and speed), and that run corrected to first order in the pinion's
departure from the held motion (tests/helpers/held_speed.py): how far each lands from the
model's own run over the set, over the force scale.

Cost (unless --no-cost): CPU µs of one compiled DOP853 step (dop853.step), of one exact step
from a new start (exponential.step: a product by L, the exponentials, a product by R), of the
two products alone (L on the acceleration rows, R) and of numba's eig of a set's augmented
matrix (what a modal form per step would start from), in compiled loops on the reference
scene.

    python benchmarks/exponential_variable.py                    # the four scenes, the cost
    python benchmarks/exponential_variable.py lead_error --segments 8 --no-cost
    python benchmarks/exponential_variable.py --no-cost --pinion   # and the pinion's departure
    python benchmarks/exponential_variable.py --no-cost --held-speed   # a held speed, corrected
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(ROOT / "tests"))

import common  # noqa: E402
import numpy as np  # noqa: E402
from helpers import held_speed, lawson  # noqa: E402

SCENES = ("lead_error", "staggered", "coinciding_switches", "contact_loss")
HELD_SPEED_FACTORS = (1.0, 1.001, 1.003, 1.01)  # held speed / the train's rigid speed


def variants(stepper):
    """(label, keyword arguments of lawson.integrate) of each scheme measured."""
    scales = stepper.absolute_tolerance / stepper.step_tolerance

    def frozen(segment):
        return lawson.frozen(segment)

    def linearized(segment):
        return lawson.linearized(segment, scales)

    return (("DOP853, step bound", None, {"max_step": stepper.max_step}),
            ("DOP853", None, {}),
            ("Lawson-DOP853, frozen", frozen, {}),
            ("Lawson-DOP853, Jacobian each step", linearized, {}),
            ("Lawson-DOPRI5, frozen", frozen, {"tableau": lawson.DOPRI5}),
            ("Lawson-DOPRI5, Jacobian each step", linearized, {"tableau": lawson.DOPRI5}))


def step_counts(path, count, warm):
    """Print the steps of every variant over `count` segments of the scene at `path`."""
    import herringbone

    scene = herringbone.load_scene(path)
    _, stepper, found = lawson.segments_after_switches(scene, count, warm)
    absolute, relative = stepper.absolute_tolerance, stepper.step_tolerance
    ends = {}
    for label, form_of, options in variants(stepper):
        accepted = rejected = 0
        for index, (segment, state, span) in enumerate(found):
            result = lawson.integrate(segment, state, span, absolute, relative,
                                      stepper.max_step / 4,
                                      form=None if form_of is None else form_of(segment),
                                      **options)
            accepted, rejected = accepted + result.accepted, rejected + result.rejected
            ends[label, index] = result.state
        apart = max(float(np.max(np.abs(ends[label, i] - ends["DOP853, step bound", i])
                                 / absolute)) for i in range(len(found)))
        print(f"{path.stem} | {label} | {accepted} | {rejected} | {apart:.2g}", flush=True)


def pinion_deviation(path, count, warm):
    """Print, per segment, how far the pinion angle strays over the set from the straight
    line (and from the parabola) fitted through it in time, over the set's length: what a
    scheme exact for a travel polynomial in t would still have to approximate."""
    from scipy.integrate import solve_ivp

    import herringbone

    scene = herringbone.load_scene(path)
    model, stepper, found = lawson.segments_after_switches(scene, count, warm)
    for segment, state, span in found:
        solution = solve_ivp(lambda _t, x, s=segment: lawson.rate(s, x), (0.0, span), state,
                             method="DOP853", rtol=1e-10,
                             atol=1e-3 * stepper.absolute_tolerance, dense_output=True)
        times = np.linspace(0.0, span, 400)
        angle = solution.sol(times)[model.pinion]
        length = angle[-1] - angle[0]
        strays = [float(np.max(np.abs(angle - np.polyval(np.polyfit(times, angle, degree),
                                                          times)))) / length
                  for degree in (1, 2)]
        print(f"{path.stem} | {span * 1e6:.0f} | {strays[0]:.1e} | {strays[1]:.1e}",
              flush=True)


def held_speed_errors(path, count, warm):
    """Print, per segment, how far the segment run at a held speed (its points moved by the
    pinion angle at the set's start going on at the train's rigid speed) lands from the
    model's own run over the set, and how far with its first-order correction in the pinion's
    departure (tests/helpers/held_speed.py), over the force scale; the corrected run also
    with the held speed off the train's by each factor of HELD_SPEED_FACTORS but the first (a
    table made for a band of speeds); and the run corrected to second order."""
    import herringbone

    scene = herringbone.load_scene(path)
    model, stepper, found = lawson.segments_after_switches(scene, count, warm)
    absolute = 1e-7 * stepper.absolute_tolerance
    for segment, state, span in found:
        own = held_speed.model_end(segment, state, span, absolute)
        held = held_speed.held_motion(segment, state, model.pinion)
        runs = [(held, 0), *((held_speed.held_motion(segment, state, model.pinion, factor), 1)
                             for factor in HELD_SPEED_FACTORS), (held, 2)]
        ends = [held_speed.corrected_end(segment, state, span, absolute, nominal, model.pinion,
                                         order) for nominal, order in runs]
        errors = " | ".join(f"{held_speed.force_error_between(model, segment, end, own):.1e}"
                            for end in ends)
        print(f"{path.stem} | {segment.count} | {span * 1e6:.0f} | {errors}", flush=True)


def compiled_cost(repeats=200_000):
    """Print the CPU µs of a DOP853 step, an exact step from a new start, the two modal
    products and a held-speed set crossed by its tables (a transition of [x; u] and a
    quadratic form of it, tests/helpers/held_speed.py), in compiled loops (reference scene,
    1e-3 s in, half the step bound)."""
    import herringbone
    from herringbone.integrate.compiled import exponential, walk
    from herringbone.integrate.compiled_stepper import CompiledStepper
    from herringbone.integrate.contract import start_position
    from herringbone.model.assembly import GearTrainModel
    from herringbone.model.equations import derivative

    scene = herringbone.load_scene(common.MODELS / "reference.toml")
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7, "exponential")
    run = stepper.start(start_position(model, scene.inputs.at(0.0)[0]))
    stepper.run_to(run, 1e-3, scene.inputs.at(0.0))
    interval, torques = int(run.place[0]), scene.inputs.at(0.0)
    exact = interval * 2
    segment = walk.CompiledSegment(stepper.tables[interval], int(stepper.counts[interval]),
                                   run.loaded, torques[0], torques[1],
                                   stepper.lengths[interval], 2, exact)
    state, size = run.state.copy(), len(run.state)
    rate = np.empty(size)
    derivative(model.system, segment.points, segment.point_count, run.loaded, torques[0],
               torques[1], state, rate)
    kernels = _cost_kernels()
    h, tables = stepper.max_step / 2, stepper.exact_tables
    cases = (("dop853.step", kernels[0],
              (model.system, segment, state, rate, h, stepper.absolute_tolerance,
               stepper.step_tolerance, np.zeros((14, size)), np.zeros(size), np.zeros(size))),
             ("exponential.step, new start", kernels[1],
              (exponential.exact_train(model.system), stepper.exact_buffers, exact, state,
               torques[0], torques[1], h, np.zeros(size))),
             ("L (acceleration rows) and R", kernels[2],
              (tables, exact, state, np.zeros(size))),
             ("a held-speed set from its tables: Φ·X and Q : X ⊗ X", kernels[4],
              (np.ones((size + 3, size + 3)), np.ones((size, size + 3, size + 3)),
               np.ones(size + 3), np.zeros(size))),
             ("np.linalg.eig of the set's Â (complex)", kernels[3],
              (lawson.frozen_form(lawson.Segment(model.system, segment.points,
                                                 segment.point_count, run.loaded,
                                                 torques)).astype(complex),)))
    for label, kernel, arguments in cases:
        kernel(*arguments, 2)
        calls = repeats if "eig" not in label else repeats // 100
        best = np.inf
        for _ in range(3):
            started = time.process_time()
            kernel(*arguments, calls)
            best = min(best, time.process_time() - started)
        print(f"{label} | {best / calls * 1e6:.3f}", flush=True)


def _cost_kernels():
    """The compiled loops compiled_cost times (compiled here, when asked for)."""
    from numba import njit

    from herringbone.integrate.compiled import dop853, exponential

    @njit
    def dop853_steps(system, segment, state, rate, h, absolute, relative, stages, work, out,
                     count):
        total = 0.0
        for _ in range(count):
            state[0] += 1e-12 * total
            total += dop853.step(system, segment, state, rate, h, absolute, relative, stages,
                                 work, out)
        return total

    @njit
    def exact_steps(train, buffers, exact, state, motor, load, h, out, count):
        total = 0.0
        for _ in range(count):
            state[0] += 1e-15  # a new start: the product by L and the exponentials again
            exponential.step(train, buffers, exact, state, motor, load, h, False, 1.0,
                             math.inf, out)
            total += out[0]
        return total

    return (dop853_steps, exact_steps) + _modal_kernels()


def _modal_kernels():
    """compiled_cost's loops of the modal products and of the eigen-decomposition."""
    from numba import njit

    @njit
    def products(tables, exact, state, out, count):
        size, half = state.shape[0], state.shape[0] // 2
        slow, fast = tables.slow_count[exact], tables.fast_count[exact]
        total = 0.0
        for _ in range(count):
            state[0] += 1e-15
            for i in range(slow):
                value = 0.0
                for j in range(half, size):
                    value += tables.slow_left[exact, i, j] * state[j]
                tables.modal_slow[i] = value
            for k in range(fast):
                real = imaginary = 0.0
                for j in range(half, size):
                    entry = tables.fast_left[exact, k, j]
                    real += entry.real * state[j]
                    imaginary += entry.imag * state[j]
                tables.modal_fast[k] = complex(real, imaginary)
            for i in range(size):
                value = 0.0
                for k in range(slow):
                    value += tables.slow_right[exact, i, k] * tables.modal_slow[k]
                for k in range(fast):
                    entry, coordinate = tables.fast_right[exact, i, k], tables.modal_fast[k]
                    value += entry.real * coordinate.real - entry.imag * coordinate.imag
                out[i] = value
            total += out[0]
        return total

    @njit
    def modal_forms(augmented, count):
        total = 0.0
        for _ in range(count):
            rates, _vectors = np.linalg.eig(augmented)
            total += rates[0].real
        return total

    @njit
    def held_speed_sets(transition, correction, start, out, count):
        size, width = out.shape[0], start.shape[0]
        total = 0.0
        for _ in range(count):
            start[0] += 1e-15
            for i in range(size):
                value = 0.0
                for j in range(width):
                    value += transition[i, j] * start[j]
                for j in range(width):
                    inner = 0.0
                    for k in range(width):
                        inner += correction[i, j, k] * start[k]
                    value += inner * start[j]
                out[i] = value
            total += out[0]
        return total

    return products, modal_forms, held_speed_sets


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenes", nargs="*", default=list(SCENES))
    parser.add_argument("--segments", type=int, default=4, help="segments per scene")
    parser.add_argument("--warm", type=float, default=0.01, help="s run before the first")
    parser.add_argument("--no-cost", dest="cost", action="store_false")
    parser.add_argument("--pinion", action="store_true",
                        help="also the pinion angle's departure from a polynomial in t")
    parser.add_argument("--held-speed", action="store_true",
                        help="also the segment run at a held speed, and corrected to first "
                             "order in the pinion's departure")
    args = parser.parse_args(argv)
    print("scene | scheme | accepted steps | rejected | max |x − x_DOP853, bound| / atol")
    for path in common.scene_paths(args.scenes, parser, "scene"):
        step_counts(path, args.segments, args.warm)
    if args.pinion:
        print("scene | set's span µs | max |φp − line| / length | max |φp − parabola| / length")
        for path in common.scene_paths(args.scenes, parser, "scene"):
            pinion_deviation(path, args.segments, args.warm)
    if args.held_speed:
        print("scene | set's points | span µs | held speed, error / force scale | "
              "corrected to first order | the same, held speed "
              + " | ".join(f"×{factor:g}" for factor in HELD_SPEED_FACTORS[1:])
              + " | corrected to second order")
        for path in common.scene_paths(args.scenes, parser, "scene"):
            held_speed_errors(path, args.segments, args.warm)
    if args.cost:
        print("compiled kernel | CPU µs a call")
        compiled_cost()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
