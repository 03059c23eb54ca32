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

It leaves out what the stiffness' change does to the vibration itself (a term of second order),
contact lost, and the modes' coupling through damping. On the reference scene the runs settled
at six resonance speeds ring at 0.74 to 0.85 of it (docs/sweeps.md, "Which resonances ring";
tests/analysis/test_excitation.py): 0.100 for the 684 Hz mode at k = 1 where the run's first
harmonic is 0.077, 0.032 for the 4397 Hz mode at k = 6 (0.023).

With sharp face edges a point takes its load at once and the excitation falls off slowly with
k (the reference's: 6.1, 2.2, 2.1, 5.1, 5.7, 4.0 % of the static force for k = 1 to 6), so
resonances up to HARMONICS_CONSIDERED are weighed, and those of STRENGTH_LISTED or more listed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..model.assembly import GearTrainModel, rigid_rotation_mode

# the mesh harmonics whose resonances are weighed (a choice, not a bound: `harmonics=`): the
# reference's sharp-edged mesh pushes with 1 to 6 % of its static force at k = 1 to 10, 0.04
# to 0.8 % at 11 to 14 and 1.3 % again at 15 and 16
HARMONICS_CONSIDERED = 12
# the least strength a resonance is listed with: its harmonic of the mesh force at 2 % of the
# static force (the reference scene's quasi-static harmonics are 2 to 6 %)
STRENGTH_LISTED = 0.02
# Gauss-Legendre nodes on each contact interval: its terms are cubic in φp, times e^{ikθ}
QUADRATURE_NODES = 24


@dataclass(frozen=True)
class Resonance:
    """A speed at which a mesh harmonic meets a natural frequency, and how hard it rings."""

    speed: float  # pinion speed, rad/s
    order: int  # k: k·f_mesh = f_n
    frequency: float  # f_n, Hz
    strength: float  # the mesh force's k-th harmonic there, over the static mesh force


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
    pitch = sum(model.mesh.contact_set(0, i).length
                for i in range(len(model.mesh.switch_phases)))
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
            rows = (model.contact_row_base[None, :]
                    + lever_arm[:, None] * model.contact_row_tilt[None, :])
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
    torque = model.scene.inputs.M_motor[0]
    force = torque * (model.motor_torque_row - model.geometry.ratio * model.load_torque_row)
    return np.linalg.lstsq(model.mean_stiffness_matrix(), force - _mean_lead_force(model),
                           rcond=None)[0]


def _mean_lead_force(model: GearTrainModel) -> np.ndarray:
    """Σ c·e·g over the points, averaged over a mesh period: what the lead errors push with."""
    total = np.zeros(model.size)
    for y, contact_set, share in model.mesh_period_nodes():
        stiffness, lever_arm, lead_error = model.contact_geometry(y, contact_set)
        rows = (model.contact_row_base[None, :]
                + lever_arm[:, None] * model.contact_row_tilt[None, :])
        total += share * (rows.T @ (stiffness * lead_error))
    pitch = sum(share for _, _, share in model.mesh_period_nodes())
    return total / pitch


def resonances(scene, low: float, high: float, least: float = STRENGTH_LISTED,
               harmonics: int = HARMONICS_CONSIDERED) -> list[Resonance]:
    """The resonances k·f_mesh = f_n with pinion speeds in [low, high] (rad/s), k up to
    `harmonics`, of strength `least` or more, by speed.

    Examples
    --------
    >>> import herringbone
    >>> from herringbone.analysis.excitation import resonances
    >>> [(round(r.speed, 1), r.order, round(r.frequency), round(r.strength, 3))
    ...  for r in resonances(herringbone.load_scene("reference"), 400.0, 560.0)]
    [(429.6, 1, 684, 0.1), (460.5, 6, 4397, 0.032), (552.6, 5, 4397, 0.045)]
    """
    model = GearTrainModel(scene)
    push = excitation(model, harmonics)
    frequencies, shapes, damping = _modes(model)
    z = scene.parameters["z_pinion"]
    found = []
    for omega, shape, zeta in zip(frequencies, shapes.T, damping):
        # an undamped mode's resonance grows without bound: inf, listed whatever `least` is
        answer = (abs(push.mesh_row @ shape) / (zeta * omega**2 * push.static_force)
                  if zeta > 0.0 else math.inf)
        for k in range(1, harmonics + 1):
            speed = omega / (k * z)
            strength = answer * abs(shape @ push.force[k])
            if low <= speed <= high and strength >= least:
                found.append(Resonance(speed, k, omega / (2.0 * math.pi), float(strength)))
    return sorted(found, key=lambda r: r.speed)


def _modes(model: GearTrainModel):
    """The elastic modes at the mean stiffness: (ω rad/s, mass-normalized shapes as columns,
    damping ratios φᵀ·C̄·φ/(2ω)), the rigid rotation left out."""
    eigenvalues, shapes = scipy.linalg.eigh(model.mean_stiffness_matrix(), np.diag(model.mass))
    rigid = rigid_rotation_mode(shapes, model.mass, model.rigid_rotation)
    keep = [i for i in range(len(eigenvalues)) if i != rigid and eigenvalues[i] > 0.0]
    omega = np.sqrt(eigenvalues[keep])
    shapes = shapes[:, keep]
    damping = np.einsum("ji,jk,ki->i", shapes, model.mean_damping_matrix(), shapes) / (2 * omega)
    return omega, shapes, damping


def strongest(scene, high: float, count: int) -> list[Resonance]:
    """The `count` strongest resonances at pinion speeds up to `high` (rad/s), strongest
    first."""
    return sorted(resonances(scene, 0.0, high), key=lambda r: -r.strength)[:count]


def resonance_lines(found: list[Resonance], name_of=None) -> list[str]:
    """One line a resonance, "  4397 rpm (460.5 rad/s)  k = 6  f_n = 4397.17 Hz  3.2 %";
    `name_of(f_n)`, where given, names the mode after it."""
    from ..model.parameters import RPM_PER_RAD_S

    return [f"  {r.speed * RPM_PER_RAD_S:8.0f} rpm ({r.speed:8.1f} rad/s)  k = {r.order:<2d}  "
            f"f_n = {r.frequency:9.2f} Hz  "
            + (f"{100 * r.strength:5.1f} %" if math.isfinite(r.strength)
               else "unbounded: an undamped mode")
            # a harmonic beyond the static force would pull the teeth: they part first
            + (" (the teeth part: the estimate holds no more)" if r.strength >= 1.0 else "")
            + (f"  {name_of(r.frequency)}" if name_of else "") for r in found]
