"""The Campbell diagram: natural frequencies against pinion speed with the mesh orders
f = k·z_pinion·n/60 (n in rpm), and their crossings, the speeds where a mesh harmonic
excites a mode (the resonance speeds of `herringbone info`).

The model has no speed-dependent stiffness or gyroscopic terms, so each natural frequency
(at the period-mean mesh stiffness, herringbone.model.assembly.natural_modes) is a horizontal line.
Each mode is named as `herringbone info` names it (report.mode_character): by the kind of motion
that holds most of its kinetic energy, torsional (the angles φ), lateral (the displacements x
along the mesh force) or tilt (the tilts ψ), and its share.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..arguments import speed_sweep_problem
from ..model.assembly import GearTrainModel, natural_modes, rigid_rotation_mode
from ..model.parameters import RPM_PER_RAD_S
from .excitation import HARMONICS_CONSIDERED, STRENGTH_LISTED, Resonance, resonances
from .plots import _pyplot, _save, spread_apart
from .report import HARMONICS, mode_character, resonance_speeds


@dataclass(frozen=True)
class Crossing:
    """A resonance of the Campbell diagram: where the k-th mesh harmonic meets a natural
    frequency."""
    speed: float  # pinion speed, rad/s
    order: int  # k: the mesh harmonic
    frequency: float  # natural frequency, Hz


SHARE_NAMED = 0.25  # a body holding this share of a mode's kinetic energy is named


@dataclass(frozen=True)
class Mode:
    """A natural mode named by what moves in it."""
    frequency: float  # Hz
    # what `herringbone info` calls it (report.mode_character): the kind of coordinate holding
    # the largest share of its kinetic energy, and that share, e.g. "torsional (56 % of
    # kinetic energy)"
    kind: str
    bodies: tuple[str, ...]  # motor, pinion, wheel, load: those that hold SHARE_NAMED or more

    @property
    def label(self) -> str:
        """For instance "684 Hz torsional (98 % of kinetic energy): wheel"."""
        return f"{self.frequency:.0f} Hz {self.kind}: {', '.join(self.bodies)}"


def _named(shares: dict[str, float]) -> list[str]:
    """The keys holding SHARE_NAMED of the total or more (at least the largest), largest first."""
    ranked = sorted(shares, key=shares.get, reverse=True)  # type: ignore[arg-type]
    return [ranked[0]] + [k for k in ranked[1:] if shares[k] >= SHARE_NAMED]


def elastic_modes(scene) -> list[Mode]:
    """The elastic natural modes (ascending frequency, no rigid rotation), each named as
    `herringbone info` names it (report.mode_character: the kind of coordinate with the
    largest share of the kinetic energy m_i·v_i² of its mass-normalized eigenvector, and that
    share: one name for a mode in both), with the bodies holding SHARE_NAMED of it or more."""
    frequencies, shapes, coordinates = natural_modes(scene)
    model = GearTrainModel(scene)
    mass = model.mass
    rigid = rigid_rotation_mode(shapes, mass, model.rigid_rotation)
    modes = []
    for index, (frequency, shape) in enumerate(zip(frequencies, shapes.T)):
        if index == rigid:
            continue
        energy = mass * shape**2 / float(np.sum(mass * shape**2))
        bodies: dict[str, float] = {}
        for name, share in zip(coordinates, energy):
            body = name.split("_", 1)[1]
            bodies[body] = bodies.get(body, 0.0) + share
        modes.append(Mode(float(frequency),
                          mode_character(shape, mass, coordinates),
                          tuple(_named(bodies))))
    return modes


def elastic_frequencies(scene) -> np.ndarray:
    """The natural frequencies of the train at its mean mesh stiffness, without the rigid
    rotation.

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    numpy.ndarray
        Hz, ascending.

    Examples
    --------
    >>> import herringbone
    >>> from herringbone.analysis.campbell import elastic_frequencies
    >>> elastic_frequencies(herringbone.load_scene("reference")).round(1).tolist()  # Hz
    [112.9, 683.7, 1497.3, 2059.4, 4397.2, 10418.6, 13354.5]
    """
    return np.array([mode.frequency for mode in elastic_modes(scene)])


def crossings(scene, low: float, high: float) -> list[Crossing]:
    """The resonances of the Campbell diagram: where a mesh harmonic k·f_mesh meets a
    natural frequency f_n.

    Parameters
    ----------
    scene : Scene
    low, high : float
        The pinion speeds between which to look, rad/s (both included).

    Returns
    -------
    list of Crossing
        By speed: the pinion speed (rad/s), the harmonic k and the natural frequency (Hz).

    Examples
    --------
    >>> import herringbone
    >>> from herringbone.analysis.campbell import crossings
    >>> [(round(c.speed, 1), c.order, round(c.frequency, 1))
    ...  for c in crossings(herringbone.load_scene("reference"), 400.0, 500.0)]
    [(429.6, 1, 683.7), (431.3, 3, 2059.4), (470.4, 2, 1497.3)]
    """
    z = scene.parameters["z_pinion"]
    return sorted((Crossing(float(speed), k, float(f)) for f in elastic_frequencies(scene)
                   for k, speed in resonance_speeds(f, z).items() if low <= speed <= high),
                  key=lambda c: c.speed)


def check_speed_range(low: float, high: float) -> None:
    """ValueError unless 0 < low < high are finite pinion speeds (rad/s), checked as every
    speed range is (arguments.speed_sweep_problem)."""
    problem = speed_sweep_problem(low, high, 2)
    if problem is not None:
        raise ValueError(f"speeds {low:g} to {high:g} rad/s: {problem}; allowed: 0 < low < high")


def _label_modes(axes, modes, top):
    """Each mode's frequency line named beside the plot, to the right, labels kept apart."""
    places = spread_apart([m.frequency for m in modes], 0.045 * top, top)
    for mode, place in zip(modes, places):
        axes.annotate(mode.label, xy=(1.0, mode.frequency), xytext=(1.02, place),
                      xycoords=("axes fraction", "data"), textcoords=("axes fraction", "data"),
                      fontsize=8, va="center", ha="left", color="C0",
                      arrowprops={"arrowstyle": "-", "color": "C0", "lw": 0.6})


