"""Pictures of a sweep: the resonance curve (K_v and dte against speed, with the resonance
speeds of `herringbone info` marked), a parameter curve or grid map, and a waterfall of the
points' dte spectra with the mesh orders and natural frequencies."""
from __future__ import annotations

import numpy as np

from ..model.parameters import RPM_PER_RAD_S
from .plots import _pyplot, _save, amplitude_spectrum
from .report import HARMONICS, resonance_speeds


def resonances_between(frequencies, z_pinion, low, high):
    """[(speed rad/s, k, f_n Hz)] with k·f_mesh = f_n for speeds in [low, high]."""
    return sorted((speed, k, f) for f in frequencies if f > 0
                  for k, speed in resonance_speeds(f, z_pinion).items() if low <= speed <= high)


def plot_resonance_curve(table, path, natural, z_pinion, title) -> None:
    """K_v (top) and dte peak-to-peak (bottom) against pinion speed, rpm (rad/s on top), each
    resonance k·f_mesh = f_n in the range marked and labelled."""
    plt = _pyplot()
    table = table.sort_values("w0_pinion")
    rpm = table["speed_rpm"].to_numpy()
    figure, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    axes[0].plot(rpm, table["K_v"], "o-", color="k", ms=3, lw=1.0,
                 label="K_v = max F_mesh / F_static")
    axes[0].set_ylabel("dynamic factor K_v")
    axes[1].plot(rpm, table["dte_p2p_um"], "o-", color="C2", ms=3, lw=1.0, label="dte peak-to-peak")
    axes[1].plot(rpm, table["dte_rms_um"], "s-", color="C0", ms=3, lw=1.0, label="dte rms")
    axes[1].set_ylabel("dte, µm")
    axes[1].set_xlabel("pinion speed, rpm")
    low, high = table["w0_pinion"].min(), table["w0_pinion"].max()
    labelled = set()
    for speed, k, f in resonances_between(natural, z_pinion, low, high):
        for panel in axes:
            panel.axvline(speed * RPM_PER_RAD_S, color=f"C{3 + k}", lw=0.8, ls="--",
                          label=None if k in labelled else f"k·f_mesh = f_n, k = {k}")
        labelled.add(k)
        axes[0].annotate(f" {f:.0f} Hz", (speed * RPM_PER_RAD_S, 0.0), rotation=90,
                         xycoords=("data", "axes fraction"), fontsize=7, ha="right",
                         va="bottom", color=f"C{3 + k}")
    top = axes[0].secondary_xaxis("top", functions=(lambda n: n / RPM_PER_RAD_S,
                                                     lambda w: w * RPM_PER_RAD_S))
    top.set_xlabel("pinion speed, rad/s")
    for panel in axes:
        panel.grid(True, alpha=0.3)
        panel.legend(loc="upper left", fontsize=8)
    axes[0].set_title(title)
    _save(figure, path)


def plot_parameter_sweep(table, axes_names, path, title) -> None:
    """K_v against one swept quantity (a curve) or over two (a coloured grid map)."""
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(9, 5))
    if len(axes_names) == 1:
        name = axes_names[0]
        axes.plot(table[name], table["K_v"], "o-", color="k", ms=3, label="K_v")
        axes.set_xlabel(name)
        axes.set_ylabel("dynamic factor K_v")
        axes.legend()
        axes.grid(True, alpha=0.3)
    else:
        first, second = axes_names
        grid = table.pivot(index=second, columns=first, values="K_v")
        mesh = axes.pcolormesh(grid.columns, grid.index, grid.to_numpy(), shading="nearest")
        figure.colorbar(mesh, ax=axes, label="dynamic factor K_v")
        axes.set_xlabel(first)
        axes.set_ylabel(second)
    axes.set_title(title)
    _save(figure, path)


def plot_waterfall(table, series, path, natural, z_pinion, title) -> None:
    """Each point's dte amplitude spectrum as a trace at its speed (rpm, upward), scaled so
    the largest peak spans two rows; mesh orders k·z·n/60 and natural frequencies drawn."""
    plt = _pyplot()
    order = np.argsort(table["w0_pinion"].to_numpy())
    rpm = table["speed_rpm"].to_numpy()[order]
    spectra = []
    for i in order:
        interval = float(np.diff(series[i]["time"]).mean())
        spectra.append(amplitude_spectrum(series[i]["dte"] * 1e6, interval))
    largest = max(s[1:].max() for _, s in spectra)
    row = np.diff(rpm).mean() if len(rpm) > 1 else 1.0
    top_frequency = HARMONICS[-1] * z_pinion * rpm.max() / 60.0 * 1.15
    figure, axes = plt.subplots(figsize=(10, 7))
    for n, (frequency, amplitude) in zip(rpm, spectra):
        keep = frequency <= top_frequency
        axes.plot(frequency[keep], n + 2.0 * row * amplitude[keep] / largest, color="k", lw=0.7)
    speeds = np.linspace(0.0, rpm.max() * 1.05, 50)
    for k in HARMONICS:
        axes.plot(k * z_pinion * speeds / 60.0, speeds, color=f"C{3 + k}", lw=0.9, ls="--",
                  label=f"mesh order k = {k} (k·z·n/60)")
    for number, f in enumerate(f for f in natural if 0 < f <= top_frequency):
        axes.axvline(f, color="C2", lw=0.8, ls=":",
                     label="natural frequencies" if number == 0 else None)
    axes.set_xlim(0, top_frequency)
    axes.set_ylim(rpm.min() - row, rpm.max() + 3 * row)
    axes.set_xlabel("frequency, Hz")
    axes.set_ylabel(f"pinion speed, rpm (traces: dte amplitude, largest {largest:.2g} µm)")
    axes.legend(loc="lower right", fontsize=8)
    axes.grid(True, alpha=0.3)
    axes.set_title(title)
    _save(figure, path)
