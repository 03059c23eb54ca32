"""docs/model.md written out again by hand, for tests: the 8-coordinate mass and stiffness
matrices and the contact points at a pinion angle, without any code of the package's own
assembly."""
import math

import numpy as np

ORDER = ["phi_motor", "phi_pinion", "psi_pinion", "x_pinion", "phi_wheel", "psi_wheel",
         "x_wheel", "phi_load"]


def unit(i):
    row = np.zeros(8)
    row[i] = 1.0
    return row


def radii(p):
    rp = p["z_pinion"] * p["m_n"] / (2 * math.cos(p["beta"]))
    return rp, rp * p["z_wheel"] / p["z_pinion"]


def contact_points(p, pinion_angle=0.0):
    """[(half, z, lever arm)] of the points with 0 <= z < b (edge_ramp 0), docs/model.md
    section 3."""
    rp, _ = radii(p)
    p_x = math.pi * p["m_n"] / math.sin(p["beta"])
    offsets = [("left", 0.0), ("left", p["eps_q"]), ("right", p["stagger"]),
               ("right", p["stagger"] + p["eps_q"])]
    points = []
    for half, offset in offsets:
        b = p["b_left"] if half == "left" else p["b_right"]
        s = (p["phase0"] * p_x + offset * p_x + rp * pinion_angle / math.tan(p["beta"])) % p_x
        n = 0
        while s + n * p_x < b:
            z = s + n * p_x
            zeta = (-(p["groove"] / 2 + p["b_left"]) + z if half == "left"
                    else p["groove"] / 2 + p["b_right"] - z)
            points.append((half, z, zeta))
            n += 1
    return points


def bearing_positions(p):
    return (-(p["a_left"] + p["b_left"] + p["groove"] / 2),
            p["a_right"] + p["b_right"] + p["groove"] / 2)


def mass_matrix(p):
    return np.diag([p["I_motor"], p["I_pinion"], p["J_pinion"], p["m_pinion"],
                    p["I_wheel"], p["J_wheel"], p["m_wheel"], p["I_load"]])


def contact_row(p, zeta):
    rp, rw = radii(p)
    return rp * unit(1) - rw * unit(4) + unit(3) - unit(6) + zeta * (unit(2) - unit(5))


def stiffness_matrix(p, pinion_angle=0.0):
    zeta_left, zeta_right = bearing_positions(p)
    rows = [(unit(0) - unit(1), p["C_shaft_in"]), (unit(4) - unit(7), p["C_shaft_out"])]
    for gear, x, psi in (("pinion", 3, 2), ("wheel", 6, 5)):
        rows.append((unit(x) + zeta_left * unit(psi), p[f"c_brg_{gear}_left"]))
        rows.append((unit(x) + zeta_right * unit(psi), p[f"c_brg_{gear}_right"]))
    for _, _, zeta in contact_points(p, pinion_angle):
        rows.append((contact_row(p, zeta), p["c_point"]))
    return sum(k * np.outer(g, g) for g, k in rows)


def static_state(p, motor_torque):
    """q of the static equilibrium under M_motor and M_load = u M_motor with every point at
    pinion angle 0 loaded (the rigid rotation pinned by φp = 0), and the point forces."""
    rp, rw = radii(p)
    u = rw / rp
    points = contact_points(p)
    force = motor_torque * unit(0) - u * motor_torque * unit(7)
    for half, z, zeta in points:
        lead_error = p[f"dbeta_{half}"] * z
        force -= contact_row(p, zeta) * p["c_point"] * lead_error
    stiffness = stiffness_matrix(p)
    free = [i for i in range(8) if i != 1]
    q = np.zeros(8)
    q[free] = np.linalg.solve(stiffness[np.ix_(free, free)], force[free])
    point_forces = [(half, zeta, p["c_point"] * (contact_row(p, zeta) @ q + p[f"dbeta_{half}"] * z))
                    for half, z, zeta in points]
    return q, point_forces
