"""The checks that every scene must pass, random (test_properties.py) or shipped
(tests/regression/*.toml): both integrators run it, then

  (a) the compiled run's F_mesh and bearing forces agree with reference_simulate's within a
      bound of the force scale (GearTrainModel.force_scale()); force_judge says why that run;
  (b) no tension: with contact_loss, no half's mesh force and no loaded point's force is below
      -TENSION_BOUND of the force scale, and no free point is pressed by more than that (a
      regain the run missed); without contact_loss points may pull, and nothing is checked;
  (c) every output of both runs is finite;
  (d) the angular momentum L = I_motor·ω_motor + I_pinion·ω_pinion + (I_wheel·ω_wheel +
      I_load·ω_load)/u follows the integral of the torque surplus M_motor − M_load/u to
      MOMENTUM_BOUND of its largest term, a body's I·ω or one torque's impulse (the mesh,
      shafts and bearings are internal; a Runge-Kutta method keeps linear invariants to the
      rounding of the terms, which may cancel);
  (e) n_contacts is the same in both runs, except at samples "within a hair of a switch"
      (contact_counts_agree says which).

A scene that both integrators refuse with the chatter message (IntegrationError naming
"edge_ramp > 0": sharp face edges at low speed) passes; one refused by one integrator only fails.
The reference of every check is reference_simulate's run (force_judge); `run_recorded` runs what
herringbone.simulate runs, and the scipy reference with each step held to the tolerance; both
keep the state at every sample so that the per-point checks can see the contact points.
"""
from __future__ import annotations

import hashlib
import math
import textwrap
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from helpers import REGRESSION, force_error, force_errors, momentum_terms
from herringbone.integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper
from herringbone.integrate.contract import IntegrationError, simulate_with
from herringbone.integrate.global_error import ReferenceAccuracyWarning, can_judge
from herringbone.integrate.reference import checked_reference_run
from herringbone.integrate.stepping import ScipyStepper
from herringbone.model import equations
from herringbone.model.assembly import GearTrainModel

REFERENCE_TOLERANCE = 1e-10  # reference_simulate's default
# (a) compiled at its default tolerance (1e-7) against the reference: issue 15's bound; at 1e-9
# the compiled run must be a hundred times closer, at 1e-5 a hundred times further off at most.
DEFAULT_BOUND = 1e-4
TIGHT_TOLERANCE, TIGHT_BOUND = 1e-9, 1e-6
LOOSE_TOLERANCE, LOOSE_BOUND = 1e-5, 1e-2  # a sweep's or a first look's
# (b) a loss is located to a hundredth of the tolerance over |λ|max past its crossing: a point
# pulls for that long by its approach rate times c, some 1e-8 N; anything near 1e-6 of the force
# scale is a missed event, not a located one.
TENSION_BOUND = 1e-6
# (d) relative to the largest term of L or of the torques' impulse.
MOMENTUM_BOUND = 1e-9
# (e) a sample is on a phase switch if φp is this close to its contact set's ends (in mesh
# pitches): a pitch of 1e-6 is where the two runs' pinion angles may differ at 1e-4 force error.
PHASE_HAIR = 1e-6
CHATTER_CURE = "edge_ramp > 0"
# checked_and_recorded's and recorded_reference's runs, by (the scene's regression name, tolerance)
_CHECKED: dict = {}
_RECORDED: dict = {}


@dataclass
class RecordedRun:
    """A run's outputs ({"time": …, name: …}) and, at every sample, (state, contact set,
    loaded points): what the outputs were computed from."""

    model: GearTrainModel
    outputs: dict
    samples: list = field(default_factory=list)
    landings: int = 0  # the reference's: ScipyStepper.landings
    name: str = "reference"  # what the run is, as a failure message names it


def run_recorded(scene, integrator: str, tolerance: float) -> RecordedRun:
    """The scipy reference ("reference", DOP853, each step held to `tolerance`: a
    ScipyStepper without a horizon) or simulate ("compiled", method "auto") at `tolerance`
    over the scene's experiment, keeping each sample's state."""
    model = GearTrainModel(scene)
    run = RecordedRun(model, {}, name=integrator)
    plain_outputs = model.outputs

    def outputs_kept(state, contact_set, loaded):
        run.samples.append((np.array(state), contact_set, np.array(loaded)))
        return plain_outputs(state, contact_set, loaded)

    model.outputs = outputs_kept  # both steppers (and simulate_with) sample through it
    stepper = (ScipyStepper(model, tolerance) if integrator == "reference"
               else _SampledAtPositions(CompiledStepper(model, tolerance)))
    run.outputs = simulate_with(stepper, scene)
    run.landings = stepper.landings if integrator == "reference" else 0
    _drop_overwritten_sample(run)
    return run


