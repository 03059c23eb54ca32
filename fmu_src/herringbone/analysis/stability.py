"""Parametric stability of the linear mesh at constant speed: Floquet multipliers.

At a constant pinion speed ω the contact points move with φp = ω·t, so the stiffness K(φp) and
damping C(φp) of the linear model (every point of each contact set loaded: no contact loss) repeat
every mesh period T = (2π/zp)/ω, and free vibration obeys M·q̈ + C(t)·q̇ + K(t)·q = 0. Its
monodromy matrix Φ(T) maps the state [q, q̇] at the start of a period to the state one period
later; its eigenvalues, the multipliers λ, say how a disturbance changes per period: the linear
model is stable when every |λ| < 1 and a disturbance grows like |λ|max^(t/T) when |λ|max > 1. The
contact geometry is prescribed by φp = ω·t; the load-dependent term F·(∂g/∂φp)·δφp of the
linearization about the loaded running state is left out, as are the static force and lead errors,
which drive the forced response and do not change its stability.

The rigid rotation. r (model.rigid_rotation) deforms no element (g·r = 0 for every row), so
K·r = C·r = 0 at all times and the rigid angle only drifts (a double multiplier 1). With
q = Q·η + r·θ, Q an M-orthonormal basis (Qᵀ·M·Q = I) of the M-orthogonal complement of r, the
symmetry of K and C splits the equations exactly into θ̈ = 0 and η̈ + Qᵀ·C·Q·η̇ + Qᵀ·K·Q·η = 0,
the 2(n−1)-state system we analyse. Its mass is the identity, and trace(Qᵀ·C·Q) =
trace(M⁻¹·C), so Liouville's det Φ = exp(−∫ trace(M⁻¹·C) dt) holds unchanged. (The model's
relative coordinates keep the rigid angle as the pinion's, coupled to the rest through inertia.)

Integration. Inside a phase interval of the mesh (mesh.switch_phases) the contact set is fixed but
the lever arms, and with an edge ramp the point stiffnesses, move linearly with φp, so K and C are
cubic in φp there (and jump at the switches): four samples of model.stiffness_matrix give them
exactly. Each interval is advanced by fourth-order Magnus steps exp(Ω), Ω = h/2·(A₁ + A₂) +
√3/12·h²·[A₂, A₁] with A₁, A₂ the state matrices at the two Gauss points: at least `substeps` per
interval, and more where a step would exceed `step_phase` radians of the interval's fastest mode
(the commutator term holds only for steps short against it: at ~100 rad per step it blows up).
A piecewise-constant stiffness (rigid bearings: no tilt; Meissner's equation) is exact with any
step, and the trace of Ω integrates trace(A) exactly, so det Φ obeys Liouville to rounding. With
the defaults Φ of the reference scene is within 6e-7 of its largest entry (fourth order). A is
taken at fractions of an interval, independent of ω: a sweep of speeds shares it and batches the
exponentials.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..arguments import check_scene, check_speeds
from ..model.assembly import GearTrainModel
from ..model.parameters import RPM_PER_RAD_S

SUBSTEPS = 4  # least Magnus steps per stretch (convergence: tests/analysis/test_stability.py)
STEP_PHASE = 1.0  # most radians of the fastest frozen mode per Magnus step
_GAUSS_POINTS = np.array([0.5 - math.sqrt(3.0) / 6.0, 0.5 + math.sqrt(3.0) / 6.0])
_MATRICES_AT_ONCE = 8192  # exponentials evaluated in one batch (memory)
# rad/s: the bracket a band edge between two charted speeds is bisected to (bisected_edges);
# the edge printed is its midpoint, within half of it
EDGE_TOLERANCE = 0.01
# where a band may hide between two charted speeds or two bands merge over a stable gap,
# each charted interval beside an unstable speed or beside a local maximum of |λ|max within
# REFINE_MARGIN of 1 (not neutral: an undamped train's are rounding) is probed at REFINE_SPLIT
# − 1 speeds more. On the example at 100 speeds over 1000-12000 rad/s (111 rad/s apart) the
# grid alone showed the k = 6 band at 1711-1753 rad/s (|λ|max up to 1.159) nowhere and gave
# 1711-1889 as one band over two stable gaps; probed, 1711.13-1753.09 stands apart
REFINE_MARGIN = 1e-2
REFINE_SPLIT = 8


@dataclass(frozen=True)
class Stretch:
    """A part of a period over which stiffness and damping vary smoothly (they may jump only
    between stretches): polynomials in the fraction s ∈ [0, 1] of the stretch done, given as
    coefficient stacks (degree + 1, n, n), lowest power first."""

    stiffness: np.ndarray
    damping: np.ndarray

    @classmethod
    def constant(cls, stiffness, damping) -> Stretch:
        """A stretch whose stiffness and damping matrices do not change along it."""
        return cls(np.atleast_2d(stiffness)[None], np.atleast_2d(damping)[None])

    @classmethod
    def interpolating(cls, stiffness_at, damping_at, degree=3) -> Stretch:
        """The polynomials of `degree` through functions of s sampled at degree + 1 points
        (exact when the functions are such polynomials)."""
        nodes = np.linspace(0.0, 1.0, degree + 1)
        vandermonde_inverse = np.linalg.inv(np.vander(nodes, increasing=True))
        return cls(*(np.einsum("ij,jkl->ikl", vandermonde_inverse,
                               np.array([function(s) for s in nodes]))
                     for function in (stiffness_at, damping_at)))

    def state_matrices(self, fractions, inverse_mass) -> np.ndarray:
        """A(s) = [[0, I], [−M⁻¹·K(s), −M⁻¹·C(s)]] for an array of fractions."""
        fractions = np.asarray(fractions, dtype=float)
        powers = fractions[..., None] ** np.arange(len(self.stiffness))
        n = len(inverse_mass)
        a = np.zeros(fractions.shape + (2 * n, 2 * n))
        a[..., :n, n:] = np.eye(n)
        a[..., n:, :n] = -inverse_mass @ np.tensordot(powers, self.stiffness, axes=1)
        a[..., n:, n:] = -inverse_mass @ np.tensordot(powers, self.damping, axes=1)
        return a


def periodic_monodromy(mass, stretches, durations, substeps=SUBSTEPS,
                       step_phase=STEP_PHASE) -> np.ndarray:
    """Φ(T) of M·x'' + C(t)·x' + K(t)·x = 0 over one period made of consecutive stretches.

    mass: (n, n) constant matrix (or a scalar); stretches: sequence of Stretch; durations: how
    long each lasts, seconds, shape (..., len(stretches)), the leading axes a batch (e.g. one row
    per speed). Each stretch takes at least `substeps` Magnus steps, and more (a power of two
    times that) to keep each step within `step_phase` radians of its fastest frozen mode.
    Returns Φ, shape (..., 2n, 2n), acting on the state [x, ẋ]."""
    mass = np.atleast_2d(np.asarray(mass, dtype=float))
    inverse_mass, size = np.linalg.inv(mass), 2 * len(mass)
    durations = np.asarray(durations, dtype=float)
    batch_shape, durations = durations.shape[:-1], durations.reshape(-1, len(stretches))
    steps = magnus_steps(stretches, inverse_mass, durations, substeps, step_phase)
    result = np.empty((len(durations), size, size))
    for pattern in np.unique(steps, axis=0):
        rows = np.flatnonzero(np.all(steps == pattern, axis=1))
        for chunk in np.array_split(rows, -(-len(rows) * pattern.max() // _MATRICES_AT_ONCE)):
            phi = np.eye(size)
            for stretch, count, duration in zip(stretches, pattern, durations[chunk].T):
                phi = _magnus_product(stretch, inverse_mass, duration, count) @ phi
            result[chunk] = phi
    return result.reshape(batch_shape + (size, size))


def magnus_steps(stretches, inverse_mass, durations, substeps=SUBSTEPS,
                 step_phase=STEP_PHASE) -> np.ndarray:
    """The Magnus steps periodic_monodromy takes over each stretch of each row of `durations`
    (s, shape (B, len(stretches))): at least `substeps`, and a power of two times that to keep
    each step within `step_phase` radians of the stretch's fastest frozen mode."""
    fastest = np.array([np.abs(np.linalg.eigvals(s.state_matrices([0.0, 0.5, 1.0], inverse_mass)))
                        .max() for s in stretches])
    # powers of two: a sweep of speeds falls into few groups that share their step counts
    refine = np.maximum(durations * fastest / (step_phase * substeps), 1.0)
    return substeps * 2 ** np.ceil(np.log2(refine)).astype(int)


