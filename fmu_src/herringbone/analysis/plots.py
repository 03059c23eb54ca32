"""Pictures an engineer reads: time histories of a run, amplitude spectra, the resonance curve
of a speed sweep, a waterfall of dte spectra. Speeds in rpm (rad/s on a second axis where the
input was in rad/s), frequencies in Hz, forces in kN, dte in µm. Each function writes a PNG.
"""
from __future__ import annotations

import math

import numpy as np

from ..files import replace_file
from ..optional import require

HARMONICS_SHOWN = 4  # a spectrum spans at least this many mesh harmonics
HARMONICS_MARKED = 12  # and marks at most this many (more crowd a log axis into a band)
# a spectrum's amplitude axis spans at most this many decades under its peak: the bins
# between the lines of a clean record fall to rounding (1e-17 of the peak), and below the
# integrator's tolerance (1e-7 of the force scale) nothing is the train's
SPECTRUM_DECADES = 7


def _pyplot():
    """matplotlib.pyplot drawing to files (Agg); MissingDependency naming the extra to install
    if matplotlib is not."""
    require("matplotlib", "the pictures").use("Agg")
    return require("matplotlib.pyplot", "the pictures")


def _save(figure, path, dpi=110):
    plt = _pyplot()
    figure.tight_layout()
    replace_file(path, lambda staging: figure.savefig(staging, dpi=dpi))
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


def _legend_beside(axes) -> None:
    """The legend to the right of the panel, off the data."""
    axes.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)


def _same(a, b) -> bool:
    """Whether two force histories are equal to a millionth of their largest magnitude (the
    halves of a gear whose halves are alike, a shaft's left and right bearings)."""
    scale = max(float(np.max(np.abs(a))), float(np.max(np.abs(b))), 1e-300)
    return bool(np.max(np.abs(a - b)) <= 1e-6 * scale)


def _plot_halves(axes, time, results) -> None:
    """Mesh force and its halves (kN); a pair of equal halves drawn once and named so."""
    axes.plot(time, results["F_mesh"] / 1e3, color="k", lw=1.0, label="F_mesh", zorder=3)
    left, right = results["F_mesh_left"], results["F_mesh_right"]
    if _same(left, right):
        axes.plot(time, left / 1e3, color="C0", lw=0.8,
                  label="each half\n(left = right: halves alike)")
    else:
        axes.plot(time, left / 1e3, color="C0", lw=0.8, label="left half")
        axes.plot(time, right / 1e3, color="C1", lw=0.8, ls="--", label="right half")
    axes.set_ylabel("mesh force, kN")


# each bearing's trace on its body's panel: the left one solid, the right one dashed, each its
# own colour, so that traces a few percent apart that cross at every mesh period (a lead
# error's) can be told apart; four in one panel lie on top of each other
BEARING_STYLES = {"left": ("C0", "-"), "right": ("C1", "--")}


def bearing_bodies(results) -> dict[str, list[str]]:
    """The bearing outputs by body: {"pinion": ["F_brg_pinion_left", ...], "wheel": [...]}, in
    the order of the outputs."""
    bodies: dict[str, list[str]] = {}
    for name in results:
        if name.startswith("F_brg_"):
            bodies.setdefault(name.removeprefix("F_brg_").rsplit("_", 1)[0], []).append(name)
    return bodies


def _plot_bearing_ripple(axes, time, results, body, bearings) -> None:
    """One body's bearing reactions as their ripple about each one's mean (kN), the mean in
    the legend: the ripple is a few percent of the mean, lost on a scale from zero. The left
    and right bearings (BEARING_STYLES) are drawn once where they carry equal forces."""
    if len(bearings) > 1 and all(_same(results[n], results[bearings[0]]) for n in bearings):
        shown = [(bearings[0], f"{body} left = right", BEARING_STYLES["left"])]
    else:
        shown = [(name, f"{body} {name.rsplit('_', 1)[1]}",
                  BEARING_STYLES.get(name.rsplit("_", 1)[1], ("C2", ":"))) for name in bearings]
    for name, label, (colour, style) in shown:
        force = results[name] / 1e3
        axes.plot(time, force - force.mean(), color=colour, ls=style, lw=0.8,
                  label=f"{label} (mean {force.mean():+.2f} kN)")
    axes.set_ylabel(f"{body} bearings,\nabout the mean, kN")


