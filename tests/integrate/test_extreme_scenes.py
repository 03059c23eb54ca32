"""Issue 5: the stiff and extreme scenes of models/, each through its FMU against the reference.

Every scene (its header says what it tests and why its values were chosen) is built into its own
FMU, simulated through fmpy at the FMU's default settings (herringbone.fmu.run.simulate_scene_fmu:
the scene's experiment and input torques, communication step = output interval; in a process of
its own, stopped after FMU_WALL_BUDGET, so that a collapsing step size fails the test instead of
hanging it) and by
herringbone.reference_simulate on the same output grid. Each run must complete with finite
outputs, F_mesh and the bearing reactions must agree with the reference within BOUND of the force
scale (GearTrainModel.force_scale(): the static mesh force of the largest input torque, so for
torque_step the static force of the stepped-up torque), and one physics check per scene must hold
for the FMU's run. Runs are short; the 10^6-mesh-period run of long_run.toml and the cost of each
scene belong in the benchmark, here only a 0.02 s slice of it runs.

The measured errors and costs of every scene are printed by benchmarks/extreme_scenes.py and
quoted in README.md. Before the compiled integrator, on scipy's DOP853, stiff_bearings missed
the bound (1.1e-4 at a sample on a contact switch) and contact_loss was 9.3e-2 off (a loss and
regain of one point inside one step went unseen: the point pulled by up to 14 N for 21 us).
"""
import math
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest
from helpers import MODELS, force_errors

import herringbone
from herringbone.analysis.phasing import contact_count, count_intervals, scene_phasing
from herringbone.model.assembly import GearTrainModel

# Of the force scale, at the FMU's default settings (issue 5), for every scene. contact_loss is
# non-smooth (each loss and regain a kink located to the tolerance), but it is held to the same
# bound: the reference converges on it like on the smooth scenes (test_reference.py) and the FMU
# meets it (5.3e-7 measured); a looser bound would hide a missed loss or regain, which lets a
# point pull by c·|approach| for a while (9.3e-2 off, measured on an earlier integrator).
BOUND = 1e-4
LAW_MARGIN = 0.01  # of a mesh period: samples this close to a switch are not read against the law
# Wall time allowed to one FMU run, the start of its process included (about 1.5 s): every run
# here takes under a second (the stiff scene about 0.5 s); a run that needs this much has
# collapsed its step size (issue 5: bounded cost).
FMU_WALL_BUDGET = 30.0


# --- physics checks, each on the FMU's run ------------------------------------------------------

def momentum(scene, r):
    """L = I1·ω1 + Ip·ωp + (Iw·ωw + I4·ω4)/u: the mesh and shafts are internal, so it changes
    only by (M_motor − M_load/u)·t (test_reference.py)."""
    p = scene.parameters
    u = p["z_wheel"] / p["z_pinion"]
    return (p["I_motor"] * r["w_motor"] + p["I_pinion"] * r["w_pinion"]
            + (p["I_wheel"] * r["w_wheel"] + p["I_load"] * r["w_load"]) / u)


def static_mesh_force(scene, time=0.0):
    return scene.inputs.at(time)[0] / GearTrainModel(scene).geometry.radius_pinion


def mesh_phase(scene, r):
    """The mesh phase φp/(2π/zp) of every sample, φp taken as w0·t: the speed swings move the
    pinion off it by less than 0.001 of a mesh period in these scenes (measured against the
    speed of a 2e-6 s grid integrated; integrating the sampled speed of the 1e-4 s grid is worse,
    up to 0.016, since the grid aliases the fast modes)."""
    return scene.parameters["w0_pinion"] * r["time"] / (2 * math.pi / scene.parameters["z_pinion"])