def plot_campbell(scene, low: float, high: float, path, title: str,
                  ringing: list[Resonance] | None = None) -> list[Crossing]:
    """Write the diagram (rpm below, rad/s above; Hz up; each mode named by its type beside
    it; the resonances that ring, `ringing`, None: excitation.resonances over the span) and
    return its crossings."""
    check_speed_range(low, high)
    plt = _pyplot()
    z = scene.parameters["z_pinion"]
    modes = elastic_modes(scene)
    found = crossings(scene, low, high)
    rpm = np.linspace(low, high, 200) * RPM_PER_RAD_S
    top = max(HARMONICS[-1] * z * rpm[-1] / 60.0, modes[0].frequency) * 1.1
    shown = [m for m in modes if m.frequency <= top]
    figure, axes = plt.subplots(figsize=(11, 7))
    for number, mode in enumerate(shown):
        axes.axhline(mode.frequency, color="C0", lw=1.0,
                     label="natural frequency f_n" if number == 0 else None)
    _label_modes(axes, shown, top)
    for k in HARMONICS:
        axes.plot(rpm, k * z * rpm / 60.0, color=f"C{3 + k}", lw=1.0, ls="--",
                  label=f"mesh order k = {k}: k·z·n/60")
    axes.plot([c.speed * RPM_PER_RAD_S for c in found], [c.frequency for c in found], "o",
              mfc="none", color="k", label="crossings (resonance speeds)")
    ringing = [r for r in (resonances(scene, low, high) if ringing is None else ringing)
               if r.frequency <= top]
    for rough, words in ((False, f"resonances that ring, k up to {HARMONICS_CONSIDERED} "
                                 f"(excitation.resonances, {STRENGTH_LISTED:.0%} or more)"),
                         (True, "the same, a rough estimate (the mode's stiffness swings "
                                "with the mesh)")):
        marked = [r for r in ringing if r.rough == rough]
        axes.plot([r.speed * RPM_PER_RAD_S for r in marked], [r.frequency for r in marked],
                  "o", ms=4, color="C3", mfc="none" if rough else "C3", label=words)
    axes.set_xlim(rpm[0], rpm[-1])
    axes.set_ylim(0, top)
    axes.set_xlabel("pinion speed n, rpm")
    axes.set_ylabel("frequency, Hz")
    upper = axes.secondary_xaxis("top", functions=(lambda n: n / RPM_PER_RAD_S,
                                                   lambda w: w * RPM_PER_RAD_S))
    upper.set_xlabel("pinion speed, rad/s")
    # below the axes: inside, it stood over the crossings and the resonances of the upper modes
    axes.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=8)
    axes.grid(True, alpha=0.3)
    axes.set_title(title)
    _save(figure, path)
    return found