def plot_time_histories(results: dict, path, title: str) -> None:
    """Panels against time (ms): mesh force and its halves (kN), each body's bearing
    reactions' ripple about their means (kN; a panel a body), dte (µm); spans with a half out
    of contact shaded."""
    plt = _pyplot()
    time = results["time"] * 1e3
    bodies = bearing_bodies(results)
    panels = 2 + len(bodies)
    figure, axes = plt.subplots(panels, 1, figsize=(11, 2.3 * panels + 0.6), sharex=True)
    lost = contact_lost(results)
    _plot_halves(axes[0], time, results)
    for panel, (body, bearings) in zip(axes[1:], bodies.items()):
        _plot_bearing_ripple(panel, time, results, body, bearings)
    axes[-1].plot(time, results["dte"] * 1e6, color="C2", lw=0.9, label="dte")
    axes[-1].set_ylabel("dte, µm")
    axes[-1].set_xlabel("time, ms")
    axes[-1].set_xlim(time[0], time[-1])
    for panel in axes:
        _shade(panel, time, lost, "a half out of contact")
        panel.grid(True, alpha=0.3)
        _legend_beside(panel)
    axes[0].set_title(title)
    _save(figure, path)


def spread_apart(values, gap, ceiling):
    """`values` (ascending) moved apart as little as possible so that neighbours are at least
    `gap` apart and none is above `ceiling`: where labels go."""
    placed = list(values)
    for i in range(1, len(placed)):
        placed[i] = max(placed[i], placed[i - 1] + gap)
    if placed and placed[-1] > ceiling:
        placed[-1] = ceiling
        for i in range(len(placed) - 2, -1, -1):
            placed[i] = min(placed[i], placed[i + 1] - gap)
    return placed


def amplitude_spectrum(signal, interval):
    """One-sided amplitude spectrum (same unit as the signal) of the fluctuation about the
    mean, Hann-windowed and corrected for the window's coherent gain: a sinusoid of amplitude
    A between bins shows at most A and at least ~0.85·A."""
    signal = np.asarray(signal, dtype=float)
    window = np.hanning(len(signal))
    spectrum = np.abs(np.fft.rfft((signal - signal.mean()) * window)) * 2.0 / window.sum()
    return np.fft.rfftfreq(len(signal), interval), spectrum


def _mark_frequencies(axes, mesh_frequency, natural, top, band=None):
    """The mesh harmonics k·f_mesh up to `top` Hz (at most HARMONICS_MARKED) as dashed lines,
    or, where the speed changes over the samples (`band`: the least and largest mesh
    frequency there, Hz), as shaded bands k·band the harmonics smear over (at most
    HARMONICS_SHOWN: wider bands overlap); the natural frequencies as dotted lines."""
    if mesh_frequency > 0.0 and band is None:
        marked = min(int(top / mesh_frequency), HARMONICS_MARKED)
        for k in range(1, marked + 1):
            axes.axvline(k * mesh_frequency, color="C3", lw=0.8, ls="--",
                         label=f"mesh harmonics k·f_mesh, k ≤ {marked}" if k == 1 else None)
    elif mesh_frequency > 0.0:
        marked = max(1, min(int(top / band[1]), HARMONICS_SHOWN))
        for k in range(1, marked + 1):
            axes.axvspan(k * band[0], k * band[1], color="C3", alpha=0.12, lw=0.0,
                         label=f"mesh harmonics k·f_mesh over the speeds, k ≤ {marked}"
                         if k == 1 else None)
    for number, f in enumerate(f for f in natural if 0 < f <= top):
        axes.axvline(f, color="C2", lw=0.8, ls=":",
                     label="natural frequencies" if number == 0 else None)


