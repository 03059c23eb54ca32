"""How hard each resonance rings: the mesh's excitation harmonic by harmonic, and each mode's
answer to it, a first-order estimate that names the mode and the mesh harmonic behind a peak.

Held at the static deflection x_s of the balanced torques (the mesh stiffness averaged over a
mesh period, K̄), the contact points push on the train with a force p(φp) that repeats every
mesh period: the stiffness and lead error of the points in contact change with the pinion angle
(docs/model.md section 3). Its k-th harmonic p̂_k drives every mode at k·f_mesh. Where that meets
mode i's frequency (mass-normalized shape φ_i, ω_i, damping ratio ζ_i = φ_iᵀ·C̄·φ_i/(2ω_i)), the
mode answers with the amplitude 2|φ_iᵀ·p̂_k|/(2ζ_i·ω_i²), and the mesh force with r̄·φ_i times
it (r̄ = Σ c·g over the points, averaged: the mesh force's row). That amplitude of the mesh
force's k-th harmonic, over the static mesh force, is the resonance's *strength*.

It leaves out what the stiffness' change does to the vibration itself, contact lost, and the
modes' coupling through damping. Where a mode's own stiffness swings little with the mesh,
runs of the reference scene settled at its resonances ring at 0.74 to 0.85 of it (0.100 for
the 684 Hz mode at k = 1, where the run's first harmonic is 0.077); where it swings by more
than ROUGH_SWING, the left-out term is of the estimate's order and the estimate is marked
rough (the reference's 10419 Hz mesh mode, 40 %: runs at 0.3 to 4.9 times it).
docs/sweeps.md, "Which resonances ring", has the table; tests/analysis/test_excitation.py
runs part of it.

With sharp face edges a point takes its load at once and the excitation falls off slowly with
k (the reference's harmonics' amplitudes: 12.1, 4.5, 4.3, 10.2, 11.3, 7.9 % of the static
force for k = 1 to 6), so
resonances up to HARMONICS_CONSIDERED are weighed, and those of STRENGTH_LISTED or more listed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.assembly import GearTrainModel, natural_modes, rigid_rotation_mode

# the mesh harmonics whose resonances are weighed (a choice, not a bound: `harmonics=`): the
# reference's sharp-edged mesh pushes with harmonics of 2 to 12 % of its static force at k =
# 1 to 10, 0.07 to 1.5 % at 11 to 14 and 2.5 % again at 15 and 16, where its 10419 Hz mesh
# mode rings at 9 to 13 % from 410 to 470 rad/s, the largest harmonics of the mesh force there
HARMONICS_CONSIDERED = 16
# the least strength a resonance is listed with: its harmonic of the mesh force at 2 % of the
# static force (the reference scene's quasi-static harmonics are 2 to 12 %)
STRENGTH_LISTED = 0.02
# Gauss-Legendre nodes on each contact interval: its terms are cubic in φp, times e^{ikθ}
QUADRATURE_NODES = 24
# a mode whose stiffness swings by more than this share over a mesh period gets a rough
# estimate (Resonance.swing): the reference's modes swing by 0.3 to 3 %, its mesh mode by 40 %
ROUGH_SWING = 0.1


@dataclass(frozen=True)
class Resonance:
    """A speed at which a mesh harmonic meets a natural frequency, and how hard it rings."""

    speed: float  # pinion speed, rad/s
    order: int  # k: k·f_mesh = f_n
    frequency: float  # f_n, Hz
    strength: float  # the mesh force's k-th harmonic there, over the static mesh force
    damping: float  # the mode's damping ratio ζ: the resonance spans about ±ζ of its speed
    # how far the mode's own stiffness swings over a mesh period, a share of its mean: where
    # it is over ROUGH_SWING the term the estimate leaves out is of its order, and the
    # estimate is rough (the reference's 10419 Hz mesh mode: 0.3 to 4.9 times the runs)
    swing: float

    @property
    def rough(self) -> bool:
        """Whether the estimate is rough: the mesh's variation acts on the mode itself."""
        return self.swing > ROUGH_SWING


@dataclass(frozen=True)
class MeshExcitation:
    """The mesh's periodic force at the static deflection, by harmonic (excitation)."""

    force: np.ndarray  # (K + 1, n) complex: p̂_k over the coordinates, N or N·m
    mesh_row: np.ndarray  # (n,): r̄, the mean mesh force's row over the coordinates
    static_force: float  # the static mesh force (N) the strengths are shares of


def excitation(model: GearTrainModel, harmonics: int = HARMONICS_CONSIDERED) -> MeshExcitation:
    """The contact points' force at the mean static deflection, harmonic by harmonic over one
    mesh period (quadrature on each contact interval, where it is a polynomial in φp)."""
    deflection = _mean_static_deflection(model)
    pitch = model.geometry.angular_pitch
    nodes, weights = np.polynomial.legendre.leggauss(QUADRATURE_NODES)
    orders = np.arange(harmonics + 1)
    force = np.zeros((harmonics + 1, model.size), complex)
    mesh_row = np.zeros(model.size)
    for interval in range(len(model.mesh.switch_phases)):
        contact_set = model.mesh.contact_set(0, interval)
        for node, weight in zip(nodes, weights):
            y = np.zeros(model.size)
            y[model.pinion] = 0.5 * (node + 1.0) * contact_set.length
            stiffness, lever_arm, lead_error = model.contact_geometry(y, contact_set)
            rows = model.contact_rows(lever_arm)
            pushed = rows.T @ (stiffness * (rows @ deflection + lead_error))
            share = 0.5 * weight * contact_set.length / pitch
            phase = 2.0 * math.pi * (contact_set.pinion_angle + y[model.pinion]) / pitch
            force += np.exp(-1j * orders * phase)[:, None] * pushed[None, :] * share
            mesh_row += share * (stiffness @ rows)
    static = abs(model.static_mesh_force()) or model.force_scale()
    return MeshExcitation(force, mesh_row, static)