def _drop_overwritten_sample(run: RecordedRun) -> None:
    """Where the last output time fell a rounding short of stop_time, it was sampled on the
    way and then overwritten by the state at stop_time itself: keep the sample stored."""
    if len(run.samples) == len(run.outputs["time"]) + 1:
        del run.samples[-2]
    assert len(run.samples) == len(run.outputs["time"])


class _SampledAtPositions:
    """A CompiledStepper whose samples go through model.outputs at the run's Position: it
    advances from sample to sample instead of sampling inside one advance. A Position re-runs
    exactly (its step size, contact set and per-interval first steps travel with it), so the
    trajectory is simulate()'s."""

    def __init__(self, stepper: CompiledStepper):
        self.stepper, self.model = stepper, stepper.model

    def advance(self, position, end, torques, sample_times=(), on_sample=None):
        for t in [t for t in sample_times if position.time <= t < end]:
            position = self.stepper.advance(position, t, torques)
            segment = position.segment
            on_sample(t, self.model.outputs(position.state, segment.contact_set, segment.loaded))
        return self.stepper.advance(position, end, torques)


def point_forces(model: GearTrainModel, state, contact_set) -> np.ndarray:
    """c·(δ + η·δ̇) of every point of the set at a state, loaded or not: what the point would
    carry if loaded (a free point's value is its gap, negative, times c)."""
    count = len(contact_set)
    approach = np.empty(count)
    equations.approaches(model.system, contact_set.table, count, state, approach)
    stiffness, _, _ = model.contact_geometry(state[:model.size], contact_set)
    return stiffness * approach


def checked_reference(scene, tolerance: float):
    """reference_simulate's run of the scene at `tolerance` and its global_error.Check, once
    per scene and tolerance in a process (the drawn tests ask for it twice), its
    ReferenceAccuracyWarning left to whoever reads the Check's estimate."""
    return checked_and_recorded(scene, tolerance)[:2]


def checked_and_recorded(scene, tolerance: float):
    """checked_reference's run and Check, and beside them the delivered run as a RecordedRun
    (its state at every sample kept, as run_recorded keeps it), made once per scene and
    tolerance in a process: check_scene judges the compiled run by it and reads its samples
    for the per-point checks, so the reference runs once (its check's runs) and not once more
    for the samples."""
    key = (regression_name(scene), tolerance)
    if key not in _CHECKED:
        recorder = _RunRecorder()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ReferenceAccuracyWarning)
            result, check = checked_reference_run(scene, tolerance=tolerance,
                                                  wrap=recorder.wrap)
        _CHECKED[key] = (result, check, recorder.delivered(result, check))
    return _CHECKED[key]


class _RunRecorder:
    """Keeps the samples of each run a check makes (`wrap`, checked_reference_run's hook: the
    model's outputs recorded as run_recorded records them), to hand over those of the run the
    check delivers (`delivered`)."""

    def __init__(self):
        self.runs: list[tuple[ScipyStepper, RecordedRun]] = []
        self.plain_outputs = None

    def wrap(self, stepper: ScipyStepper) -> ScipyStepper:
        """Record the run `stepper` is about to make (one model serves all the check's runs)."""
        model = stepper.model
        if self.plain_outputs is None:
            self.plain_outputs = plain = model.outputs

            def outputs_kept(state, contact_set, loaded):
                self.runs[-1][1].samples.append((np.array(state), contact_set,
                                                 np.array(loaded)))
                return plain(state, contact_set, loaded)

            model.outputs = outputs_kept
        self.runs.append((stepper, RecordedRun(model, {}, name="checked reference")))
        return stepper

    def delivered(self, result, check) -> RecordedRun:
        """The run the check delivered (`result`, made at check.step_tolerance) with its
        samples; its model's outputs no longer recorded."""
        stepper, run = next(made for made in self.runs
                            if made[0].tolerance == check.step_tolerance)
        run.model.outputs = self.plain_outputs
        run.outputs, run.landings = result, stepper.landings
        _drop_overwritten_sample(run)
        return run


