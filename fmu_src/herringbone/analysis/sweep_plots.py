"""Pictures of a sweep: the resonance curve (K_v and dte against speed, with the resonance
speeds of `herringbone info` marked), a parameter curve or grid map, and a waterfall of the
points' dte spectra with the mesh orders and natural frequencies."""
from __future__ import annotations

import math

import numpy as np

from ..model.parameters import RPM_PER_RAD_S, unit_of
from .plots import _pyplot, _save, amplitude_spectrum, spread_apart
from .report import HARMONICS, resonance_speeds
from .sweep_point import SETTLED_DRIFT


def resonances_between(frequencies, z_pinion, low, high):
    """[(speed rad/s, k, f_n Hz)] with k·f_mesh = f_n for speeds in [low, high]."""
    return sorted((speed, k, f) for f in frequencies if f > 0
                  for k, speed in resonance_speeds(f, z_pinion).items() if low <= speed <= high)


def is_branch(table) -> bool:
    """A table of sweep's method "shooting" (rows in branch order, a stability column)."""
    return "stability" in table and table["stability"].isin(["stable", "unstable"]).any()


DOUBLED_COLOUR = "C0"  # a period-2 branch's lines on every panel
# How a legend names a table column where its name is not what it shows
SHOWN_AS = {"dte_p2p_um": "dte peak-to-peak"}


def draw_branch(axes, table, columns, along: str = "speed_rpm") -> None:
    """The branch in its order on each panel (one a column of `columns`) against the column
    `along`: stable stretches solid, unstable dashed, points found by time integration as open
    circles, folds as crosses; rows in branch order (a fold makes the speed turn back). A
    table with period-2 branches (its `branch` column) draws each of them so too, in
    DOUBLED_COLOUR, with the period doublings they start from as diamonds."""
    numbers = table["branch"].to_numpy() if "branch" in table else np.zeros(len(table), int)
    for number in np.unique(numbers):
        part = table[numbers == number]
        doubled = number > 0
        shown = [(column, DOUBLED_COLOUR if doubled else colour) for column, colour in columns]
        draw_one_branch(axes, part, shown, along, "period 2T, " if doubled else "")
        if doubled:
            for panel, (column, _) in zip(axes, columns):
                panel.plot(part[along].iloc[:1], part[column].iloc[:1], "D", ms=6,
                           color=DOUBLED_COLOUR, mfc="none",
                           label=_once(panel, "period doubling"))


def draw_one_branch(axes, table, columns, along: str, kind_label: str) -> None:
    """One branch of draw_branch's (rows in its order); each kind of line gets one legend
    entry on a panel, however many branches draw it."""
    abscissa = table[along].to_numpy()
    stability = table["stability"].to_numpy()
    # where the branch was lost and shooting began again, no line: nothing was computed there
    gaps = np.flatnonzero(table["event"].str.contains("restart").to_numpy())
    for panel, (column, colour) in zip(axes, columns):
        values, name = table[column].to_numpy(), SHOWN_AS.get(column, column)
        for kind, style in (("stable", "-"), ("unstable", "--")):
            if not (stability == kind).any():
                continue  # no legend entry for a line the picture does not have
            # each stretch drawn to the next orbit, so that stretches join; not into a point
            # run by time integration, which is no orbit of the branch
            orbit = np.isin(stability, ("stable", "unstable"))
            shown = (stability == kind) | (np.r_[False, stability[:-1] == kind] & orbit)
            masked = np.where(shown, values, np.nan)
            panel.plot(np.insert(abscissa.astype(float), gaps, np.nan),
                       np.insert(masked.astype(float), gaps, np.nan), style, color=colour,
                       lw=1.3, label=_once(panel, f"{name}, {kind_label}{kind} orbits"))
        timed = stability == "time"
        if timed.any():
            panel.plot(abscissa[timed], values[timed], "o", mfc="none", color=colour, ms=5,
                       label=_once(panel, f"{name}, time integration (no orbit "
                                                 "converged)"))
        folds = table["event"].str.contains("fold").to_numpy()
        if folds.any():
            panel.plot(abscissa[folds], values[folds], "x", color="C3", ms=9, mew=2,
                       label=_once(panel, "fold (jump)"))


def _once(panel, label: str) -> str | None:
    """`label`, or None where a line of the panel already carries it (one legend entry)."""
    return None if label in [line.get_label() for line in panel.get_lines()] else label