def modulus_resolution(stretches, durations, substeps=SUBSTEPS,
                       step_phase=STEP_PHASE) -> np.ndarray:
    """What |λ| of the rigid-free system (mass I, the stretches' size n) can resolve at each
    row of `durations` (s, shape (B, len(stretches))): N·2n·ε, a pure number per period.

    Φ is the product of the period's N Magnus factors (magnus_steps), each of size 2n: each
    factor and each product of two rounds to about 2n·ε of its norm (ε the float's epsilon,
    2.2e-16), and the N of them add up, so a multiplier on the unit circle comes out as
    1 ± N·2n·ε. An excess |λ|max − 1 within it is rounding, not growth: measured on undamped
    trains from 5 to 20 000 rad/s (N 16 to 16 896), at most 0.08 of it. In the exponent it is
    ln(1 + N·2n·ε)/T 1/s, T the period (StabilityChart.exponent_resolution)."""
    size = 2 * stretches[0].stiffness.shape[-1]
    steps = magnus_steps(stretches, np.eye(size // 2), durations, substeps, step_phase)
    return steps.sum(axis=-1) * size * np.finfo(float).eps


def _magnus_product(stretch, inverse_mass, durations, count):
    """The transition over a stretch of each duration (B,): `count` fourth-order Magnus steps
    exp(h/2·(A₁ + A₂) + √3/12·h²·[A₂, A₁]), multiplied later-on-the-left."""
    fractions = (np.arange(count)[:, None] + _GAUSS_POINTS) / count
    a = stretch.state_matrices(fractions, inverse_mass)  # (count, 2, size, size)
    mean = 0.5 * (a[:, 0] + a[:, 1])
    commutator = a[:, 1] @ a[:, 0] - a[:, 0] @ a[:, 1]
    step = (durations / count)[:, None, None, None]
    factors = scipy.linalg.expm(step * mean + step ** 2 * (math.sqrt(3.0) / 12.0) * commutator)
    product = factors[:, 0]
    for k in range(1, count):
        product = factors[:, k] @ product
    return product


# --- the gear train -------------------------------------------------------------------------

def rigid_free_basis(model: GearTrainModel) -> np.ndarray:
    """Q (n × n−1): Qᵀ·M·Q = I and Qᵀ·M·r = 0 for the rigid rotation r."""
    root_mass = np.sqrt(model.mass)
    orthonormal = scipy.linalg.null_space((root_mass * model.rigid_rotation)[None, :])
    return orthonormal / root_mass[:, None]


def mesh_stretches(model: GearTrainModel):
    """The phase intervals of one mesh period as stretches of the rigid-free system (mass I),
    and their angular lengths (rad). K and C are cubic in the travel into an interval (point
    stiffness and lever arm both linear in it), so cubic interpolation reproduces them."""
    basis = rigid_free_basis(model)

    def sampled(matrix_at, contact_set):  # Qᵀ·matrix·Q at a fraction of the interval
        def at(fraction):
            y = np.zeros(model.size)
            y[model.pinion] = fraction * contact_set.length
            return basis.T @ matrix_at(y, contact_set) @ basis
        return at

    sets = [model.mesh.contact_set(0, i) for i in range(len(model.mesh.switch_phases))]
    stretches = [Stretch.interpolating(
        sampled(model.stiffness_matrix, contact_set),
        sampled(model.damping_matrix, contact_set))
        for contact_set in sets]
    return stretches, np.array([contact_set.length for contact_set in sets])


def monodromy(scene, pinion_speed, substeps=SUBSTEPS, step_phase=STEP_PHASE) -> np.ndarray:
    """Φ over one mesh period at a constant pinion speed (rad/s, > 0; an array gives a stack),
    in the rigid-free coordinates [η, η̇], q = rigid_free_basis(model)·η: 2(n−1) square. The
    period starts at the first switch phase (the multipliers do not depend on where). A speed
    that is not finite and > 0, or an empty array, raises ValueError; a non-Scene, SceneError."""
    speeds = check_speeds(pinion_speed, "pinion_speed")
    model = GearTrainModel(check_scene(scene))
    stretches, lengths = mesh_stretches(model)
    return periodic_monodromy(np.eye(model.size - 1), stretches, lengths / speeds[..., None],
                              substeps, step_phase)


def multipliers(scene, pinion_speed, substeps=SUBSTEPS, step_phase=STEP_PHASE) -> np.ndarray:
    """The Floquet multipliers (eigenvalues of the monodromy), largest modulus first."""
    values = np.linalg.eigvals(monodromy(scene, pinion_speed, substeps, step_phase))
    order = np.argsort(-np.abs(values), axis=-1, kind="stable")
    return np.take_along_axis(values, order, axis=-1)


def largest_multiplier(scene, pinion_speed, substeps=SUBSTEPS, step_phase=STEP_PHASE):
    """|λ|max: the factor by which the fastest-growing (or slowest-decaying) disturbance
    changes per mesh period; > 1 inside a parametric-resonance band."""
    return np.abs(multipliers(scene, pinion_speed, substeps, step_phase)[..., 0])


PROGRESS_BATCHES = 10  # stability_chart's batches of speeds when it reports its progress


@dataclass(frozen=True)
class StabilityChart:
    """The largest Floquet multiplier over a range of pinion speeds, as |λ|max per mesh period
    and as the largest Floquet exponent ln|λ|max/T (1/s), the bands where it exceeds 1 by more
    than rounding, and that rounding (`resolution`, modulus_resolution): where |λ|max is 1
    within it, a disturbance neither grows nor decays as far as the computation can tell
    (`neutral`; every speed of a train without damping, but inside its bands).

    The exponent is what the chart shows: a disturbance grows (> 0) or decays (< 0) like
    exp(exponent·t) whatever the speed, whereas |λ|max per period of a train whose least-damped
    mode decays at a constant rate σ rises towards 1 with speed (exp(−σ·T), T shrinking) and
    reads like an approach to instability that is not there."""
    speeds: np.ndarray  # pinion speeds, rad/s, ascending
    largest_modulus: np.ndarray  # |λ|max at each speed, per mesh period
    # (from, to) rad/s where |λ|max > 1 + resolution; an edge between two speeds bisected
    # to within edge_tolerance/2 of where it passes, one at the first or last speed there
    unstable_bands: tuple[tuple[float, float], ...]
    mesh_teeth: int  # z_pinion: mesh frequency = speed·z_pinion/(2π)
    resolution: np.ndarray  # |λ|max's rounding at each speed, per mesh period (pure number)
    edge_tolerance: float = EDGE_TOLERANCE  # rad/s, the bisected brackets' width
    # speeds probed between the charted ones where a band may hide or two merge
    # (refined_speeds, then unstable_midpoints), rad/s ascending, and |λ|max there: the bands
    # are of both
    probed_speeds: np.ndarray = field(default_factory=lambda: np.zeros(0))
    probed_modulus: np.ndarray = field(default_factory=lambda: np.zeros(0))
    refine_split: int = REFINE_SPLIT  # each interval probed was split into this many

    @property
    def grid_step(self) -> float:
        """The widest spacing of the charted speeds, rad/s: a band, or a stable gap between
        two, narrower than it may fall between them unseen where the chart did not probe."""
        return float(np.diff(self.speeds).max()) if len(self.speeds) > 1 else 0.0

    @property
    def largest_exponent(self) -> np.ndarray:
        """ln|λ|max / T at each speed, 1/s, T = 2π/(z_pinion·speed) the mesh period."""
        return np.log(self.largest_modulus) / self._period

    @property
    def exponent_resolution(self) -> np.ndarray:
        """The exponent's rounding at each speed, ln(1 + resolution)/T, 1/s."""
        return np.log1p(self.resolution) / self._period

    @property
    def neutral(self) -> np.ndarray:
        """At each speed, whether |λ|max is 1 within its rounding (nothing grows or decays)."""
        return np.abs(self.largest_modulus - 1.0) <= self.resolution

    @property
    def _period(self) -> np.ndarray:
        """The mesh period at each speed, s."""
        return 2.0 * math.pi / (self.speeds * self.mesh_teeth)


def band_runs(largest_modulus, resolution=0.0) -> list[tuple[int, int]]:
    """(first, last) sample index of each run of samples where |λ|max > 1 + `resolution`
    (a pure number or one per sample)."""
    excess = np.asarray(largest_modulus) - 1.0 - np.asarray(resolution, dtype=float)
    change = np.diff(np.concatenate([[0], (excess > 0.0).astype(int), [0]]))
    return list(zip(np.flatnonzero(change == 1).tolist(),
                    (np.flatnonzero(change == -1) - 1).tolist()))


def unstable_bands(parameter, largest_modulus, resolution=0.0) -> tuple[tuple[float, float], ...]:
    """The intervals of a sampled parameter where |λ|max > 1 + `resolution` (what the
    computation resolves, a pure number or one per sample, modulus_resolution; 0: any excess),
    their edges interpolated linearly in |λ|max − 1 − resolution between samples (a band open
    at an end of the samples ends there). Where |λ|max can be evaluated between the samples,
    bisected_edges places the edges to a tolerance instead: |λ|max rises like a square root
    from a band's edge, so the line from the stable sample's −σ·T to the unstable one's excess
    lands next to the stable sample (a tenth of the spacing off, and more)."""
    x = np.asarray(parameter, dtype=float)
    excess = np.asarray(largest_modulus) - 1.0 - np.asarray(resolution, dtype=float)

    def crossing(i):  # where |λ|max − 1 passes zero between samples i and i + 1
        return float(x[i] + (x[i + 1] - x[i]) * excess[i] / (excess[i] - excess[i + 1]))

    return tuple((float(x[0]) if first == 0 else crossing(first - 1),
                  float(x[-1]) if last == len(x) - 1 else crossing(last))
                 for first, last in band_runs(largest_modulus, resolution))


def bisected_edges(excess_at, stable, unstable, tolerance) -> np.ndarray:
    """Band edges by bisection on the sign of excess_at(speeds) (|λ|max − 1 − resolution at
    an array of speeds, rad/s, all at once): each edge bracketed by a speed where the excess
    is ≤ 0 (`stable`) and one where it is > 0 (`unstable`), halved until the bracket is at
    most `tolerance` (rad/s) wide; returns the brackets' midpoints, within tolerance/2 of a
    speed where the excess changes sign. All edges go together: one batch of monodromies a
    halving, log2(spacing/tolerance) of them (14 for 111 rad/s to 0.01 rad/s)."""
    if not tolerance > 0.0:  # a bracket of adjacent floats halves no further
        raise ValueError(f"edge tolerance {tolerance} rad/s; allowed: > 0")
    stable, unstable = (np.array(a, dtype=float) for a in (stable, unstable))
    while stable.size and np.abs(unstable - stable).max() > tolerance:
        middle = 0.5 * (stable + unstable)
        growing = excess_at(middle) > 0.0
        unstable = np.where(growing, middle, unstable)
        stable = np.where(growing, stable, middle)
    return 0.5 * (stable + unstable)


def refined_speeds(speeds, largest, resolution, margin=REFINE_MARGIN,
                   split=REFINE_SPLIT) -> np.ndarray:
    """The speeds (rad/s) to probe between charted `speeds` (ascending) where a band may hide
    or two merge: `split` − 1 evenly inside each interval beside a speed where |λ|max
    (`largest`) exceeds 1 + `resolution`, or beside a local maximum of |λ|max above 1 −
    `margin` that is not 1 within its resolution (neutral: rounding, no peak)."""
    speeds, largest = np.asarray(speeds, dtype=float), np.asarray(largest, dtype=float)
    if len(speeds) < 2:
        return np.zeros(0)
    resolution = np.broadcast_to(np.asarray(resolution, dtype=float), largest.shape)
    padded = np.concatenate([[-np.inf], largest, [-np.inf]])
    peak = (largest >= padded[:-2]) & (largest >= padded[2:])
    near = peak & (largest > 1.0 - margin) & (np.abs(largest - 1.0) > resolution)
    suspect = (largest > 1.0 + resolution) | near
    intervals = np.flatnonzero(suspect[:-1] | suspect[1:])
    inside = np.arange(1, split) / split
    low, high = speeds[intervals, None], speeds[intervals + 1, None]
    return (low + (high - low) * inside).ravel()


def speed_bands(stretches, lengths, speeds, largest, resolution, substeps=SUBSTEPS,
                step_phase=STEP_PHASE, tolerance=EDGE_TOLERANCE):
    """The unstable bands over charted speeds (rad/s, ascending) of the rigid-free system
    (mass I) made of `stretches` of angular `lengths` (rad): the runs of speeds where the
    charted |λ|max (`largest`) exceeds 1 + `resolution`, each edge between two speeds
    bisected (bisected_edges) on |λ|max − 1 − modulus_resolution to `tolerance` (rad/s); an
    edge at the first or last speed stays there. Returns ((from, to), ...) rad/s."""
    size = stretches[0].stiffness.shape[-1]

    def excess_at(at):
        durations = lengths / at[:, None]
        phi = periodic_monodromy(np.eye(size), stretches, durations, substeps, step_phase)
        return (np.abs(np.linalg.eigvals(phi)).max(axis=-1) - 1.0
                - modulus_resolution(stretches, durations, substeps, step_phase))

    runs = band_runs(largest, resolution)
    # each edge: (stable neighbour, unstable speed), or a charted end where the band is open
    brackets = [pair for first, last in runs
                for pair in (((first - 1, first) if first > 0 else (first, first)),
                             ((last + 1, last) if last < len(speeds) - 1 else (last, last)))]
    inner = [n for n, (out, inside) in enumerate(brackets) if out != inside]
    edges = speeds[[inside for _, inside in brackets]].astype(float)
    edges[inner] = bisected_edges(excess_at, speeds[[brackets[n][0] for n in inner]],
                                  speeds[[brackets[n][1] for n in inner]], tolerance)
    return tuple((float(low), float(high)) for low, high in edges.reshape(-1, 2))


def stability_chart(scene, speeds, substeps=SUBSTEPS, step_phase=STEP_PHASE,
                    on_progress=None, edge_tolerance=EDGE_TOLERANCE) -> StabilityChart:
    """The parametric stability of the linear mesh over pinion speeds: the largest Floquet
    multiplier |λ|max at each speed and the unstable bands, found at the speeds and at those
    probed between them where a band may hide or two merge (refined_speeds: REFINE_SPLIT − 1
    more monodromies in each interval beside an unstable speed or a near-unstable peak; then
    unstable_midpoints: one between each two unstable speeds).

    Parameters
    ----------
    scene : Scene
    speeds : array_like
        Pinion speeds, rad/s, finite and > 0 (sorted here).
    substeps, step_phase : float
        The monodromy's resolution (periodic_monodromy): at least `substeps` Magnus steps
        per stretch of one contact set, each within `step_phase` radians of its fastest mode.
    on_progress : callable or None
        on_progress(count) is called as each of about ten batches of speeds is done, with
        the batch's size (for a progress bar).
    edge_tolerance : float
        rad/s: each band edge between two speeds is bisected to a bracket this wide
        (speed_bands), at a monodromy per edge per halving: 14 halvings from 111 rad/s.

    Returns
    -------
    StabilityChart

    Raises
    ------
    ValueError
        No speed, or one not finite and > 0, before any work.

    Examples
    --------
    >>> import herringbone, numpy as np
    >>> from herringbone.analysis.stability import stability_chart
    >>> chart = stability_chart(herringbone.load_scene("reference"), np.linspace(1e3, 3e3, 41))
    >>> chart.unstable_bands, round(float(chart.largest_exponent.max()), 1)  # rad/s; 1/s
    ((), -2.0)
    """
    check_scene(scene)
    speeds = np.sort(check_speeds(speeds))
    # the model once for every batch and for the resolution (monodromy builds its own)
    stretches, lengths = mesh_stretches(GearTrainModel(scene))
    steps = (substeps, step_phase)
    charted = (speeds, *largest_moduli(stretches, lengths, speeds, *steps, on_progress))
    probed = refined_speeds(*charted)
    union = _joined(charted, (probed, *largest_moduli(stretches, lengths, probed, *steps)))
    middles = unstable_midpoints(*union)
    union = _joined(union, (middles, *largest_moduli(stretches, lengths, middles, *steps)))
    bands = speed_bands(stretches, lengths, union[0], union[1], union[2], *steps,
                        edge_tolerance)
    extra = ~np.isin(union[0], speeds)
    return StabilityChart(speeds, charted[1], bands, scene.parameters["z_pinion"], charted[2],
                          edge_tolerance, union[0][extra], union[1][extra])


def _joined(first, second) -> tuple[np.ndarray, ...]:
    """Two (speeds, |λ|max, resolution) as one, by speed."""
    joined = [np.concatenate([a, b]) for a, b in zip(first, second)]
    order = np.argsort(joined[0], kind="stable")
    return tuple(column[order] for column in joined)


def unstable_midpoints(speeds, largest, resolution) -> np.ndarray:
    """The midpoints (rad/s) between neighbouring speeds (ascending) where |λ|max exceeds
    1 + `resolution` at both: a stable midpoint splits the run there into two bands, which
    the line through the two would have shown as one."""
    unstable = np.asarray(largest) > 1.0 + np.asarray(resolution)
    pairs = np.flatnonzero(unstable[:-1] & unstable[1:])
    return 0.5 * (np.asarray(speeds)[pairs] + np.asarray(speeds)[pairs + 1])


def largest_moduli(stretches, lengths, speeds, substeps=SUBSTEPS, step_phase=STEP_PHASE,
                   on_progress=None) -> tuple[np.ndarray, np.ndarray]:
    """(|λ|max, its resolution) at each speed (rad/s) of the rigid-free system (mass I) made
    of `stretches` of angular `lengths` (rad): in PROGRESS_BATCHES batches of speeds where
    on_progress(count) is given, called as each is done; in one otherwise."""
    size = stretches[0].stiffness.shape[-1]
    durations = np.asarray(lengths) / np.asarray(speeds, dtype=float)[:, None]
    batches = np.array_split(np.arange(len(speeds)), min(len(speeds), PROGRESS_BATCHES)) \
        if on_progress is not None else [np.arange(len(speeds))]
    parts = [np.zeros(0)]
    for batch in batches:
        if len(batch):
            phi = periodic_monodromy(np.eye(size), stretches, durations[batch], substeps,
                                     step_phase)
            parts.append(np.abs(np.linalg.eigvals(phi)).max(axis=-1))
        if on_progress is not None:
            on_progress(len(batch))
    return (np.concatenate(parts),
            modulus_resolution(stretches, durations, substeps, step_phase))


def chart_curve(chart: StabilityChart) -> tuple[np.ndarray, np.ndarray]:
    """(speeds rad/s, largest exponent 1/s) as the chart draws them: the charted speeds, those
    probed between them (refined_speeds: the curve rises over the bands found there) and
    each band edge bisected between two of them, where the exponent is 0 (within its rounding
    and the bisection's tolerance), so that the curve crosses 0 where the shading begins and
    ends, not where the line between two charted speeds would."""
    sampled = np.concatenate([chart.speeds, chart.probed_speeds])
    edges = np.array([edge for band in chart.unstable_bands for edge in band
                      if not np.any(sampled == edge)])
    period = 2.0 * math.pi / (chart.probed_speeds * chart.mesh_teeth)
    speeds = np.concatenate([sampled, edges])
    exponent = np.concatenate([chart.largest_exponent, np.log(chart.probed_modulus) / period,
                               np.zeros(len(edges))])
    order = np.argsort(speeds, kind="stable")
    return speeds[order], exponent[order]


def plot_stability_chart(chart: StabilityChart, path, title=None):
    """Write a PNG of the largest Floquet exponent (1/s) against pinion speed (rad/s, the unit
    the command takes and prints the bands in; rpm on an axis below it, mesh frequency in Hz
    on the top one; chart_curve), with the line 0 (growth above, decay below) and the
    unstable bands shaded."""
    from .plots import _legend_beside, _pyplot, _save

    plt = _pyplot()
    hertz_per_rad_s = chart.mesh_teeth / (2.0 * np.pi)
    figure, axes = plt.subplots(figsize=(11, 5))
    speeds, exponent = chart_curve(chart)
    axes.plot(speeds, exponent, color="C0", lw=1.2,
              label="largest Floquet exponent ln|λ|max / T")
    axes.axhline(0.0, color="k", lw=0.8, ls="--", label="0: neither growth nor decay")
    for number, (low, high) in enumerate(chart.unstable_bands):
        axes.axvspan(low, high, color="C3", alpha=0.25,
                     label="unstable band (disturbances grow)" if number == 0 else None)
    axes.set_xlabel("pinion speed, rad/s")
    axes.set_ylabel("largest Floquet exponent, 1/s\n(< 0: slowest decay rate)")
    top = axes.secondary_xaxis("top", functions=(lambda w: np.asarray(w) * hertz_per_rad_s,
                                                 lambda f: np.asarray(f) / hertz_per_rad_s))
    top.set_xlabel("mesh frequency, Hz")
    below = axes.secondary_xaxis(-0.2, functions=(lambda w: np.asarray(w) * RPM_PER_RAD_S,
                                                  lambda n: np.asarray(n) / RPM_PER_RAD_S))
    below.set_xlabel("pinion speed, rpm")
    axes.set_title(title or "Parametric stability of the linear mesh (Floquet exponents)")
    _legend_beside(axes)  # off the curve and the bands, wherever they lie
    axes.grid(True, alpha=0.3)
    _save(figure, path, dpi=120)


# --- closed form: one degree of freedom with a stiffness alternating between two values ------

def constant_stiffness_transition(stiffness, mass, damping, duration) -> np.ndarray:
    """The 2×2 state transition over `duration` of m·x'' + c·x' + k·x = 0, closed form:
    e^(−γt)·[[cos ω_d t + γ·S, S], [−ω²·S, cos ω_d t − γ·S]], S = sin(ω_d t)/ω_d, γ = c/2m,
    ω_d² = k/m − γ² (complex ω_d covers the overdamped case)."""
    gamma = damping / (2.0 * mass)
    squared = stiffness / mass
    damped = np.sqrt(complex(squared - gamma ** 2))
    cosine = np.cos(damped * duration)
    sine_over = duration * np.sinc(damped * duration / math.pi)  # sin(ω_d t)/ω_d, also at ω_d = 0
    matrix = np.array([[cosine + gamma * sine_over, sine_over],
                       [-squared * sine_over, cosine - gamma * sine_over]])
    return (math.exp(-gamma * duration) * matrix).real


def meissner_half_trace(k1, k2, mass, damping, duration1, duration2) -> float:
    """tr(Φ)/2 of Meissner's equation: stiffness k1 for duration1, then k2 for duration2
    (N/m, kg, N·s/m, s). The multipliers solve λ² − tr·λ + det = 0 with det = e^(−c·T/m);
    with damping (det < 1) both lie inside the unit circle iff |tr|/2 < (1 + det)/2 (Jury),
    undamped the classical |tr|/2 < 1 keeps them on it."""
    product = (constant_stiffness_transition(k2, mass, damping, duration2)
               @ constant_stiffness_transition(k1, mass, damping, duration1))
    return 0.5 * float(np.trace(product))


def meissner_multipliers(k1, k2, mass, damping, duration1, duration2) -> np.ndarray:
    """The two multipliers a ± √(a² − det) (a the half-trace), largest modulus first."""
    half_trace = meissner_half_trace(k1, k2, mass, damping, duration1, duration2)
    determinant = math.exp(-damping * (duration1 + duration2) / mass)
    root = np.sqrt(complex(half_trace ** 2 - determinant))
    pair = np.array([half_trace + root, half_trace - root])
    return pair[np.argsort(-np.abs(pair), kind="stable")]
