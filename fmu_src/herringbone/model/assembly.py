"""The gear train assembled from its elements (docs/model.md sections 1 and 4-7).

Every elastic element k (shaft, bearing, contact point) has a deformation δ_k = g_k·q + e_k with
a row g_k over the coordinates q, and a force F_k = c_k·δ_k + h_k·δ̇_k; then
M·q̈ = f_ext − Σ g_k·F_k. A scene without motor, load or bearings has fewer coordinates.

Relative coordinates (docs/model.md section 10). The state holds, instead of q,
    y_i = q_i − r_i·φp  (i ≠ pinion),   y_pinion = φp − φ_start
where r is the rigid rotation (1 on the motor and pinion angles, 1/u on the wheel and load
angles, 0 on tilts and displacements) and φ_start is where the current contact set begins, so
every entry stays small however far the train has turned. No element deforms under the rigid
rotation (g·r = 0), so δ = g̃·y and δ̇ = g̃·ẏ, g̃ being g with its pinion entry zeroed.

Contact points carry rows g = g_base + ζ·g_tilt whose lever arm ζ moves with φp; as in the
article the rows are taken as given at each instant (no ∂g/∂φp terms), and the damping acts on
the rate g·q̇ of the bodies' motion. (docs/model.md does not say whether δ̇ includes the slide of the
point along a lead error, ė = Δβ·ż; taking g·q̇ keeps a steadily running train free of a
spurious drag force.)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from . import equations
from .geometry import GearGeometry
from .mesh import ContactSet, Mesh
from .parameters import PARAMETERS, outputs_of

ALL_COORDINATES = ("phi_motor", "phi_pinion", "psi_pinion", "x_pinion",
                   "phi_wheel", "psi_wheel", "x_wheel", "phi_load")
COMPONENT_COORDINATES = {"motor": ("phi_motor",), "load": ("phi_load",),
                         "bearings": ("psi_pinion", "x_pinion", "psi_wheel", "x_wheel")}


@dataclass(frozen=True)
class ElasticElement:
    """A shaft or bearing: output name, row g, stiffness and damping."""

    name: str
    row: np.ndarray
    stiffness: float
    damping: float


class GearTrainModel:
    """The assembled equations of motion of a scene's gear train."""

    def __init__(self, scene):
        p = scene.parameters
        self.scene = scene
        self.geometry = GearGeometry.from_parameters(p)
        self.mesh = Mesh(p)
        self._place_coordinates(scene)
        self._assemble_rows(p)
        self._damp_the_mesh(p)
        self.system = self._compiled_system()
        self.packed_system = equations.pack_system(self.system)
        self.output_names = output_names(scene)
        self._mean_stiffness = None
        self.output_layout = self._output_layout()
        self.output_layout_size = (equations.FIRST_ELEMENT_FORCE + len(self.elements)
                                   + self.size)

    def _place_coordinates(self, scene) -> None:
        """The scene's coordinates, their masses, the rigid rotation and the torque rows."""
        p, g = scene.parameters, self.geometry
        left_out = {c for comp, coords in COMPONENT_COORDINATES.items()
                    if not scene.has(comp) for c in coords}
        self.coordinates = [c for c in ALL_COORDINATES if c not in left_out]
        self.size = len(self.coordinates)
        self.pinion = self.coordinates.index("phi_pinion")
        self.wheel = self.coordinates.index("phi_wheel")

        inertia = {"phi_motor": "I_motor", "phi_pinion": "I_pinion", "psi_pinion": "J_pinion",
                   "x_pinion": "m_pinion", "phi_wheel": "I_wheel", "psi_wheel": "J_wheel",
                   "x_wheel": "m_wheel", "phi_load": "I_load"}
        self.mass = np.array([p[inertia[c]] for c in self.coordinates])
        self.rigid_rotation = np.array([1.0 if c in ("phi_motor", "phi_pinion") else
                                        1.0 / g.ratio if c in ("phi_wheel", "phi_load") else 0.0
                                        for c in self.coordinates])
        # ÿ = q̈ − (r − e_pinion)·φ̈p turns accelerations of q into those of the state
        self._relative_offset = self.rigid_rotation.copy()
        self._relative_offset[self.pinion] = 0.0
        self.motor_torque_row = self.unit("phi_motor" if scene.has("motor") else "phi_pinion")
        self.load_torque_row = self.unit("phi_load" if scene.has("load") else "phi_wheel")

    def _assemble_rows(self, p) -> None:
        """The rows g of the shafts, bearings and contact, in absolute and relative
        coordinates; none may move under the rigid rotation."""
        g = self.geometry
        self.elements = self._shafts_and_bearings(p)
        self.contact_row_base = (g.radius_pinion * self.unit("phi_pinion")
                                 - g.radius_wheel * self.unit("phi_wheel")
                                 + self.unit("x_pinion") - self.unit("x_wheel"))
        self.contact_row_tilt = self.unit("psi_pinion") - self.unit("psi_wheel")
        for row in [e.row for e in self.elements] + [self.contact_row_base]:
            assert abs(row @ self.rigid_rotation) <= 1e-12 * np.abs(row).max()
        self.element_rows = np.array([e.row for e in self.elements]).reshape(-1, self.size)
        self.element_stiffness = np.array([e.stiffness for e in self.elements])
        self.element_damping = np.array([e.damping for e in self.elements])
        self._element_rows_relative = self.relative(self.element_rows)
        self._contact_base_relative = self.relative(self.contact_row_base)
        self._contact_tilt_relative = self.relative(self.contact_row_tilt)

    def _damp_the_mesh(self, p) -> None:
        """The mesh damping factor η (h = η·c, from zeta_mesh at the mean mesh frequency) and
        the approach rows it enters."""
        g = self.geometry
        equivalent_mass = 1.0 / (g.radius_pinion ** 2 / p["I_pinion"]
                                 + g.radius_wheel ** 2 / p["I_wheel"])
        mesh_frequency = math.sqrt(self.mesh.mean_stiffness() / equivalent_mass)
        self.mesh_damping_factor = 2.0 * p["zeta_mesh"] / mesh_frequency  # η: h = η·c
        self.contact_loss = p["contact_loss"]
        # g̃ of a point's base and tilt parts acting on [y, ẏ] as y + η·ẏ (point_approaches)
        self._approach_rows = np.array([
            np.concatenate([row, self.mesh_damping_factor * row])
            for row in (self._contact_base_relative, self._contact_tilt_relative)])
        self.axial_travel_per_radian = g.axial_speed_per_radian

    def _compiled_system(self) -> equations.System:
        """The equations' constants as the compiled kernels read them."""
        g = self.geometry
        # ÿ = P·(generalized force): q̈ = M⁻¹·f, then ÿ = q̈ − r̃·φ̈p
        to_relative = ((np.eye(self.size) - np.outer(self._relative_offset,
                                                    self.unit("phi_pinion"))) / self.mass)
        elastic = -to_relative @ (self.element_rows.T * self.element_stiffness) \
            @ self._element_rows_relative
        damping = -to_relative @ (self.element_rows.T * self.element_damping) \
            @ self._element_rows_relative
        coupled = np.nonzero((elastic != 0.0) | (damping != 0.0))
        return equations.System(
            pinion=self.pinion, wheel=self.wheel, mass=self.mass,
            rigid_rotation=self.rigid_rotation,
            element_rows_relative=self._element_rows_relative,
            element_stiffness=self.element_stiffness, element_damping=self.element_damping,
            motor_acceleration=to_relative @ self.motor_torque_row,
            load_acceleration=to_relative @ self.load_torque_row,
            coupling_row=coupled[0], coupling_column=coupled[1],
            elastic_acceleration=elastic[coupled], damping_acceleration=damping[coupled],
            contact_base_acceleration=to_relative @ self.contact_row_base,
            contact_tilt_acceleration=to_relative @ self.contact_row_tilt,
            contact_row_base_relative=self._contact_base_relative,
            contact_row_tilt_relative=self._contact_tilt_relative,
            mesh_damping_factor=float(self.mesh_damping_factor),
            axial_travel_per_radian=float(g.axial_speed_per_radian),
            radius_wheel=float(g.radius_wheel), contact_loss=bool(self.contact_loss))

    def _output_layout(self) -> list[tuple[str, int]]:
        """Where each output of the scene sits in the vector equations.outputs fills, as
        parameters.OUTPUTS declares it: the entry of its equations constant (K_MESH, ...), the
        rate of its coordinate (after the element forces), or its element's force."""
        first_speed = equations.FIRST_ELEMENT_FORCE + len(self.elements)
        elements = [e.name for e in self.elements]
        layout = []
        for output in outputs_of(self.scene.components).values():
            if output.slot is not None:
                entry = getattr(equations, output.slot)
            elif output.rate_of is not None:
                entry = first_speed + self.coordinates.index(output.rate_of)
            else:
                entry = equations.FIRST_ELEMENT_FORCE + elements.index(output.name)
            layout.append((output.name, entry))
        return layout

    def unit(self, coordinate: str) -> np.ndarray:
        """The unit row of a coordinate (zero if the scene leaves the coordinate out)."""
        row = np.zeros(self.size)
        if coordinate in self.coordinates:
            row[self.coordinates.index(coordinate)] = 1.0
        return row

    def relative(self, rows: np.ndarray) -> np.ndarray:
        """g̃: rows acting on the relative coordinates (the pinion entry zeroed)."""
        rows = np.array(rows, dtype=float)
        rows[..., self.pinion] = 0.0
        return rows

    def _shafts_and_bearings(self, p) -> list[ElasticElement]:
        elements = []
        if self.scene.has("motor"):
            elements.append(ElasticElement("T_shaft_in", self.unit("phi_motor")
                                           - self.unit("phi_pinion"),
                                           p["C_shaft_in"], p["h_shaft_in"]))
        if self.scene.has("load"):
            elements.append(ElasticElement("T_shaft_out", self.unit("phi_wheel")
                                           - self.unit("phi_load"),
                                           p["C_shaft_out"], p["h_shaft_out"]))
        if self.scene.has("bearings"):
            for gear in ("pinion", "wheel"):
                for side in ("left", "right"):
                    row = (self.unit(f"x_{gear}") + self.geometry.bearing_position(side)
                           * self.unit(f"psi_{gear}"))
                    elements.append(ElasticElement(f"F_brg_{gear}_{side}", row,
                                                   p[f"c_brg_{gear}_{side}"],
                                                   p[f"h_brg_{gear}_{side}"]))
        return elements

    # --- the equations (compiled: equations.py) ---------------------------------------------

    def contact_geometry(self, y: np.ndarray, contact_set: ContactSet):
        """Stiffness, lever arm and lead error of each point at the state's pinion angle."""
        return equations.point_geometry(self.system, contact_set.table, len(contact_set),
                                        float(y[self.pinion]))

    def point_approaches(self, state, contact_set: ContactSet) -> np.ndarray:
        """δ + η·δ̇ of every point of the set (its load per unit stiffness): at one
        state (a vector; gives one value a point) or at each column of a 2-D array of states
        (gives a row a point). The compiled equations.approaches computes the same.

        With ζ = ζ0 + ζ1·s and e = e0 + e1·s linear in the axial travel s = v·y_pinion, the
        approach is (g_b + ζ·g_t)·(y + η·ẏ) + e = B + e0 + ζ0·T + s·(ζ1·T + e1), where
        B, T = g_b·(y + η·ẏ), g_t·(y + η·ẏ)."""
        states = state if state.ndim == 2 else state[:, None]
        base, tilt = self._approach_rows @ states
        travel = self.axial_travel_per_radian * states[self.pinion]
        approach = np.empty((len(contact_set), states.shape[1]))
        equations.approaches_from_sums(contact_set.table, len(contact_set), base, tilt, travel,
                                       approach)
        return approach if state.ndim == 2 else approach[:, 0]

    def point_approach(self, state, contact_set: ContactSet, point: int) -> float:
        """point_approaches of point `point` alone at one state (a vector), to the bit: a
        root search reads one point many times."""
        return float(self.point_approaches(state, contact_set)[point])

    def point_forces(self, state, contact_set: ContactSet, loaded) -> np.ndarray:
        """The force (N) each point of the set carries at a state, c·(δ + η·δ̇) where it is
        loaded and 0 where it is not, in numpy (shapes as point_approaches). With contact loss
        a correct run never shows a negative one."""
        y = state[:self.size]
        travel = self.axial_travel_per_radian * y[self.pinion]
        stiffness = contact_set.table[equations.STIFFNESS0][:, None] + np.multiply.outer(
            contact_set.table[equations.STIFFNESS_SLOPE], travel).reshape(len(contact_set), -1)
        loaded = np.asarray(loaded, dtype=float)
        forces = (loaded[:, None] * stiffness) * self.point_approaches(
            state if state.ndim == 2 else state[:, None], contact_set)
        return forces if state.ndim == 2 else forces[:, 0]

    def derivative(self, state, contact_set, loaded, motor_torque, load_torque):
        """d(state)/dt for state = [y, ẏ] with the contact set and loaded points held fixed."""
        return self.rate_function(contact_set, loaded, motor_torque, load_torque)(0.0, state)

    def rate_function(self, contact_set, loaded, motor_torque, load_torque):
        """f(t, state) = d(state)/dt with the contact set, loaded points and torques bound, as
        scipy's solvers call it: its arguments are converted once here, not at every stage."""
        floats, ints = self.packed_system
        table, count = contact_set.table, len(contact_set)
        loaded = np.asarray(loaded, dtype=float)
        motor_torque, load_torque = float(motor_torque), float(load_torque)
        kernel = equations.packed_derivative

        def rate(_time, state):
            out = np.empty_like(state)
            kernel(floats, ints, table, count, loaded, motor_torque, load_torque, state, out)
            return out
        return rate

    def outputs(self, state, contact_set, loaded) -> dict[str, float]:
        """The outputs of docs/model.md section 7 at a state; `loaded` is 1 for the points that
        carry load (all points of the set where contact cannot be lost)."""
        return self.named_outputs(self.output_vector(state, contact_set, loaded))

    def named_outputs(self, values) -> dict[str, float]:
        """The vector `output_vector` gives, by output name."""
        return {name: float(values[i]) for name, i in self.output_layout}

    def output_vector(self, state, contact_set, loaded) -> np.ndarray:
        """The outputs as equations.outputs lays them out (`output_layout` names them)."""
        values = np.empty(self.output_layout_size)
        equations.outputs(self.system, contact_set.table, len(contact_set), loaded, state, values)
        return values

    # --- stiffness, statics, modes ------------------------------------------------------

    def contact_rows(self, lever_arm, relative=False) -> np.ndarray:
        """Each contact point's row g = g_base + ζ·g_tilt (docs/model.md section 5), one a
        point of the lever arms ζ given, over q (`relative`: over the relative coordinates)."""
        base, tilt = ((self._contact_base_relative, self._contact_tilt_relative) if relative
                      else (self.contact_row_base, self.contact_row_tilt))
        return base[None, :] + lever_arm[:, None] * tilt[None, :]

    def balanced_torque_force(self, motor_torque: float) -> np.ndarray:
        """The generalized force of the motor torque (N·m) balanced by M_load = u·M_motor."""
        return motor_torque * (self.motor_torque_row - self.geometry.ratio * self.load_torque_row)

    def stiffness_matrix(self, y, contact_set, loaded=None, relative=False) -> np.ndarray:
        """K = Σ c·g·gᵀ of shafts, bearings and (loaded) contact points at the state's angle."""
        stiffness, lever_arm, _ = self.contact_geometry(y, contact_set)
        if loaded is not None:
            stiffness = stiffness * loaded
        rows = self._element_rows_relative if relative else self.element_rows
        contact_rows = self.contact_rows(lever_arm, relative)
        return (self._element_matrix(self.element_stiffness, rows)
                + (contact_rows.T * stiffness) @ contact_rows)

    def damping_matrix(self, y, contact_set) -> np.ndarray:
        """C = Σ h·g·gᵀ of the shafts and bearings + η·Σ c·g·gᵀ of the contact points (all
        loaded) over q, at the state's pinion angle, like stiffness_matrix."""
        contacts = (self.stiffness_matrix(y, contact_set)
                    - self._element_matrix(self.element_stiffness))
        return (self._element_matrix(self.element_damping)
                + self.mesh_damping_factor * contacts)

    def static_deflection(self, y, contact_set, motor_torque) -> np.ndarray:
        """Relative coordinates of the static equilibrium under M_motor balanced by
        M_load = u·M_motor, every point of the set loaded (docs/model.md section 6). A set
        without a point (a face too narrow for its streams' phasing: K_ε = 0) holds the two
        sides of the train apart, with no equilibrium under a torque: the train is then taken
        undeflected, as a torque-free one."""
        if len(contact_set) == 0:
            deflection = np.zeros(self.size)
            deflection[self.pinion] = y[self.pinion]
            return deflection
        stiffness, lever_arm, lead_error = self.contact_geometry(y, contact_set)
        force = (self.balanced_torque_force(motor_torque)
                 - self.contact_rows(lever_arm, relative=True).T @ (stiffness * lead_error))
        elastic = [i for i in range(self.size) if i != self.pinion]
        stiffness_matrix = self.stiffness_matrix(y, contact_set, relative=True)
        deflection = np.zeros(self.size)
        try:
            deflection[elastic] = np.linalg.solve(stiffness_matrix[np.ix_(elastic, elastic)],
                                                  force[elastic])
        except np.linalg.LinAlgError:
            raise ValueError(self._unsolvable_stiffness()) from None
        deflection[self.pinion] = y[self.pinion]
        return deflection

    def _unsolvable_stiffness(self) -> str:
        """Why the static deflection has no solution: the stiffness matrix is singular in double
        precision, which stiffnesses far apart make it; the message names the extremes."""
        given = {name: value for name, value in self.scene.parameters.items()
                 if PARAMETERS[name].unit == "N/m" and value > 0.0}
        low, high = (pick(given, key=lambda name: given[name]) for pick in (min, max))
        return (f"the static deflection has no solution: the train's stiffness matrix is "
                f"singular in double precision, its stiffnesses from {low} = {given[low]:g} N/m "
                f"to {high} = {given[high]:g} N/m, {given[high] / given[low]:.2g} times it; "
                "allowed: stiffnesses that double precision sets beside each other (a ratio "
                "far under 1/ε = 4.5e15)")

    def mean_stiffness_matrix(self) -> np.ndarray:
        """K averaged over one mesh period (Gauss-Legendre on each contact interval: the
        contact terms are cubic in φp). Computed once per model: scales, modes and the choice
        of integrator all read it."""
        if self._mean_stiffness is None:
            total = np.zeros((self.size, self.size))
            for y, contact_set, share in self.mesh_period_nodes():
                total += share * self.stiffness_matrix(y, contact_set)
            self._mean_stiffness = total / self.geometry.angular_pitch
        return self._mean_stiffness.copy()

    def mesh_period_nodes(self) -> list[tuple[np.ndarray, ContactSet, float]]:
        """The nodes of an average over one mesh period: (y at rest with φp at the node, the
        node's contact set, its share in rad), Gauss-Legendre with 3 nodes on each contact
        interval (the contact terms are cubic in φp). The shares add up to the angular pitch:
        a sum over the nodes, over the pitch, is the average."""
        nodes, weights = np.polynomial.legendre.leggauss(3)
        result = []
        for interval in range(len(self.mesh.switch_phases)):
            contact_set = self.mesh.contact_set(0, interval)
            for node, weight in zip(nodes, weights):
                y = np.zeros(self.size)
                y[self.pinion] = 0.5 * (node + 1.0) * contact_set.length
                result.append((y, contact_set, 0.5 * weight * contact_set.length))
        return result

    def mean_damping_matrix(self) -> np.ndarray:
        """C = Σ h·g·gᵀ of shafts and bearings plus η·(the contact points' mean stiffness)."""
        return self._element_matrix(self.element_damping) + self.mesh_damping_factor * (
            self.mean_stiffness_matrix() - self._element_matrix(self.element_stiffness))

    def eigenvalues(self, stiffness=None, damping=None) -> np.ndarray:
        """The eigenvalues of the linearized train, 1/s: −ζω ± iω√(1−ζ²) of each mode, at the
        mean stiffness and damping over a mesh period, every point loaded, or at the given
        stiffness and damping matrices over q."""
        stiffness = self.mean_stiffness_matrix() if stiffness is None else stiffness
        damping = self.mean_damping_matrix() if damping is None else damping
        inverse_mass = 1.0 / self.mass[:, None]
        state_matrix = np.block([[np.zeros((self.size, self.size)), np.eye(self.size)],
                                 [-inverse_mass * stiffness, -inverse_mass * damping]])
        return np.linalg.eigvals(state_matrix)

    def free_flight_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """K and C over q of the shafts and bearings alone: the train with no point in
        contact, as it flies between a lift-off and a landing."""
        return (self._element_matrix(self.element_stiffness),
                self._element_matrix(self.element_damping))

    def _element_matrix(self, values, rows=None) -> np.ndarray:
        """Σ value·g·gᵀ over the shafts and bearings (rows g, or the given ones)."""
        rows = self.element_rows if rows is None else rows
        return (rows.T * values) @ rows

    def static_mesh_force(self) -> float:
        """M_motor/Rp at t = 0, N: the mesh force of the train at rest under its motor
        torque."""
        return self.geometry.mesh_force(self.scene.inputs.M_motor[0])

    def force_scale(self) -> float:
        """The static mesh force of the largest input torque: the scale errors are judged on.
        A train without torque is judged on the force of a 1 µm approach of one point."""
        torques = self.scene.inputs
        scale = max(max(self.geometry.mesh_force(abs(m)) for m in torques.M_motor),
                    max(self.geometry.mesh_force(abs(m), "wheel") for m in torques.M_load))
        return scale if scale > 0.0 else self.mesh.c_point * 1e-6

    def state_scales(self) -> np.ndarray:
        """For each state entry, the change that moves a force by the force scale: an error
        tolerance `tol` on forces becomes the absolute tolerance `tol·state_scales()`.

        A deflection y_i changes the generalized elastic force by K_ii·y_i; a rate by its
        mode's ω_i = sqrt(K_ii/M_ii) times that. The pinion angle only moves the contact
        points; a phase error shifts a switch by δφ/ω_p, worth F·(ω_max/ω_p)·δφ, so it is
        held a thousand times tighter (in radians) than the force."""
        stiffness = np.diag(self.mean_stiffness_matrix())
        angular_frequency = np.sqrt(stiffness / self.mass)
        highest = angular_frequency.max()
        force = self.force_scale()
        deflection = np.where(stiffness > 0.0, force / np.where(stiffness > 0.0, stiffness, 1.0),
                              1.0)
        deflection[self.pinion] = 1e-3
        rate = deflection * np.where(stiffness > 0.0, angular_frequency, highest)
        rate[self.pinion] = 1e-3 * highest
        return np.concatenate([deflection, rate])


