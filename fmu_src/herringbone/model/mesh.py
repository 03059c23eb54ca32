"""The contact points of the mesh (docs/model.md section 3) and the phases at which the set changes.

The mesh phase θ = φp / (2π/zp) counts angular pitches of the pinion; over one pitch every point
travels one axial pitch p_x. Each of the four streams (two halves × two lines of engagement)
holds points at z = s + n·p_x with s = ((lead + θ) mod 1)·p_x, where `lead` = phase0 + offset/p_x.

A point's stiffness weight w(z) is piecewise linear in z with kinks at z = −r, r, b − r, b + r
(r = edge_ramp; entry and exit z = 0, b when r = 0). Between two consecutive kink phases the set
of points with w > 0 and each point's linear piece are fixed: a `ContactSet` describes them as
linear functions of the pinion angle inside that phase interval. Integrators hold one contact set
over a segment and change it only when φp reaches the interval's end (a solver whose trial
steps see the switch loses accuracy or fails).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import equations
from .geometry import HALVES, GearGeometry

# Phases closer than this (in pitches; 3e-12 m of axial travel on the reference gear) are one
# switch: coinciding switches of different streams must not leave a segment of zero length.
PHASE_TOLERANCE = 1e-10
# An edge ramp shorter than this share of the wider face acts as sharp edges (0): a point's
# weight on the face, (min(z + r, b) - max(z - r, 0))/(2r), carries the rounding of z, about
# 1e-16·b/r of the point's stiffness (1e-8 at this bound, 0.35 nm on the reference's 35 mm),
# and all of it once r falls below the rounding of z (edge_ramp = 1e-20 m would give every point
# weight 0, a run without a mesh force). A ramp that short is sharp for every purpose.
SHARP_RAMP = 1e-8


def fraction_of_period(phase: float) -> float:
    """`phase` (fraction of a period) taken into [0, 1), where the mesh reads every phase:
    Python's `%` takes a tiny negative phase to 1.0 itself (−1e-38 % 1.0 == 1.0)."""
    fraction = phase % 1.0
    return 0.0 if fraction >= 1.0 else fraction


@dataclass(frozen=True)
class Stream:
    """One of the four streams of contact points: a helix half's line of engagement."""

    half: str  # "left" or "right"
    line: str  # "pre-pole" or "post-pole"
    lead: float  # phase by which the stream runs ahead of phase 0, fraction of p_x in [0, 1)

    @property
    def delay(self) -> float:
        """The stream's delay k against phase 0 (Kryukov & Savelieva), fraction of a period."""
        return fraction_of_period(-self.lead)


def streams(parameters: dict) -> list[Stream]:
    """The four streams of contact points, in the order left pre-pole, left post-pole, right
    pre-pole, right post-pole; `parameters` as a scene gives them (eps_q, stagger, phase0)."""
    offsets = {("left", "pre-pole"): 0.0,
               ("left", "post-pole"): parameters["eps_q"],
               ("right", "pre-pole"): parameters["stagger"],
               ("right", "post-pole"): parameters["stagger"] + parameters["eps_q"]}
    return [Stream(half, line, fraction_of_period(parameters["phase0"] + offset))
            for (half, line), offset in offsets.items()]


def resolved_edge_ramp(parameters: dict) -> float:
    """The edge ramp the mesh takes (m): the scene's edge_ramp, or 0 (sharp edges) where it is
    shorter than SHARP_RAMP of the wider face."""
    ramp = parameters["edge_ramp"]
    return 0.0 if ramp < SHARP_RAMP * max(parameters["b_left"], parameters["b_right"]) \
        else ramp


def weight(z: float, face_width: float, edge_ramp: float) -> float:
    """w(z): 1 inside the face, 0 outside; with an edge ramp, the share of the contact ellipse
    (half-length r) that lies on the face."""
    if edge_ramp == 0.0:
        return 1.0 if 0.0 <= z < face_width else 0.0
    on_face = min(z + edge_ramp, face_width) - max(z - edge_ramp, 0.0)
    return min(max(on_face / (2.0 * edge_ramp), 0.0), 1.0)


def weight_slope(z: float, face_width: float, edge_ramp: float) -> float:
    """dw/dz on the linear piece that contains z."""
    if edge_ramp == 0.0 or weight(z, face_width, edge_ramp) in (0.0, 1.0):
        return 0.0
    return (float(z + edge_ramp < face_width) - float(z - edge_ramp > 0.0)) / (2.0 * edge_ramp)


