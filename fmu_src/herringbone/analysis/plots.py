"""Pictures an engineer reads: time histories of a run, amplitude spectra, the resonance curve
of a speed sweep, a waterfall of dte spectra. Speeds in rpm (rad/s on a second axis where the
input was in rad/s), frequencies in Hz, forces in kN, dte in µm. Each function writes a PNG.
"""
from __future__ import annotations

import numpy as np

from ..optional import require

HARMONICS_SHOWN = 4  # mesh harmonics marked on spectra


def _pyplot():
    """matplotlib.pyplot drawing to files (Agg); MissingDependency naming the extra to install
    if matplotlib is not."""
    require("matplotlib", "the pictures").use("Agg")
    return require("matplotlib.pyplot", "the pictures")


def _save(figure, path):
    plt = _pyplot()
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def contact_lost(results) -> np.ndarray:
    """Samples at which a helix half carries no load (its teeth have separated)."""
    return (results["F_mesh_left"] <= 0.0) | (results["F_mesh_right"] <= 0.0)


def _shade(axes, time, mask, label):
    """Shade the spans of `time` where `mask` holds."""
    change = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    for number, (a, b) in enumerate(zip(np.flatnonzero(change == 1),
                                        np.flatnonzero(change == -1) - 1)):
        axes.axvspan(time[a], time[b], color="C3", alpha=0.2,
                     label=label if number == 0 else None)


def plot_time_histories(results: dict, path, title: str) -> None:
    """Four panels against time (ms): mesh force and its halves, bearing reactions, dte;
    spans with a half out of contact shaded."""
    plt = _pyplot()
    time = results["time"] * 1e3
    bearings = [n for n in results if n.startswith("F_brg_")]
    panels = 3 if bearings else 2
    figure, axes = plt.subplots(panels, 1, figsize=(10, 2.6 * panels + 0.6), sharex=True)
    lost = contact_lost(results)
    axes[0].plot(time, results["F_mesh"] / 1e3, color="k", lw=1.0, label="F_mesh")
    axes[0].plot(time, results["F_mesh_left"] / 1e3, color="C0", lw=0.8, label="left half")
    axes[0].plot(time, results["F_mesh_right"] / 1e3, color="C1", lw=0.8, label="right half")
    axes[0].set_ylabel("mesh force, kN")
    for name in bearings:
        axes[1].plot(time, results[name] / 1e3, lw=0.8, label=name.removeprefix("F_brg_"))
    if bearings:
        axes[1].set_ylabel("bearing reaction, kN")
    axes[-1].plot(time, results["dte"] * 1e6, color="C2", lw=0.9, label="dte")
    axes[-1].set_ylabel("dte, µm")
    axes[-1].set_xlabel("time, ms")
    for panel in axes:
        _shade(panel, time, lost, "a half out of contact")
        panel.grid(True, alpha=0.3)
        panel.legend(loc="upper right", fontsize=8, ncol=2)
    axes[0].set_title(title)
    _save(figure, path)


def amplitude_spectrum(signal, interval):
    """One-sided amplitude spectrum (same unit as the signal) of the fluctuation about the
    mean, Hann-windowed and corrected for the window's coherent gain: a sinusoid of amplitude
    A between bins shows at most A and at least ~0.85·A."""
    signal = np.asarray(signal, dtype=float)
    window = np.hanning(len(signal))
    spectrum = np.abs(np.fft.rfft((signal - signal.mean()) * window)) * 2.0 / window.sum()
    return np.fft.rfftfreq(len(signal), interval), spectrum


def _mark_frequencies(axes, mesh_frequency, natural, top):
    for k in range(1, int(top / mesh_frequency) + 1):  # every harmonic in the plotted range
        axes.axvline(k * mesh_frequency, color="C3", lw=0.8, ls="--",
                     label="mesh harmonics k·f_mesh" if k == 1 else None)
    for number, f in enumerate(f for f in natural if 0 < f <= top):
        axes.axvline(f, color="C2", lw=0.8, ls=":",
                     label="natural frequencies" if number == 0 else None)


def plot_spectra(results: dict, path, mesh_frequency, natural, title, skip=0.0) -> None:
    """Amplitude spectra of dte (µm) and F_mesh (kN) of a run from `skip` s on, with the
    mesh harmonics and the natural frequencies marked; log amplitude."""
    plt = _pyplot()
    keep = results["time"] >= skip
    interval = float(np.diff(results["time"][keep]).mean())
    top = min(0.5 / interval, max(HARMONICS_SHOWN + 0.5, 1) * mesh_frequency * 1.2)
    figure, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for panel, name, scale, unit in ((axes[0], "dte", 1e6, "µm"),
                                     (axes[1], "F_mesh", 1e-3, "kN")):
        frequency, amplitude = amplitude_spectrum(results[name][keep] * scale, interval)
        panel.semilogy(frequency[1:], amplitude[1:], color="k", lw=0.9, label=name)
        _mark_frequencies(panel, mesh_frequency, natural, top)
        panel.set_ylabel(f"{name} amplitude, {unit}")
        panel.grid(True, which="both", alpha=0.3)
        panel.legend(loc="upper right", fontsize=8)
    axes[1].set_xlim(0, top)
    axes[1].annotate(f"resolution {1.0 / (keep.sum() * interval):.3g} Hz (record length)",
                     (0.01, 0.02), xycoords="axes fraction", fontsize=8)
    axes[1].set_xlabel("frequency, Hz")
    axes[0].set_title(title)
    _save(figure, path)