def follows_contact_law(scene, r, require_both_sides=True):
    """n_contacts is the count of the four streams' alternation law (docs/model.md section 8) at
    every sample whose mesh phase is not within LAW_MARGIN of a switch; the run saw the counts
    on both sides of a switch. With an edge ramp r a point counts while −r < z < b + r: the law
    is that of faces 2r wider whose points enter r/p_x of a period earlier."""
    p = scene.parameters
    if p["edge_ramp"] > 0.0:
        shift = p["edge_ramp"] / GearTrainModel(scene).geometry.axial_pitch
        law_scene = scene.with_parameters(b_left=p["b_left"] + 2 * p["edge_ramp"],
                                          b_right=p["b_right"] + 2 * p["edge_ramp"],
                                          phase0=(p["phase0"] + shift) % 1.0, edge_ramp=0.0)
        phasing = scene_phasing(law_scene)
    else:
        phasing = scene_phasing(scene)
    breaks = np.array([start for start, _, _ in count_intervals(phasing.streams)] + [1.0])
    seen = set()
    for t, n, phase in zip(r["time"], r["n_contacts"], mesh_phase(scene, r) % 1.0):
        if np.abs(breaks - phase).min() < LAW_MARGIN:
            continue
        expected = contact_count(phasing.streams, phase)
        assert n == expected, (f"t = {t:g} s (mesh phase {phase:.4f}): {n:g} points in contact, "
                               f"the law {phasing.law} gives {expected}")
        seen.add(expected)
    if require_both_sides:
        assert len(seen) >= 2, f"the run saw only the counts {seen}: no switch was checked"


def bearings_carry_the_mesh_force(scene, r):
    """However stiff the bearings, each gear is a rigid body on two supports: on average its
    bearings take the mesh force (pinion −F_mesh, wheel +F_mesh), and in this symmetric train
    (equal halves, no stagger, no lead error) the lever rule splits it equally. The sample means
    still hold lateral inertia and aliasing of the output grid: 5 % and 1 % (1.6 % and 0.001 %
    measured)."""
    mesh = r["F_mesh"].mean()
    for gear, sign in (("pinion", -1.0), ("wheel", 1.0)):
        left, right = r[f"F_brg_{gear}_left"].mean(), r[f"F_brg_{gear}_right"].mean()
        assert left + right == pytest.approx(sign * mesh, rel=0.05), gear
        assert left == pytest.approx(right, rel=0.01), gear
    follows_contact_law(scene, r)


def undamped_keeps_momentum_and_vibrating(scene, r):
    """Torques balanced: L constant. Nothing dissipates, so the vibration that the switches
    excite must not die out: the mesh force swings at least half as much over the last quarter
    of the run as over the first (an integrator with numerical damping fails this)."""
    L = momentum(scene, r)
    assert np.abs(L - L[0]).max() <= 1e-9 * abs(L[0])
    quarter = len(r["time"]) // 4
    assert np.ptp(r["F_mesh"][-quarter:]) >= 0.5 * np.ptp(r["F_mesh"][1:quarter])


def high_speed_keeps_speed_and_law(scene, r):
    """At 20 000 rpm the count still follows 6-4-6-4 at every sample (no switch lost at 3.3 kHz
    mesh frequency) and, the torques balanced, the speed stays at w0 (1 % on the mean)."""
    follows_contact_law(scene, r)
    assert r["w_pinion"].mean() == pytest.approx(scene.parameters["w0_pinion"], rel=0.01)


def quasi_static(scene, r):
    """At 1 rpm the train is quasi-static: the mesh force stays within 3 % of M_motor/Rp at
    every sample but those within 0.001 of a mesh period (6 ms) of a switch; and the count
    follows the law (4, then 6 from the entry at 0.06 s, 4 after the exit at 0.92 s)."""
    phase = mesh_phase(scene, r) % 1.0
    breaks = np.array([start for start, _, _ in count_intervals(scene_phasing(scene).streams)]
                      + [1.0])
    away = np.abs(breaks[None, :] - phase[:, None]).min(axis=1) > 1e-3
    deviation = np.abs(r["F_mesh"][away] / static_mesh_force(scene) - 1.0)
    assert deviation.max() < 0.03, f"F_mesh off M_motor/Rp by {deviation.max():.3g}"
    follows_contact_law(scene, r)


def accelerates_from_rest(scene, r):
    """From rest under M_motor and M_load < u·M_motor: L grows at exactly M_motor − M_load/u,
    and the pinion speed at (M_motor − M_load/u)/I_total on average (least-squares slope; the
    113 Hz torsional mode that the load's drop at t = 0 excites rides on it: 5 %)."""
    p = scene.parameters
    u = p["z_wheel"] / p["z_pinion"]
    motor, load = scene.inputs.at(0.0)
    surplus = motor - load / u
    inertia = p["I_motor"] + p["I_pinion"] + (p["I_wheel"] + p["I_load"]) / u ** 2
    for name in ("w_motor", "w_pinion", "w_wheel", "w_load"):
        assert r[name][0] == 0.0, name
    L = momentum(scene, r)
    assert np.abs(L - surplus * r["time"]).max() <= 1e-9 * surplus * r["time"][-1]
    slope = np.polyfit(r["time"], r["w_pinion"], 1)[0]
    assert slope == pytest.approx(surplus / inertia, rel=0.05)