def recorded_reference(scene, tolerance: float) -> RecordedRun:
    """run_recorded(scene, "reference", tolerance), once per scene and tolerance in a process
    (the drawn tests' per_step_holds and check_scene read the same run)."""
    key = (regression_name(scene), tolerance)
    if key not in _RECORDED:
        _RECORDED[key] = run_recorded(scene, "reference", tolerance)
    return _RECORDED[key]


def can_be_judged(scene, tolerance: float, bound: float) -> bool:
    """Whether a drawn scene can judge the compiled run against the reference at `tolerance`
    by `bound`: the reference resolves it (resolved_by_the_reference) and holds its own steps
    to the bound (per_step_holds)."""
    return (resolved_by_the_reference(scene, tolerance, bound)
            and per_step_holds(scene, tolerance, bound))


def resolved_by_the_reference(scene, tolerance: float, bound: float) -> bool:
    """Whether reference_simulate at `tolerance` estimates its own error over the run (its
    check of a run that lands) well enough to judge against `bound` (global_error.can_judge,
    the random-scene benchmark's rule). A train that rattles beyond what
    double precision resolves (no damping anywhere, dozens to hundreds of landings) puts every
    run, reference or compiled, force scales apart: it can judge no integrator, and the draw
    found one after another. A scene the reference refuses is left to check_scene."""
    try:
        _, check = checked_reference(scene, tolerance)
    except IntegrationError:
        return True
    return can_judge(check.estimate, bound)


def rounding_spread(scene, tolerance: float) -> float:
    """How far (of the force scale) the checked reference at `tolerance` moves for a relative
    1e-13 on the initial pinion speed (some 500 units of double precision): the train's
    sensitivity, what rounding alone can move its forces by."""
    moved = scene.with_parameters(w0_pinion=scene.parameters["w0_pinion"] * (1.0 + 1e-13))
    return force_error(checked_reference(scene, tolerance)[0],
                       checked_reference(moved, tolerance)[0], scene)


def per_step_holds(scene, tolerance: float, bound: float) -> bool:
    """Whether the recorded reference at `tolerance`, each step held to it, lies within
    `bound` of the force scale from force_judge's run. Where it does not, the train amplifies
    a step's error (from landing to landing) or adds it up (over long ringing) beyond what a
    tolerance per step holds to the bound, a thousand times tighter than the compiled run's
    or not (found_de62c18e83, no damping at all: 4.8e-4 at 1e-10 against the bound 1e-4). A
    scene the reference refuses is left to check_scene."""
    try:
        reference = recorded_reference(scene, tolerance)
        judge = force_judge(scene, tolerance)
    except IntegrationError:
        return True
    return force_error(reference.outputs, judge.outputs, scene) <= bound


def force_judge(scene, tolerance: float) -> RecordedRun:
    """The reference run of check_scene: (a) judges the compiled forces against it, and (b)
    to (e) read its samples. It is reference_simulate's at `tolerance` (checked_and_recorded),
    not run_recorded's reference, whose steps are each held to the tolerance itself:
    reference_simulate holds each step to what holds the whole run to the tolerance
    (stepping.step_tolerance: cut by the radians a lightly damped train rings, on every
    shipped and seeded scene at 1e-10), and where the train lifts off and lands it checks its
    error over the run and tightens its steps until it holds. A step's error adds up over the
    ringing (found_b94916f10b, in contact throughout on undamped bearings: the recorded run
    lies 1.6e-5 of the force scale off at 1e-10, where reference_simulate's run lies 5.8e-8
    from itself at 1e-12) and grows from landing to landing (5.5e-4 on found_302cde7a53 at
    1e-10, 1.7e-6 on found_1b70095ae3 at 1e-12, where the compiled runs lay 8.7e-4 and 3.9e-8
    from the checked one)."""
    return checked_and_recorded(scene, tolerance)[2]


def forces_agree(run: RecordedRun, reference: RecordedRun, bound: float) -> None:
    """(a): max |F(run) − F(reference)| over F_mesh and the bearing forces <= bound·scale."""
    scale = reference.model.force_scale()
    errors = force_errors(run.outputs, reference.outputs, reference.model)
    worst = max(errors, key=errors.get)
    at = reference.outputs["time"][np.argmax(np.abs(run.outputs[worst]
                                                    - reference.outputs[worst]))]
    assert errors[worst] <= bound, (
        f"compiled vs {reference.name}: {worst} {errors[worst]:.3g} of the force scale "
        f"({scale:.4g} N) off at t = {at:.6g} s, bound {bound:g}")


