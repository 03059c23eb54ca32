"""Geometry of the herringbone pair (docs/model.md section 2): radii, ratio, axial pitch, positions.

Axial positions ζ are measured from the centre of a gear body, positive towards the right half.
Local positions z in a half are measured from that half's outer face towards the groove.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

HALVES = ("left", "right")


@dataclass(frozen=True)
class GearGeometry:
    """The herringbone pair's dimensions (teeth, normal module m, helix angle rad, face widths,
    groove and bearing distances m) and what follows from them, all in SI units."""

    z_pinion: int
    z_wheel: int
    m_n: float
    beta: float
    b_left: float
    b_right: float
    groove: float
    a_left: float = 0.0
    a_right: float = 0.0

    @classmethod
    def from_parameters(cls, parameters: dict) -> GearGeometry:
        """The geometry of a scene's parameters (bearing distances 0 without bearings)."""
        return cls(**{name: parameters.get(name, 0.0) for name in cls.__dataclass_fields__})

    @property
    def radius_pinion(self) -> float:
        """Rp = zp·m_n / (2 cos β)"""
        return self.z_pinion * self.m_n / (2.0 * math.cos(self.beta))

    @property
    def radius_wheel(self) -> float:
        """Rw = zw·m_n / (2 cos β), m."""
        return self.z_wheel * self.m_n / (2.0 * math.cos(self.beta))

    @property
    def ratio(self) -> float:
        """u = zw / zp"""
        return self.z_wheel / self.z_pinion

    @property
    def axial_pitch(self) -> float:
        """p_x = π·m_n / sin β: how far a contact point travels per angular pitch 2π/zp."""
        return math.pi * self.m_n / math.sin(self.beta)

    @property
    def angular_pitch(self) -> float:
        """2π/zp, rad: the pinion turn over which the mesh repeats (one mesh period)."""
        return 2.0 * math.pi / self.z_pinion

    @property
    def axial_speed_per_radian(self) -> float:
        """dz/dφp = Rp·cot β (article eq. 1, divided by ω_p)."""
        return self.radius_pinion / math.tan(self.beta)

    @property
    def length(self) -> float:
        """L = b_left + b_right + groove: the length of a gear body."""
        return self.b_left + self.b_right + self.groove

    def mesh_force(self, torque: float, gear: str = "pinion") -> float:
        """The static mesh force, N, that balances `torque` (N·m) on `gear` ("pinion" or
        "wheel"): torque / pitch radius, the one home of that formula."""
        return torque / (self.radius_pinion if gear == "pinion" else self.radius_wheel)

    def face_width(self, half: str) -> float:
        """b of a helix half ("left" or "right"), m."""
        return self.b_left if half == "left" else self.b_right

    def axial_overlap(self, half: str) -> float:
        """ε_β = b / p_x of one half."""
        return self.face_width(half) / self.axial_pitch

    def bearing_position(self, side: str) -> float:
        """ζ of a bearing: −(aL + bL + δ/2) on the left, +(aR + bR + δ/2) on the right."""
        if side == "left":
            return -(self.a_left + self.b_left + self.groove / 2.0)
        return self.a_right + self.b_right + self.groove / 2.0

    def lever_arm(self, half: str, z: float) -> float:
        """ζ of a contact point at local position z of a half."""
        if half == "left":
            return -(self.groove / 2.0 + self.b_left) + z
        return self.groove / 2.0 + self.b_right - z

    def lever_arm_direction(self, half: str) -> float:
        """dζ/dz: points move towards the groove, so right-half points move to smaller ζ."""
        return 1.0 if half == "left" else -1.0


def solid_cylinder_transverse_inertia(parameters: dict, gear: str) -> float:
    """J = m·(3R² + L²)/12 of a gear body taken as a solid cylinder of its pitch radius."""
    geometry = GearGeometry.from_parameters(parameters)
    radius = geometry.radius_pinion if gear == "pinion" else geometry.radius_wheel
    return parameters[f"m_{gear}"] * (3.0 * radius ** 2 + geometry.length ** 2) / 12.0