def kink_positions(face_width: float, edge_ramp: float) -> tuple[float, ...]:
    """Local positions where a point's weight changes its linear piece."""
    if edge_ramp == 0.0:
        return (0.0, face_width)
    r = edge_ramp
    return (-r, r, face_width - r, face_width + r)


@dataclass(frozen=True)
class ContactSet:
    """The contact points of one phase interval, as linear functions of the pinion angle.

    `table` holds one column a point, its rows named by the constants of
    model/equations.py (HALF: 0 left, 1 right; the others in N/m, m, rad). For a
    pinion angle φp inside the interval, with Δ = φp − `pinion_angle` (the angle at which the
    interval starts) and the axial travel s = v·Δ (v = Rp cot β, m/rad):
        c = STIFFNESS0 + STIFFNESS_SLOPE·s  (N/m),  ζ = LEVER_ARM0 + LEVER_ARM_SLOPE·s  (m),
        e = LEAD_ERROR0 + LEAD_ERROR_SLOPE·s  (m, the lead error's share of the approach).
    """

    cycle: int  # number of the mesh period the interval belongs to
    index: int  # number of the interval within a mesh period
    pinion_angle: float  # φp where the interval starts (the cycle it belongs to included)
    length: float  # angular extent of the interval, rad
    table: np.ndarray  # the points, one column each, as the compiled equations take them

    def __len__(self) -> int:
        """The number of points of the set."""
        return self.table.shape[1]