def outputs_finite(run: RecordedRun, label: str) -> None:
    """(c): every output at every sample is finite."""
    bad = [name for name, values in run.outputs.items() if not np.all(np.isfinite(values))]
    assert not bad, f"{label}: outputs not finite: {bad}"


def no_tension(run: RecordedRun, label: str) -> None:
    """(b): with contact_loss, halves and loaded points never pull and free points are never
    pressed, beyond TENSION_BOUND of the force scale."""
    if not run.model.contact_loss:
        return
    limit = TENSION_BOUND * run.model.force_scale()
    for half in ("left", "right"):
        least = run.outputs[f"F_mesh_{half}"].min()
        assert least >= -limit, f"{label}: F_mesh_{half} pulls: {least:.4g} N"
    for t, (state, contact_set, loaded) in zip(run.outputs["time"], run.samples):
        forces = point_forces(run.model, state, contact_set)
        pulling = forces[loaded != 0.0].min(initial=0.0)
        pressed = forces[loaded == 0.0].max(initial=0.0)
        assert pulling >= -limit, (f"{label}: a loaded point pulls by {-pulling:.4g} N at "
                                   f"t = {t:.6g} s")
        assert pressed <= limit, (f"{label}: a free point is pressed by {pressed:.4g} N at "
                                  f"t = {t:.6g} s (a missed regain)")


def momentum_follows_torques(run: RecordedRun, label: str) -> None:
    """(d): L(t) − L(0) = ∫ (M_motor − M_load/u) dt to MOMENTUM_BOUND of the largest term that
    enters it: a body's I·ω or one torque's impulse. Rounding is relative to the terms, not to
    their sum, which can cancel (a free pair driven apart by equal torques keeps L near zero
    while each body gains N·m·s)."""
    scene, r = run.model.scene, run.outputs
    ratio = scene.parameters["z_wheel"] / scene.parameters["z_pinion"]
    bodies = momentum_terms(scene, r)
    momentum = np.sum(bodies, axis=0)
    motor_impulse, load_impulse = torque_impulses(scene, r["time"])
    change = motor_impulse - load_impulse / ratio
    scale = max(np.abs(term).max() for term in (*bodies, motor_impulse, load_impulse / ratio))
    error = np.abs(momentum - momentum[0] - change).max() / scale
    assert error <= MOMENTUM_BOUND, (f"{label}: angular momentum off the torque impulse by "
                                     f"{error:.3g} of its scale {scale:.4g} N·m·s")


def torque_impulses(scene, times) -> tuple[np.ndarray, np.ndarray]:
    """(∫₀ᵗ M_motor dt, ∫₀ᵗ M_load dt) at each time, the inputs held row by row."""
    schedule = scene.inputs
    starts = np.array(schedule.times)
    ends = np.append(starts[1:], np.inf)
    held = np.clip(np.asarray(times)[:, None] - starts[None, :], 0.0, ends - starts)
    return held @ np.array(schedule.M_motor), held @ np.array(schedule.M_load)


def contact_counts_agree(run: RecordedRun, reference: RecordedRun, bound: float) -> None:
    """(e): n_contacts equal at every sample but those within a hair of a switch, in the
    reference's state there: a point whose force (loaded or not) is within `bound` of the force
    scale of zero (runs that agree on forces to `bound` may disagree on it), or φp within
    PHASE_HAIR of a pitch of its contact set's ends."""
    model = reference.model
    hair = bound * model.force_scale()
    phase_hair = PHASE_HAIR * model.geometry.angular_pitch
    differ = np.flatnonzero(run.outputs["n_contacts"] != reference.outputs["n_contacts"])
    for k in differ:
        state, contact_set, _ = reference.samples[k]
        travelled = state[model.pinion]
        near_phase = min(travelled, contact_set.length - travelled) <= phase_hair
        near_force = np.abs(point_forces(model, state, contact_set)).min() <= hair
        assert near_phase or near_force, (
            f"n_contacts {run.outputs['n_contacts'][k]:g} (compiled) against "
            f"{reference.outputs['n_contacts'][k]:g} (reference) at t = "
            f"{reference.outputs['time'][k]:.6g} s, not at a switch")


