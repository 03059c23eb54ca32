"""The Campbell diagram: natural frequencies against pinion speed with the mesh orders
f = k·z_pinion·n/60 (n in rpm), and their crossings, the speeds where a mesh harmonic
excites a mode (the resonance speeds of `herringbone info`).

The model has no speed-dependent stiffness or gyroscopic terms, so each natural frequency
(at the period-mean mesh stiffness, herringbone.model.assembly.natural_modes) is a horizontal line.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..arguments import speed_sweep_problem
from ..model.assembly import natural_modes
from ..model.parameters import RPM_PER_RAD_S
from .plots import _pyplot, _save
from .report import HARMONICS, resonance_speeds


@dataclass(frozen=True)
class Crossing:
    """A resonance of the Campbell diagram: where the k-th mesh harmonic meets a natural
    frequency."""
    speed: float  # pinion speed, rad/s
    order: int  # k: the mesh harmonic
    frequency: float  # natural frequency, Hz


def elastic_frequencies(scene) -> np.ndarray:
    """Natural frequencies (Hz, ascending) without the rigid rotation."""
    frequencies = natural_modes(scene)[0]
    return frequencies[frequencies > 1e-6 * max(frequencies.max(), 1.0)]


def crossings(scene, low: float, high: float) -> list[Crossing]:
    """Where k·f_mesh = f_n for low <= speed <= high (rad/s), by speed."""
    z = scene.parameters["z_pinion"]
    return sorted((Crossing(speed, k, f) for f in elastic_frequencies(scene)
                   for k, speed in resonance_speeds(f, z).items() if low <= speed <= high),
                  key=lambda c: c.speed)


def check_speed_range(low: float, high: float) -> None:
    """ValueError unless 0 < low < high are finite pinion speeds (rad/s), checked as every
    speed range is (arguments.speed_sweep_problem)."""
    problem = speed_sweep_problem(low, high, 2)
    if problem is not None:
        raise ValueError(f"speeds {low:g} to {high:g} rad/s: {problem}; allowed: 0 < low < high")


def plot_campbell(scene, low: float, high: float, path, title: str) -> list[Crossing]:
    """Write the diagram (rpm below, rad/s above; Hz up) and return its crossings."""
    check_speed_range(low, high)
    plt = _pyplot()
    z = scene.parameters["z_pinion"]
    frequencies = elastic_frequencies(scene)
    found = crossings(scene, low, high)
    rpm = np.linspace(low, high, 200) * RPM_PER_RAD_S
    top = max(HARMONICS[-1] * z * rpm[-1] / 60.0, frequencies.min()) * 1.1
    figure, axes = plt.subplots(figsize=(10, 6))
    for number, f in enumerate(f for f in frequencies if f <= top):
        axes.axhline(f, color="C0", lw=1.0, label="natural frequency f_n" if number == 0 else None)
        axes.annotate(f"{f:.0f} Hz", (1.0, f), xycoords=("axes fraction", "data"),
                      fontsize=7, va="bottom", ha="right", color="C0")
    for k in HARMONICS:
        axes.plot(rpm, k * z * rpm / 60.0, color=f"C{3 + k}", lw=1.0, ls="--",
                  label=f"mesh order k = {k}: k·z·n/60")
    axes.plot([c.speed * RPM_PER_RAD_S for c in found], [c.frequency for c in found], "o",
              mfc="none", color="k", label="crossings (resonance speeds)")
    axes.set_xlim(rpm[0], rpm[-1])
    axes.set_ylim(0, top)
    axes.set_xlabel("pinion speed n, rpm")
    axes.set_ylabel("frequency, Hz")
    upper = axes.secondary_xaxis("top", functions=(lambda n: n / RPM_PER_RAD_S,
                                                   lambda w: w * RPM_PER_RAD_S))
    upper.set_xlabel("pinion speed, rad/s")
    axes.legend(loc="upper left", fontsize=8)
    axes.grid(True, alpha=0.3)
    axes.set_title(title)
    _save(figure, path)
    return found