class Mesh:
    """The four streams of a gear pair and their switch phases."""

    def __init__(self, parameters: dict):
        self.geometry = GearGeometry.from_parameters(parameters)
        self.streams = streams(parameters)
        self.c_point = parameters["c_point"]
        self.edge_ramp = resolved_edge_ramp(parameters)
        self.lead_error = {"left": parameters["dbeta_left"], "right": parameters["dbeta_right"]}
        self.switch_phases = self._switch_phases()
        self._sets_of_first_period: dict[int, ContactSet] = {}  # shared: never written to
        self._period_table: equations.PeriodTable | None = None

    def _switch_phases(self) -> np.ndarray:
        p_x = self.geometry.axial_pitch
        phases = sorted(fraction_of_period(z / p_x - stream.lead)
                        for stream in self.streams
                        for z in kink_positions(self.geometry.face_width(stream.half),
                                                self.edge_ramp))
        distinct = [phases[0]]
        for phase in phases[1:]:
            if phase - distinct[-1] > PHASE_TOLERANCE:
                distinct.append(phase)
        if 1.0 + distinct[0] - distinct[-1] <= PHASE_TOLERANCE and len(distinct) > 1:
            distinct.pop()
        return np.array(distinct)

    def mean_stiffness(self) -> float:
        """k̄: mean over a mesh period of Σc of all points with w > 0. Every stream carries on
        average ∫w dz / p_x = b / p_x points (the edge ramp keeps the area of w)."""
        return self.c_point * sum(self.geometry.axial_overlap(s.half) for s in self.streams)

    def share_without_contact(self) -> float:
        """The fraction of a mesh period in which no point is on the face (0 to 1): a face too
        narrow for its streams' phasing (K_ε = 0) leaves the pair unloaded then, the train's
        two sides free of each other until the next point enters."""
        bounds = np.append(self.switch_phases, self.switch_phases[0] + 1.0)
        return float(sum(end - start for interval, (start, end)
                         in enumerate(zip(bounds[:-1], bounds[1:]))
                         if len(self.contact_set(0, interval)) == 0))

    def locate(self, pinion_angle: float, backwards: bool = False) -> tuple[int, int]:
        """(cycle, interval) of the phase interval that holds φp; an angle on a switch belongs to
        the interval that starts there (points enter at z = 0 inclusive), or where the pinion
        turns `backwards`, to the one that ends there: the one it moves into."""
        phase = pinion_angle / self.geometry.angular_pitch
        cycle = math.floor(phase + PHASE_TOLERANCE)
        within = phase - cycle
        interval = int(np.searchsorted(self.switch_phases, within + PHASE_TOLERANCE,
                                       side="right")) - 1
        last = len(self.switch_phases) - 1
        if interval < 0:  # before the first switch: the last interval of the previous cycle
            cycle, interval, within = cycle - 1, last, within + 1.0
        if backwards and within - self.switch_phases[interval] <= PHASE_TOLERANCE:
            interval -= 1  # on the switch
            if interval < 0:
                cycle, interval = cycle - 1, last
        return cycle, interval

    def interval_start(self, cycle: int, interval: int) -> float:
        """φp at which an interval starts."""
        return (cycle + self.switch_phases[interval]) * self.geometry.angular_pitch

    def contact_set(self, cycle: int, interval: int) -> ContactSet:
        """The points of an interval and their linear pieces, read at the interval's middle."""
        n = len(self.switch_phases)
        cycle += interval // n
        interval %= n
        if interval not in self._sets_of_first_period:
            self._sets_of_first_period[interval] = self._contact_set(interval)
        first = self._sets_of_first_period[interval]
        if cycle == 0:
            return first
        # every period holds the same sets; only where they start moves: a shallow copy with
        # two fields set (dataclasses.replace takes 3.3 µs, copy.copy 1.9, this 0.5; once per
        # doStep)
        contact_set = object.__new__(ContactSet)
        contact_set.__dict__.update(first.__dict__, cycle=cycle, pinion_angle=(
            cycle + self.switch_phases[interval]) * self.geometry.angular_pitch)
        return contact_set

    def _contact_set(self, interval: int) -> ContactSet:
        cycle, n = 0, len(self.switch_phases)
        start = self.switch_phases[interval]
        end = self.switch_phases[interval + 1] if interval + 1 < n else self.switch_phases[0] + 1.0
        middle = 0.5 * (start + end)
        g = self.geometry
        p_x, travel_to_middle = g.axial_pitch, (middle - start) * g.axial_pitch
        columns: dict[int, list[float]] = {row: [] for row in range(equations.POINT_FIELDS)}
        for stream in self.streams:
            b = g.face_width(stream.half)
            s = ((stream.lead + middle) % 1.0) * p_x
            # every point whose weight is positive somewhere: −r < z < b + r
            for n_point in range(-math.ceil((self.edge_ramp + s) / p_x),
                                 math.ceil((b + self.edge_ramp - s) / p_x) + 1):
                z_middle = s + n_point * p_x
                w = weight(z_middle, b, self.edge_ramp)
                if w <= 0.0:
                    continue
                slope = weight_slope(z_middle, b, self.edge_ramp)
                z0 = z_middle - travel_to_middle
                columns[equations.HALF].append(HALVES.index(stream.half))
                columns[equations.STIFFNESS0].append(self.c_point
                                                     * (w - slope * travel_to_middle))
                columns[equations.STIFFNESS_SLOPE].append(self.c_point * slope)
                columns[equations.LEVER_ARM0].append(g.lever_arm(stream.half, z0))
                columns[equations.LEVER_ARM_SLOPE].append(g.lever_arm_direction(stream.half))
                columns[equations.LEAD_ERROR0].append(self.lead_error[stream.half] * z0)
                columns[equations.LEAD_ERROR_SLOPE].append(self.lead_error[stream.half])
        table = np.array([columns[row] for row in range(equations.POINT_FIELDS)],
                         dtype=float).reshape(equations.POINT_FIELDS, -1)
        return ContactSet(cycle=cycle, index=interval,
                          pinion_angle=(cycle + start) * g.angular_pitch,
                          length=(end - start) * g.angular_pitch, table=table)

    def period_table(self) -> equations.PeriodTable:
        """Every contact set of one mesh period, for the compiled kernels (the sets of other
        periods differ only in where they start): the intervals' lengths, their numbers of
        points, and their point tables stacked, padded with zero columns to the longest.
        Computed once; the arrays are shared and never written to."""
        if self._period_table is None:
            sets = [self.contact_set(0, i) for i in range(len(self.switch_phases))]
            counts = np.array([len(s) for s in sets], dtype=np.int64)
            tables = np.zeros((len(sets), equations.POINT_FIELDS, max(1, counts.max())))
            for i, contact_set in enumerate(sets):
                tables[i, :, :counts[i]] = contact_set.table
            self._period_table = equations.PeriodTable(np.array([s.length for s in sets]),
                                                       counts, tables)
        return self._period_table