def _mean_static_deflection(model: GearTrainModel) -> np.ndarray:
    """The deflection under the motor torque balanced by the load's (M_load = u·M_motor) and
    the points' mean lead error, every point loaded, the stiffness averaged over a mesh period;
    the least-squares one along the rigid rotation, which no element feels."""
    force = model.balanced_torque_force(model.scene.inputs.M_motor[0])
    return np.linalg.lstsq(model.mean_stiffness_matrix(), force - _mean_lead_force(model),
                           rcond=None)[0]


def _mean_lead_force(model: GearTrainModel) -> np.ndarray:
    """Σ c·e·g over the points, averaged over a mesh period: what the lead errors push with."""
    total = np.zeros(model.size)
    for y, contact_set, share in model.mesh_period_nodes():
        stiffness, lever_arm, lead_error = model.contact_geometry(y, contact_set)
        total += share * (model.contact_rows(lever_arm).T @ (stiffness * lead_error))
    return total / model.geometry.angular_pitch  # what mesh_period_nodes' shares add up to


def resonances(scene, low: float, high: float, least: float = STRENGTH_LISTED,
               harmonics: int = HARMONICS_CONSIDERED) -> list[Resonance]:
    """The resonances k·f_mesh = f_n with pinion speeds in [low, high] (rad/s), k up to
    `harmonics`, of strength `least` or more, by speed.

    Examples
    --------
    >>> import herringbone
    >>> from herringbone.analysis.excitation import resonances
    >>> for r in resonances(herringbone.load_scene("reference"), 420.0, 470.0):
    ...     print(round(r.speed, 1), r.order, round(r.frequency), round(r.strength, 3), r.rough)
    429.6 1 684 0.1 False
    436.4 15 10419 0.127 True
    460.5 6 4397 0.032 False
    467.6 14 10419 0.074 True
    """
    model = GearTrainModel(scene)
    push = excitation(model, harmonics)
    frequencies, shapes, damping = _modes(model)
    swings = _stiffness_swings(model, frequencies, shapes)
    z = scene.parameters["z_pinion"]
    found = []
    for omega, shape, zeta, swing in zip(frequencies, shapes.T, damping, swings):
        # an undamped mode's resonance grows without bound: inf, listed whatever `least` is
        answer = (abs(push.mesh_row @ shape) / (zeta * omega**2 * push.static_force)
                  if zeta > 0.0 else math.inf)
        for k in range(1, harmonics + 1):
            speed = omega / (k * z)
            strength = answer * abs(shape @ push.force[k])
            if low <= speed <= high and strength >= least:
                found.append(Resonance(float(speed), k, float(omega / (2.0 * math.pi)),
                                       float(strength), float(zeta), float(swing)))
    return sorted(found, key=lambda r: r.speed)


def _stiffness_swings(model: GearTrainModel, omega: np.ndarray, shapes: np.ndarray):
    """For each mode (ω rad/s, its mass-normalized shape a column of `shapes`), how far its
    stiffness φᵀ·K(φp)·φ swings over a mesh period (at the period's quadrature nodes), a
    share of its mean ω²."""
    modal = np.array([np.einsum("ji,jk,ki->i", shapes, model.stiffness_matrix(y, contact_set),
                                shapes) for y, contact_set, _ in model.mesh_period_nodes()])
    return (modal.max(axis=0) - modal.min(axis=0)) / omega**2


def _modes(model: GearTrainModel):
    """The elastic modes at the mean stiffness: (ω rad/s, mass-normalized shapes as columns,
    damping ratios φᵀ·C̄·φ/(2ω)), the rigid rotation left out."""
    frequencies, shapes, _ = natural_modes(model.scene)
    rigid = rigid_rotation_mode(shapes, model.mass, model.rigid_rotation)
    keep = [i for i in range(len(frequencies)) if i != rigid and frequencies[i] > 0.0]
    omega = 2.0 * math.pi * frequencies[keep]
    shapes = shapes[:, keep]
    damping = np.einsum("ji,jk,ki->i", shapes, model.mean_damping_matrix(), shapes) / (2 * omega)
    return omega, shapes, damping


def strongest(scene, high: float, count: int) -> list[Resonance]:
    """The `count` strongest resonances at pinion speeds up to `high` (rad/s), strongest
    first."""
    return sorted(resonances(scene, 0.0, high), key=lambda r: -r.strength)[:count]


def resonance_lines(found: list[Resonance], name_of=None) -> list[str]:
    """One line a resonance, "  4397 rpm (460.5 rad/s)  k = 6  f_n = 4397.17 Hz  zeta 0.080
    3.2 %", said rough where it is (Resonance.rough); `name_of(f_n)`, where given, names the
    mode after it."""
    from ..model.parameters import RPM_PER_RAD_S

    return [f"  {r.speed * RPM_PER_RAD_S:8.0f} rpm ({r.speed:8.1f} rad/s)  k = {r.order:<2d}  "
            f"f_n = {r.frequency:9.2f} Hz  zeta {r.damping:.3f}  "
            + (f"{100 * r.strength:5.1f} %" if math.isfinite(r.strength)
               else "unbounded: an undamped mode")
            # a harmonic beyond the static force would pull the teeth: they part first
            + (" (the teeth part: the estimate holds no more)" if r.strength >= 1.0 else "")
            + (f" (rough: the mode's stiffness swings {100 * r.swing:.0f} % with the mesh)"
               if r.rough else "")
            + (f"  {name_of(r.frequency)}" if name_of else "") for r in found]