def check_scene(scene, tolerance=DEFAULT_TOLERANCE, bound=DEFAULT_BOUND,
                reference_tolerance=REFERENCE_TOLERANCE) -> None:
    """Run the scene on both integrators and apply checks (a)-(e); raises AssertionError (or
    the integrator's exception) naming what failed and by how much. Saves the scene to
    tests/regression/ when hypothesis replays its final failing example (save_if_final)."""
    try:
        runs = _run_both(scene, tolerance, reference_tolerance)
        if runs is None:
            return  # both refused the scene with the chatter message: an accepted outcome
        reference, compiled = runs
        for run in (reference, compiled):
            outputs_finite(run, run.name)
            no_tension(run, run.name)
            momentum_follows_torques(run, run.name)
        forces_agree(compiled, reference, bound)
        contact_counts_agree(compiled, reference, bound)
    except Exception as failure:
        save_if_final(scene, f"compiled at {tolerance:g}, reference at {reference_tolerance:g}: "
                             f"{type(failure).__name__}: {failure}")
        raise


def _run_both(scene, tolerance, reference_tolerance):
    """(force_judge's reference, compiled) runs, or None where both stop with the chatter
    message."""
    outcomes = {}
    for integrator, tol in (("reference", reference_tolerance), ("compiled", tolerance)):
        try:
            outcomes[integrator] = (force_judge(scene, tol) if integrator == "reference"
                                    else run_recorded(scene, integrator, tol))
        except IntegrationError as error:
            if CHATTER_CURE not in str(error):
                raise
            outcomes[integrator] = error
    refused = [name for name, outcome in outcomes.items() if isinstance(outcome, Exception)]
    if len(refused) == 2:
        return None
    assert not refused, f"only the {refused[0]} run chatters: {outcomes[refused[0]]}"
    return outcomes["reference"], outcomes["compiled"]


# --- regression scenes --------------------------------------------------------------------

def scene_toml(scene, header: str) -> str:
    """The scene as a scene file (tests/regression/ style: a comment saying what failed and by
    how much, then [components] if any is left out, [parameters], [experiment], [inputs]);
    herringbone.load_scene reads it back to the same scene."""
    lines = ["# " + line for line in textwrap.wrap(header, 98)]
    if not all(scene.components.values()):
        lines += ["[components]"] + [f"{name} = {_toml_value(on)}"
                                     for name, on in scene.components.items() if not on]
    lines += ["[parameters]"] + [f"{name} = {_toml_value(value)}"
                                 for name, value in scene.given.items()]
    lines += ["[experiment]", f"stop_time = {scene.experiment.stop_time!r}",
              f"output_interval = {scene.experiment.output_interval!r}", "[inputs]"]
    schedule = scene.inputs
    if len(schedule.times) == 1:
        lines += [f"M_motor = {schedule.M_motor[0]!r}", f"M_load = {schedule.M_load[0]!r}"]
    else:
        rows = ", ".join(f"[{t!r}, {m!r}, {ld!r}]" for t, m, ld in
                         zip(schedule.times, schedule.M_motor, schedule.M_load))
        lines.append(f"table = [{rows}]")
    return "\n".join(lines) + "\n"


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    assert math.isfinite(value), value
    return repr(float(value))


def regression_name(scene) -> str:
    """The name its regression file takes: found_<digest>, the digest of the scene itself."""
    return "found_" + hashlib.sha1(scene_toml(scene, "").encode()).hexdigest()[:10]


def save_regression_scene(scene, failure: str, folder: Path = REGRESSION) -> Path:
    """Write the scene with `failure` as its header to folder/<regression_name> .toml (so the
    same scene found twice is one file, its header saying every failure found on it); returns
    the path."""
    path = folder / f"{regression_name(scene)}.toml"
    header = f"Found by tests/integrate/test_properties.py: {failure}"
    if path.exists():
        known = path.read_text(encoding="utf-8").split("\n[", 1)[0]
        if " ".join(failure.split()) not in " ".join(known.replace("#", " ").split()):
            path.write_text(known + "\n" + scene_toml(scene, "Also: " + failure),
                            encoding="utf-8")
        return path
    folder.mkdir(parents=True, exist_ok=True)
    path.write_text(scene_toml(scene, header), encoding="utf-8")
    return path


def save_if_final(scene, failure: str) -> None:
    """Inside hypothesis, save the scene only when it replays its final (shrunk) failing example,
    not at every step of the shrinking; outside hypothesis, do nothing."""
    try:
        from hypothesis.control import current_build_context
        from hypothesis.errors import InvalidArgument
    except ImportError:
        return
    try:
        final = current_build_context().is_final
    except InvalidArgument:  # not inside a hypothesis test
        return
    if final:
        path = save_regression_scene(scene, failure.splitlines()[0])
        print(f"saved the failing scene as {path}")