def output_names(scene) -> list[str]:
    """The names of the outputs (docs/model.md section 7) that a scene has, in the order of
    parameters.OUTPUTS."""
    return list(outputs_of(scene.components))


def mass_matrix(scene) -> np.ndarray:
    """M = diag(inertias) over the scene's coordinates (GearTrainModel.coordinates)."""
    return np.diag(GearTrainModel(scene).mass)


def natural_modes(scene, pinion_angle=None):
    """Natural frequencies (Hz, ascending), mode shapes (columns, over q) and coordinate names,
    with every contact point of the set at `pinion_angle` loaded, or with the stiffness averaged
    over a mesh period when `pinion_angle` is None."""
    model = GearTrainModel(scene)
    if pinion_angle is None:
        stiffness = model.mean_stiffness_matrix()
    else:
        contact_set = model.mesh.contact_set(*model.mesh.locate(pinion_angle))
        y = np.zeros(model.size)
        y[model.pinion] = pinion_angle - contact_set.pinion_angle
        stiffness = model.stiffness_matrix(y, contact_set)
    eigenvalues, shapes = scipy.linalg.eigh(stiffness, np.diag(model.mass))
    return np.sqrt(np.clip(eigenvalues, 0.0, None)) / (2 * math.pi), shapes, list(model.coordinates)


def rigid_rotation_mode(shapes, masses, rigid_rotation) -> int:
    """The column of `shapes` (natural_modes') that turns the train as a whole: the one most
    nearly along `rigid_rotation` (GearTrainModel's) in the metric of the `masses` (the mass
    matrix's diagonal). Told by its shape, not by its frequency: an elastic mode can be slower
    than any threshold that the rounding of the zero allows (a motor on a shaft of 1e-4
    N·m/rad rings at 8 mHz beside a tilt mode at 13 kHz, under 1e-6 of it)."""
    along = np.abs((masses * rigid_rotation) @ shapes)
    lengths = np.sqrt(np.einsum("i,ij,ij->j", masses, shapes, shapes))
    return int(np.argmax(along / lengths))