def draw_time_sweeps(axes, sweeps, columns) -> None:
    """Time-integration sweeps over the curve, e.g. {"up": table, "down": table} from
    sweep.chained_time_sweep: triangles pointing the way each went, open where the point had
    not settled (window_drift over SETTLED_DRIFT: its figures are of a transient)."""
    for name, table in (sweeps or {}).items():
        rising = table["w0_pinion"].iloc[-1] >= table["w0_pinion"].iloc[0]
        unsettled = (table["window_drift"] > SETTLED_DRIFT).to_numpy() \
            if "window_drift" in table else np.zeros(len(table), dtype=bool)
        for panel, (column, _) in zip(axes, columns):
            for chosen, face, label in ((~unsettled, None, "each point from the last"),
                                        (unsettled, "none", "not settled")):
                if chosen.any():
                    panel.plot(table["speed_rpm"][chosen], table[column][chosen],
                               "^" if rising else "v", color="C1" if rising else "C4", ms=5,
                               ls="none", mfc=face, label=f"time sweep {name} ({label})")


def plot_resonance_curve(table, path, natural, z_pinion, title, sweeps=None) -> None:
    """K_v (top) and dte peak-to-peak (bottom) against pinion speed, rpm (rad/s on top), each
    resonance k·f_mesh = f_n in the range marked and labelled. A branch table (sweep's method
    "shooting") is drawn as `draw_branch` says; `sweeps`: time sweeps drawn over it."""
    plt = _pyplot()
    branch = is_branch(table)
    if not branch:
        table = table.sort_values("w0_pinion")
    rpm = table["speed_rpm"].to_numpy()
    figure, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    if branch:
        columns = [("K_v", "k"), ("dte_p2p_um", "C2")]
        draw_branch(axes, table, columns)
        draw_time_sweeps(axes, sweeps, columns)
    else:
        axes[0].plot(rpm, table["K_v"], "o-", color="k", ms=3, lw=1.0,
                     label="K_v = max F_mesh / F_static")
        axes[1].plot(rpm, table["dte_p2p_um"], "o-", color="C2", ms=3, lw=1.0,
                     label=SHOWN_AS["dte_p2p_um"])
        axes[1].plot(rpm, table["dte_rms_um"], "s-", color="C0", ms=3, lw=1.0, label="dte rms")
    axes[0].set_ylabel("dynamic factor K_v")
    axes[1].set_ylabel("dte, µm")
    axes[1].set_xlabel("pinion speed, rpm")
    mark_resonances(axes, natural, z_pinion, table["w0_pinion"].min(),
                    table["w0_pinion"].max())
    top = axes[0].secondary_xaxis("top", functions=(lambda n: n / RPM_PER_RAD_S,
                                                     lambda w: w * RPM_PER_RAD_S))
    top.set_xlabel("pinion speed, rad/s")
    for panel in axes:
        panel.grid(True, alpha=0.3)
        panel.legend(loc="upper left", fontsize=8)
    axes[0].set_title(title)
    _save(figure, path)


# rpm between two resonance labels, as a share of the speeds swept: a label's height at 7 pt
LABEL_GAP = 0.018


def mark_resonances(axes, natural, z_pinion, low, high) -> None:
    """Each resonance k·f_mesh = f_n between the speeds low and high (rad/s): a dashed line
    on every panel, one legend entry per order k in the order of k, and f_n written at the
    foot of the first panel, labels moved apart where lines lie close."""
    resonances = resonances_between(natural, z_pinion, low, high)
    for k in sorted({k for _, k, _ in resonances}):
        for panel in axes:  # the legend's entries, in the order of k
            panel.plot([], [], color=f"C{3 + k}", lw=0.8, ls="--",
                       label=f"k·f_mesh = f_n, k = {k}")
    rpm = [speed * RPM_PER_RAD_S for speed, _, _ in resonances]
    places = spread_apart(rpm, LABEL_GAP * (high - low) * RPM_PER_RAD_S, math.inf)
    for (_, k, f), at, place in zip(resonances, rpm, places):
        for panel in axes:
            panel.axvline(at, color=f"C{3 + k}", lw=0.8, ls="--")
        axes[0].annotate(f" {f:.0f} Hz", (at, 0.0), xytext=(place, 0.0), rotation=90,
                         xycoords=("data", "axes fraction"),
                         textcoords=("data", "axes fraction"), fontsize=7, ha="right",
                         va="bottom", color=f"C{3 + k}")


