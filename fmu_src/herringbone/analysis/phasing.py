"""Mesh-phase theory (docs/model.md section 8): contact ratios, phase overlap and alternation laws.

A stream is a pair (eps, delay): contact ratio ε and delay k, a fraction of a mesh period (one
angular pitch of the pinion). The stream has ⌊ε⌋+1 pairs in contact over a fraction frac(ε) of
each period starting at its phase 0, and ⌊ε⌋ over the rest; delayed by k it counts c(φ − k)
(Kryukov & Savelieva). Phases φ are fractions of a period. Angles are in radians throughout.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq

from ..model.geometry import GearGeometry
from ..model.mesh import PHASE_TOLERANCE, Mesh, fraction_of_period
from ..model.mesh import streams as mesh_streams


def involute(angle: float) -> float:
    """inv α = tan α − α."""
    return math.tan(angle) - angle


def spur_contact_ratio(z1, z2, x1=0.0, x2=0.0, alpha=math.radians(20), ha=1.0) -> float:
    """ε_α of an involute spur pair cut by a rack of pressure angle `alpha` (rad) and addendum
    coefficient `ha`, profile shifts x1, x2, at the zero-backlash centre distance; tips are
    shortened by Δy (docs/model.md section 8). Independent of the module."""
    z_sum = z1 + z2
    inv_working = 2.0 * (x1 + x2) * math.tan(alpha) / z_sum + involute(alpha)
    # inv is increasing on [0, π/2): a single root below the pole of tan
    working_angle = brentq(lambda a: involute(a) - inv_working, 1e-9, math.pi / 2 - 1e-9,
                           xtol=1e-15)
    y = z_sum / 2.0 * (math.cos(alpha) / math.cos(working_angle) - 1.0)
    shortening = x1 + x2 - y
    tip_terms = 0.0
    for z, x in ((z1, x1), (z2, x2)):
        tip_diameter = z + 2.0 * (ha + x - shortening)  # in modules
        tip_angle = math.acos(z * math.cos(alpha) / tip_diameter)
        tip_terms += z * math.tan(tip_angle)
    return (tip_terms - z_sum * math.tan(working_angle)) / (2.0 * math.pi)


def phase_overlap(alpha_k, alpha_l, rho_f, rho_a) -> float:
    """ε_q of a Novikov DLZ generating rack (Petrovsky): profile angle α_k and angle α_l (rad),
    fillet and addendum arc radii ρ_f*, ρ_a* in modules.
    ε_q = 1 − l_k·cos α_k / π, l_k = ρ_f*·(sin α_k − sin α_l) + ρ_a*·sin α_k (docs/model.md
    reads the printed π·tan α_k as π, which reproduces the article's 0.8 for the elementary
    rack)."""
    l_k = rho_f * (math.sin(alpha_k) - math.sin(alpha_l)) + rho_a * math.sin(alpha_k)
    return 1.0 - l_k * math.cos(alpha_k) / math.pi


def stream_count(eps: float, delay: float, phase: float) -> int:
    """Pairs in contact of one stream at `phase`: the points z/p = u + n (u = (φ − k) mod 1,
    n ≥ 0) with z < ε, i.e. ⌊ε⌋+1 for u < frac(ε), else ⌊ε⌋ — the way mesh.py counts them."""
    return max(0, math.ceil(eps - fraction_of_period(phase - delay)))


def contact_count(streams, phase: float) -> int:
    """k_c(φ): total pairs in contact of the streams [(eps, delay), ...] at `phase`. At a
    breakpoint the count of the interval that starts there is returned."""
    return sum(stream_count(eps, delay, phase) for eps, delay in streams)


def count_intervals(streams) -> list[tuple[float, float, int]]:
    """[(start, end, count)] covering one period [0, 1) from φ = 0: the count is constant on
    each interval. Breakpoints (entry at k, exit at k + frac(ε)) closer than PHASE_TOLERANCE are
    one, as in mesh.py, so coinciding entries and exits leave no interval of zero length."""
    points = sorted(fraction_of_period(p) for eps, delay in streams
                    for p in (delay, delay + eps % 1.0))
    breaks = [0.0]
    for p in points:
        if p - breaks[-1] > PHASE_TOLERANCE and 1.0 - p > PHASE_TOLERANCE:
            breaks.append(p)
    edges = breaks + [1.0]
    return [(a, b, contact_count(streams, 0.5 * (a + b))) for a, b in zip(edges, edges[1:])]


def alternation_law(streams) -> str:
    """The alternation law: the distinct consecutive counts over one period read from φ = 0,
    e.g. "3-4-3-2"; a constant count is a single number, "3". Equal neighbours merge; the period
    is not wrapped, so a law that ends on its first value shows it again ("1-2-1")."""
    law: list[int] = []
    for _, _, count in count_intervals(streams):
        if not law or law[-1] != count:
            law.append(count)
    return "-".join(str(count) for count in law)


@dataclass(frozen=True)
class ScenePhasing:
    """Mesh-phase figures of a herringbone scene (sharp face edges: edge_ramp = 0)."""

    eps_beta_left: float  # ε_β = b/p_x of each half
    eps_beta_right: float
    q21: float  # m: axial distance between the two lines' points, ε_q·p_x
    # (ε, delay) of the streams left pre-, left post-, right pre-, right post-pole
    streams: tuple[tuple[float, float], ...]
    law: str
    k_eps: int  # K_ε: least number of points in contact of the pair over a mesh period

    @property
    def eps_beta(self) -> float:
        """ε_β of a half; the mean of the two when they differ."""
        return 0.5 * (self.eps_beta_left + self.eps_beta_right)

    @property
    def k_eps_ratio(self) -> float:
        """K_ε/ε_β per helical half (Petrovsky's measure, 2 for an integer ε_β): the pair's K_ε
        over the overlap of both halves, εβ_left + εβ_right = 2·eps_beta."""
        return self.k_eps / (self.eps_beta_left + self.eps_beta_right)


def scene_phasing(scene_or_parameters) -> ScenePhasing:
    """ε_β, q21, the four streams (delays from mesh.Stream) and their law for a Scene or its
    complete parameter dict."""
    parameters = getattr(scene_or_parameters, "parameters", scene_or_parameters)
    geometry = GearGeometry.from_parameters(parameters)
    pairs = tuple((geometry.axial_overlap(s.half), s.delay) for s in mesh_streams(parameters))
    return ScenePhasing(eps_beta_left=geometry.axial_overlap("left"),
                        eps_beta_right=geometry.axial_overlap("right"),
                        q21=parameters["eps_q"] * geometry.axial_pitch,
                        streams=pairs, law=alternation_law(pairs),
                        k_eps=min(count for _, _, count in count_intervals(pairs)))


def without_contact_note(mesh: Mesh) -> str:
    """A line on a face too narrow for its streams' phasing: how much of each mesh period no
    point is on it (Mesh.share_without_contact), when the pair transmits no torque and the
    teeth meet again by impact; '' where some point is always on the face."""
    share = mesh.share_without_contact()
    if share == 0.0:
        return ""
    return (f"no point is on the face for {100.0 * share:.3g} % of each mesh period: the pair "
            "transmits no torque then, and the teeth meet again by impact (a wider face keeps "
            "a point on it)")

