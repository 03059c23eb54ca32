"""The one home of the random-scene distribution: what tests/helpers/random_scenes.py
(hypothesis) and
benchmarks/random_scenes.py (seeded, numpy only) both draw from.

`draw_scene_data(sampler)` builds a scene (as the tables of a scene file, for
herringbone.scene_from_dict) from a handful of sampler calls; where the numbers come from is the
sampler's business: `SeededSampler` (numpy's generator, reproducible from one seed) here, a
hypothesis-backed one in tests/helpers/random_scenes.py, so that hypothesis can shrink a
failing scene.

The spans are those of issue 15's independent check: 8-60 teeth, helix 5°-40°, bearings 1e8-1e11
N/m, damping down to exactly zero, speeds 1-2500 rad/s, light loads, torque steps, lead errors of
a few 1e-4 rad, stagger, phase0 and edge ramps. Bodies are steel cylinders of their pitch radius
(partly hollowed), so masses and inertias follow the geometry; shafts and bearings are drawn as
natural frequencies and damping ratios, not raw stiffnesses, so that every scene is a train one
could build. Runs are short (5-20 ms, 100-300 samples) so that one scene costs seconds.

Needs only numpy and herringbone (no hypothesis, nothing else from tests/).
"""
from __future__ import annotations

import math

import numpy as np

import herringbone

STEEL_DENSITY = 7850.0  # kg/m³
# At speeds below this (rad/s) the faces get an edge ramp: with sharp edges the train can chatter
# on a switch, which both integrators refuse with an IntegrationError ("edge_ramp > 0").
LOW_SPEED = 30.0


class SeededSampler:
    """The sampler contract on numpy's default generator: uniform(lo, hi), log_uniform(lo, hi)
    (both within [lo, hi]), integer(lo, hi) (inclusive) and chance(p) (True with probability p).
    The same seed gives the same draws on any machine."""

    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)

    def uniform(self, low: float, high: float) -> float:
        return float(self.rng.uniform(low, high))

    def log_uniform(self, low: float, high: float) -> float:
        return float(math.exp(self.rng.uniform(math.log(low), math.log(high))))

    def integer(self, low: int, high: int) -> int:
        return int(self.rng.integers(low, high + 1))

    def chance(self, probability: float) -> bool:
        return bool(self.rng.uniform() < probability)


def draw_scene_data(s) -> dict:
    """A random scene as the tables of a scene file (components, parameters, experiment, inputs),
    drawn through the sampler `s`; every value lies in its parameter's allowed range."""
    components = {"motor": not s.chance(0.1), "load": not s.chance(0.1),
                  "bearings": not s.chance(0.15)}
    p = _geometry(s)
    p.update(_bodies(s, p, components))
    p.update(_mesh(s, p))
    if components["bearings"]:
        p.update(_bearings(s, p))
    stop_time, output_interval = _experiment(s)
    inputs = _inputs(s, p, stop_time)
    return {"components": components, "parameters": p,
            "experiment": {"stop_time": stop_time, "output_interval": output_interval},
            "inputs": inputs}


def random_scene(seed: int):
    """The scene that seed `seed` draws (herringbone.Scene, named random_<seed>)."""
    return herringbone.scene_from_dict(draw_scene_data(SeededSampler(seed)),
                                       name=f"random_{seed}", source=f"<random scene {seed}>")


def turned_backwards(scene, torques_too: bool):
    """The scene with its initial pinion speed reversed, and where `torques_too` its torques:
    the train running backwards under reversed torques, or braked by the torques as drawn (the
    motor against the motion, the load with it)."""
    scene = scene.with_parameters(w0_pinion=-scene.parameters["w0_pinion"])
    if not torques_too:
        return scene
    inputs = scene.inputs
    return scene.with_inputs(table=[[t, -motor, -load] for t, motor, load
                                    in zip(inputs.times, inputs.M_motor, inputs.M_load)])


def made_exact(scene):
    """The scene with what keeps a contact set from being time-invariant taken away, so that
    the exponential method propagates its segments exactly (docs/exponential-integrator.md):
    the right half as the left (face width, bearings and their places), no lead errors, no
    stagger, and sharp face edges where the train is not slow (below LOW_SPEED the drawn ramps
    stay, sharp edges there chatter: those trains are exact between the ramps)."""
    p = scene.parameters
    exact = {"b_right": p["b_left"], "dbeta_left": 0.0, "dbeta_right": 0.0, "stagger": 0.0}
    if abs(p["w0_pinion"]) >= LOW_SPEED:
        exact["edge_ramp"] = 0.0
    for name in [name for name in p if name.endswith("_left")
                 and name.startswith(("a_", "c_brg_", "h_brg_"))]:
        exact[name.replace("_left", "_right")] = p[name]
    return scene.with_parameters(**exact)


def pitch_radii(p: dict) -> tuple[float, float]:
    """Rp, Rw = z·m_n / (2 cos β)."""
    return tuple(p[z] * p["m_n"] / (2.0 * math.cos(p["beta"])) for z in ("z_pinion", "z_wheel"))