def _amplitude_floor(panel, amplitude: np.ndarray) -> None:
    """The amplitude axis from the least amplitude shown, or SPECTRUM_DECADES under the
    largest where that lies lower, to matplotlib's top."""
    shown = amplitude[amplitude > 0.0]
    if shown.size:
        panel.set_ylim(bottom=max(shown.min(), shown.max() * 10.0 ** -SPECTRUM_DECADES))


def whole_mesh_periods(time, mesh_frequency: float,
                       longest: float | None = None) -> tuple[np.ndarray, int]:
    """(which samples, how many mesh periods): the largest whole number of mesh periods, at
    least one, that fits in `longest` s (None: the second half of a run, its start-up
    transient left out), at the run's end. Over a whole number of periods each mesh harmonic
    falls on a bin of the spectrum; over the second half of a 20 ms run at 250 Hz, 2.5
    periods, the odd ones fell between two. N samples stand for N intervals (the spectrum's
    record length), so the window's first sample, which its last repeats a whole number of
    periods later, is left out; a run shorter than the period is taken whole."""
    time = np.asarray(time, dtype=float)
    interval = float(np.diff(time).mean())
    period = 1.0 / mesh_frequency
    longest = 0.5 * (time[-1] - time[0]) if longest is None else longest
    # the 1e-9: a second half of exactly n periods is n, not n − 1 by rounding
    periods = max(1, math.floor(longest / period * (1.0 + 1e-9)))
    samples = min(round(periods * period / interval), len(time))
    keep = np.zeros(len(time), dtype=bool)
    keep[len(time) - samples:] = True
    return keep, periods


def plot_spectra(results: dict, path, mesh_frequency, natural, title, skip=0.0,
                 keep=None, record: str = "record length", mesh_band=None) -> None:
    """Amplitude spectra of dte (µm) and F_mesh (kN) of a run from `skip` s on (or of the
    samples `keep` says, e.g. whole_mesh_periods', which `record` names in the annotation),
    with the mesh harmonics and the natural frequencies marked (`mesh_band`: the least and
    largest mesh frequency over the samples, Hz, where the speed changes: the harmonics are
    drawn as the bands they smear over); log amplitude over log frequency, up to the highest
    natural frequency the sampling resolves (Nyquist's), so that a mode ringing far above the
    mesh frequency shows, and at least HARMONICS_SHOWN harmonics."""
    plt = _pyplot()
    keep = results["time"] >= skip if keep is None else keep
    interval = float(np.diff(results["time"][keep]).mean())
    nyquist = 0.5 / interval
    resolved = [f for f in natural if 0 < f < nyquist]
    highest = mesh_frequency if mesh_band is None else mesh_band[1]
    top = min(nyquist, 1.2 * max([(HARMONICS_SHOWN + 0.5) * highest, *resolved]))
    figure, axes = plt.subplots(2, 1, figsize=(11, 6.5), sharex=True)
    for panel, name, scale, unit in ((axes[0], "dte", 1e6, "µm"),
                                     (axes[1], "F_mesh", 1e-3, "kN")):
        frequency, amplitude = amplitude_spectrum(results[name][keep] * scale, interval)
        panel.loglog(frequency[1:], amplitude[1:], color="k", lw=0.9, label=name)
        _amplitude_floor(panel, amplitude[1:][frequency[1:] <= top])
        _mark_frequencies(panel, mesh_frequency, natural, top, mesh_band)
        panel.set_ylabel(f"{name} amplitude, {unit}")
        panel.grid(True, which="both", alpha=0.3)
        _legend_beside(panel)
    axes[1].set_xlim(frequency[1], top)
    axes[1].annotate(f"resolution {1.0 / (keep.sum() * interval):.3g} Hz ({record}); "
                     f"sampled every {interval:.3g} s",
                     (0.01, 0.02), xycoords="axes fraction", fontsize=8)
    axes[1].set_xlabel("frequency, Hz")
    axes[0].set_title(title, fontsize=10)
    _save(figure, path)