def settles_at_ten_times_the_force(scene, r):
    """After the step to 10× both torques the mesh force swings about the new static force:
    its mean over the rest of the run (1.7 periods of the 113 Hz mode) is within 15 % of it
    (1.07 measured), and the step response of the lightly damped train overshoots to nearly
    twice it (1.87 measured)."""
    step = scene.inputs.change_times()[0]
    force = static_mesh_force(scene, step)
    assert force == pytest.approx(10 * static_mesh_force(scene))
    after = r["time"] > step
    assert r["F_mesh"][after].mean() == pytest.approx(force, rel=0.15)
    assert 1.5 * force < r["F_mesh"][after].max() < 2.2 * force


def teeth_separate_and_reengage(scene, r):
    """Points lose contact (fewer than K_eps points of the no-loss law carry load at some
    sample) and regain it (a later sample has K_eps or more); no half ever pulls."""
    least = scene_phasing(scene).k_eps
    below = np.flatnonzero(r["n_contacts"] < least)
    assert below.size, f"n_contacts never drops below the no-loss minimum {least}"
    assert (r["n_contacts"][below[0]:] >= least).any(), "contact never regained"
    for half in ("left", "right"):
        assert r[f"F_mesh_{half}"].min() >= 0.0, half


def integer_overlap_is_constant(scene, r):
    """ε_β = 1: every stream holds exactly one point at all times, so the mesh stiffness and
    the load centre never change (the lever arms jump by b at each switch, symmetrically in the
    two halves): nothing excites the train, which runs in its static equilibrium at 4 points."""
    assert np.all(r["n_contacts"] == 4)
    assert np.abs(r["F_mesh"] / static_mesh_force(scene) - 1.0).max() < 1e-6
    assert np.abs(r["w_pinion"] / scene.parameters["w0_pinion"] - 1.0).max() < 1e-6


def wide_face_law(scene, r):
    """32 or 34 points: the law 34-32-34-32 (its 34-point intervals last 0.038 of a period, one
    sample at most on this grid, so the law is checked where the grid allows and both counts
    must appear)."""
    follows_contact_law(scene, r, require_both_sides=False)
    assert set(r["n_contacts"]) == {32.0, 34.0}
    assert scene_phasing(scene).k_eps == 32


def law_and_momentum(scene, r):
    follows_contact_law(scene, r)
    L = momentum(scene, r) if "w_motor" in r and "w_load" in r else None
    if L is not None:
        assert np.abs(L - L[0]).max() <= 1e-9 * abs(L[0])


# herringbone.fmu.run.simulate_scene_fmu (fmpy, the scene's input torques held over each
# communication step = output interval, default settings), in a process of its own so that a run
# whose cost explodes is stopped after FMU_WALL_BUDGET (fmpy's own timeout is only checked
# between doSteps, and one doStep can take minutes). Writes the outputs and the wall time of the
# simulation alone (not the start of the process) to an .npz file.
RUNNER = """
import sys, time
import numpy as np
import herringbone
from herringbone.fmu.run import simulate_scene_fmu
fmu, scene_file, stop_time, output_interval, out = sys.argv[1:]
scene = herringbone.load_scene(scene_file)
started = time.perf_counter()
result = simulate_scene_fmu(fmu, scene, stop_time=float(stop_time),
                            output_interval=float(output_interval))
np.savez(out, wall=time.perf_counter() - started, **result)
"""


def simulate_through_fmu(fmu, scene, stop_time, output_interval, folder):
    out = folder / f"{scene.name}_fmu.npz"
    try:
        run = subprocess.run([sys.executable, "-c", RUNNER, str(fmu), scene.source,
                              repr(stop_time), repr(output_interval), str(out)],
                             capture_output=True, text=True, timeout=FMU_WALL_BUDGET)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{scene.name}: the FMU did not finish {stop_time:g} s in "
                    f"{FMU_WALL_BUDGET:g} s of wall time (its step size collapsed?)")
    assert run.returncode == 0, f"{scene.name}: the FMU run failed:\n{run.stderr[-2000:]}"
    with np.load(out) as data:
        result = {name: data[name] for name in data.files}
    return result, float(result.pop("wall"))