def _geometry(s) -> dict:
    """Teeth, module, helix, face widths (an axial overlap of 1.05-3 per half, so every stream
    always has a point on the face; faces at most 0.25 m unless 5° helices need more)."""
    p = {"z_pinion": s.integer(8, 60), "z_wheel": s.integer(8, 60),
         "m_n": s.log_uniform(0.002, 0.006), "beta": s.uniform(math.radians(5), math.radians(40))}
    axial_pitch = math.pi * p["m_n"] / math.sin(p["beta"])
    width = min(s.uniform(1.05, 3.0) * axial_pitch, max(0.25, 1.05 * axial_pitch))
    p["b_left"] = width
    p["b_right"] = width if s.chance(0.7) else width * s.uniform(0.9, 1.1)
    p["groove"] = s.uniform(0.0, 0.5) * width
    return p


def _bodies(s, p, components) -> dict:
    """Gears as partly hollowed steel cylinders of their pitch radius over the body length;
    motor and load rotors, and the shafts as natural frequencies with damping ratios."""
    length = p["b_left"] + p["b_right"] + p["groove"]
    bodies = {}
    for gear, radius in zip(("pinion", "wheel"), pitch_radii(p)):
        mass = s.uniform(0.4, 1.0) * STEEL_DENSITY * math.pi * radius ** 2 * length
        bodies[f"I_{gear}"] = s.uniform(0.5, 0.7) * mass * radius ** 2
        if components["bearings"]:
            bodies[f"m_{gear}"] = mass
    shafts = [("motor", "in", "pinion", (300.0, 5000.0), 500.0),
              ("load", "out", "wheel", (100.0, 2000.0), 30.0)]
    for component, shaft, gear, frequency, rotor_ratio in shafts:
        if not components[component]:
            continue
        gear_inertia = bodies[f"I_{gear}"]
        bodies[f"I_{component}"] = gear_inertia * s.log_uniform(1.0, rotor_ratio)
        stiffness = gear_inertia * (2 * math.pi * s.log_uniform(*frequency)) ** 2
        bodies[f"C_shaft_{shaft}"] = stiffness
        bodies[f"h_shaft_{shaft}"] = 0.0 if s.chance(0.2) else (
            2.0 * s.log_uniform(0.005, 0.2) * math.sqrt(stiffness * gear_inertia))
    return bodies


def _mesh(s, p) -> dict:
    """Point stiffness, phasing, contact loss, mesh damping (sometimes none), lead errors,
    speed, and an edge ramp (always at low speed, see LOW_SPEED)."""
    mesh = {"c_point": s.log_uniform(1e8, 6e8), "eps_q": s.uniform(0.3, 0.95),
            "stagger": 0.0 if s.chance(0.6) else s.uniform(0.0, 0.99),
            "phase0": 0.0 if s.chance(0.5) else s.uniform(0.0, 0.99),
            "contact_loss": s.chance(0.85),
            "zeta_mesh": 0.0 if s.chance(0.2) else s.log_uniform(0.005, 0.15)}
    for half in ("left", "right"):
        mesh[f"dbeta_{half}"] = 0.0 if s.chance(0.4) else s.uniform(-4e-4, 4e-4)
    mesh["w0_pinion"] = s.log_uniform(1.0, 2500.0)
    sharp = mesh["w0_pinion"] >= LOW_SPEED and s.chance(0.6)
    mesh["edge_ramp"] = 0.0 if sharp else s.log_uniform(2e-4, 2e-3)
    return mesh


def _bearings(s, p) -> dict:
    """Per gear a stiffness of 1e8-1e11 N/m (sides equal or up to 2× apart) and a damping ratio
    of its lateral mode of 0.1-30 %, or no damping at all."""
    bearings = {}
    for gear in ("pinion", "wheel"):
        stiffness = s.log_uniform(1e8, 1e11)
        undamped = s.chance(0.2)
        for side in ("left", "right"):
            c = stiffness if s.chance(0.6) else min(max(stiffness * s.uniform(0.5, 2.0), 1e8), 1e11)
            bearings[f"c_brg_{gear}_{side}"] = c
            bearings[f"h_brg_{gear}_{side}"] = 0.0 if undamped else (
                2.0 * s.log_uniform(1e-3, 0.3) * math.sqrt(c * p[f"m_{gear}"] / 2.0))
    return bearings


def _experiment(s) -> tuple[float, float]:
    """5-20 ms sampled 100-300 times (rounded to the microsecond and its divisions)."""
    samples = s.integer(100, 300)
    stop_time = round(s.uniform(0.005, 0.02), 6)
    return stop_time, stop_time / samples


def _inputs(s, p, stop_time) -> dict:
    """Light loads: a static approach of 0.2-30 µm per point (of four), so that lead errors of
    a few 1e-4 rad can lift points off; the load balances the motor or not (±20 %); sometimes a
    step of the motor torque (to 0.1-3 times) part way."""
    radius_pinion, _ = pitch_radii(p)
    ratio = p["z_wheel"] / p["z_pinion"]
    motor = s.log_uniform(2e-7, 3e-5) * 4.0 * p["c_point"] * radius_pinion
    load = ratio * motor * (1.0 if s.chance(0.6) else s.uniform(0.8, 1.2))
    if not s.chance(0.35):
        return {"M_motor": motor, "M_load": load}
    step_time = round(s.uniform(0.2, 0.7) * stop_time, 7)
    return {"table": [[0.0, motor, load], [step_time, motor * s.uniform(0.1, 3.0), load]]}