def plot_parameter_sweep(table, axes_names, path, title) -> None:
    """K_v against one swept quantity (a curve; a branch table as `draw_branch` draws it) or
    over two (a coloured grid map)."""
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(9, 5))
    if len(axes_names) == 1:
        name = axes_names[0]
        if is_branch(table):
            draw_branch([axes], table, [("K_v", "k")], along=name)
        else:
            axes.plot(table[name], table["K_v"], "o-", color="k", ms=3, label="K_v")
        mark_contact_loss(axes, table, name, "K_v")
        axes.set_xlabel(_axis_label(name))
        axes.set_ylabel("dynamic factor K_v")
        axes.legend()
        axes.grid(True, alpha=0.3)
    else:
        first, second = axes_names
        grid = table.pivot(index=second, columns=first, values="K_v")
        mesh = axes.pcolormesh(grid.columns, grid.index, grid.to_numpy(), shading="nearest")
        figure.colorbar(mesh, ax=axes, label="dynamic factor K_v")
        if mark_contact_loss(axes, table, first, second, colour="w"):
            axes.legend(fontsize=8)
        axes.set_xlabel(_axis_label(first))
        axes.set_ylabel(_axis_label(second))
    axes.set_title(title)
    _save(figure, path)


CONTACT_LOST = "a helix half out of contact (contact_lost_share > 0)"


def mark_contact_loss(axes, table, x: str, y: str, colour: str = "C3") -> bool:
    """An open square at each point of `table` where a helix half lost contact in its window
    or orbit (contact_lost_share > 0), at its columns (x, y); whether there was one. Without
    it the picture showed nothing of the loss the summary reported."""
    if "contact_lost_share" not in table:
        return False
    lost = (table["contact_lost_share"] > 0).to_numpy()
    if lost.any():
        axes.plot(table[x].to_numpy()[lost], table[y].to_numpy()[lost], "s", ms=8,
                  mfc="none", mew=1.2, color=colour, ls="none", label=CONTACT_LOST)
    return bool(lost.any())


def _axis_label(name: str) -> str:
    """A swept quantity's axis label: its name and unit (w0_pinion, a parameter or a torque)."""
    unit = unit_of(name)
    return f"{name}, {unit}" if unit else name


def plot_waterfall(table, series, path, natural, z_pinion, title) -> None:
    """Each point's dte amplitude spectrum as a trace at its speed (rpm, upward), scaled so
    the largest peak spans two rows, with a scale bar of amplitude beside the plot; mesh orders
    k·z·n/60 and natural frequencies drawn. The speed axis spans the sweep's speeds."""
    from matplotlib.transforms import blended_transform_factory

    plt = _pyplot()
    order = np.argsort(table["w0_pinion"].to_numpy())
    rpm = table["speed_rpm"].to_numpy()[order]
    spectra = []
    for i in order:
        interval = float(np.diff(series[i]["time"]).mean())
        spectra.append(amplitude_spectrum(series[i]["dte"] * 1e6, interval))
    largest = max(s[1:].max() for _, s in spectra)
    row = np.diff(rpm).mean() if len(rpm) > 1 else 1.0
    per_um = 2.0 * row / largest  # rpm of trace height per µm of amplitude
    top_frequency = HARMONICS[-1] * z_pinion * rpm.max() / 60.0 * 1.15
    figure, axes = plt.subplots(figsize=(11, 7))
    for n, (frequency, amplitude) in zip(rpm, spectra):
        keep = frequency <= top_frequency
        axes.plot(frequency[keep], n + per_um * amplitude[keep], color="k", lw=0.7)
    speeds = np.linspace(0.0, rpm.max(), 50)
    for k in HARMONICS:
        axes.plot(k * z_pinion * speeds / 60.0, speeds, color=f"C{3 + k}", lw=0.9, ls="--",
                  label=f"mesh order k = {k} (k·z·n/60)")
    for number, f in enumerate(f for f in natural if 0 < f <= top_frequency):
        axes.axvline(f, color="C2", lw=0.8, ls=":",
                     label="natural frequencies" if number == 0 else None)
    axes.set_xlim(0, top_frequency)
    axes.set_ylim(rpm.min() - 0.5 * row, rpm.max() + 2.2 * row)  # room for the top trace
    axes.set_yticks([t for t in axes.get_yticks() if rpm.min() <= t <= rpm.max()])
    axes.spines["left"].set_bounds(rpm.min(), rpm.max())
    bar = 10.0 ** np.floor(np.log10(largest))
    bar *= max(m for m in (1, 2, 5) if m * bar <= largest)
    beside = blended_transform_factory(axes.transAxes, axes.transData)
    axes.plot([1.02, 1.02], [rpm.min(), rpm.min() + per_um * bar], color="k", lw=2.0,
              transform=beside, clip_on=False)
    axes.text(1.03, rpm.min() + 0.5 * per_um * bar, f"{bar:g} µm\ndte amplitude",
              transform=beside, va="center", ha="left", fontsize=8)
    axes.set_xlabel("frequency, Hz")
    axes.set_ylabel("pinion speed, rpm (each trace: the dte amplitude spectrum at that speed)")
    axes.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    axes.grid(True, alpha=0.3)
    axes.set_title(title)
    _save(figure, path)