@dataclass(frozen=True)
class Case:
    check: Callable
    bound: float = BOUND
    stop_time: float | None = None  # None: the scene's own experiment
    output_interval: float | None = None


SCENES = {
    "stiff_bearings": Case(bearings_carry_the_mesh_force),
    "undamped": Case(undamped_keeps_momentum_and_vibrating),
    "high_speed": Case(high_speed_keeps_speed_and_law),
    "low_speed": Case(quasi_static),
    "from_rest": Case(accelerates_from_rest),
    "torque_step": Case(settles_at_ten_times_the_force),
    "contact_loss": Case(teeth_separate_and_reengage),
    "integer_overlap": Case(integer_overlap_is_constant),
    "wide_face": Case(wide_face_law),
    "helix_5deg": Case(law_and_momentum),
    "helix_40deg": Case(law_and_momentum),
    "coinciding_switches": Case(law_and_momentum),
    "long_run": Case(law_and_momentum, stop_time=0.02, output_interval=1e-4),
}


def test_every_scene_of_issue_5_is_shipped():
    shipped = {path.stem for path in MODELS.glob("*.toml")}
    assert set(SCENES) <= shipped, set(SCENES) - shipped


@pytest.mark.parametrize("name", list(SCENES))
def test_scene_through_its_fmu_agrees_with_the_reference(scene_fmu, name, record_property,
                                                         tmp_path):
    case = SCENES[name]
    scene = herringbone.load_scene(MODELS / f"{name}.toml")
    stop_time = case.stop_time or scene.experiment.stop_time
    output_interval = case.output_interval or scene.experiment.output_interval
    fmu = scene_fmu(name)

    result, wall = simulate_through_fmu(fmu, scene, stop_time, output_interval, tmp_path)
    record_property("fmu_wall_s", wall)
    started = time.perf_counter()
    reference = herringbone.reference_simulate(scene, stop_time=stop_time,
                                               output_interval=output_interval)
    record_property("reference_wall_s", time.perf_counter() - started)

    assert result["time"] == pytest.approx(reference["time"], abs=1e-9 * output_interval)
    for run, outputs in (("FMU", result), ("reference", reference)):
        bad = [k for k, v in outputs.items() if not np.all(np.isfinite(v))]
        assert not bad, f"{run}: outputs not finite: {bad}"
    scale = GearTrainModel(scene).force_scale()
    errors = force_errors(result, reference, scene)
    record_property("error", max(errors.values()))
    worst = max(errors, key=errors.get)
    at = reference["time"][np.argmax(np.abs(result[worst] - reference[worst]))]
    assert errors[worst] <= case.bound, (
        f"{name}: max |{worst}(FMU) - {worst}(reference)| = {errors[worst]:.3g} of the force "
        f"scale {scale:.1f} N at t = {at:g} s, bound {case.bound:g}")
    case.check(scene, result)


def test_sharp_edges_at_1_rpm_stop_with_a_message_that_names_the_cure(scene_fmu, tmp_path):
    """With edge_ramp = 0 the points entering at 0.06 s take load at once and throw the pinion
    back across the switch, the motor pushes it forward again, without end. Both integrators
    stop there and say why and what to do, instead of hanging (the FMU: Discard, within
    seconds)."""
    import fmpy

    scene = herringbone.load_scene(MODELS / "low_speed.toml").with_parameters(edge_ramp=0.0,
                                                                             phase0=0.99)
    with pytest.raises(herringbone.integrate.contract.IntegrationError, match="edge_ramp > 0"):
        herringbone.reference_simulate(scene, stop_time=0.1, output_interval=1e-3)
    received = []
    started = time.perf_counter()
    result = fmpy.simulate_fmu(str(scene_fmu("low_speed")), stop_time=0.1, output_interval=1e-3,
                               start_values={"edge_ramp": 0.0, "phase0": 0.99},
                               debug_logging=True,
                               logger=lambda *args: received.append(args[-1].decode()))
    assert time.perf_counter() - started < 20.0
    assert 0.059 <= result["time"][-1] < 0.061  # stopped at the entry, not before
    assert any("chatters" in m and "edge_ramp > 0" in m for m in received), received[-3:]
