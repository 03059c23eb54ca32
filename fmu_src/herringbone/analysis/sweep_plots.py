"""Pictures of a sweep: the resonance curve (K_v and dte against speed, with the resonance
speeds of `herringbone info` marked), a parameter curve or grid map, and a waterfall of the
points' dte spectra with the mesh orders and natural frequencies."""
from __future__ import annotations

import numpy as np

from ..model.parameters import RPM_PER_RAD_S, unit_of
from .plots import _legend_beside, _pyplot, _save, amplitude_spectrum, spread_apart
from .report import HARMONICS
from .sweep_point import SETTLED_DRIFT


def is_branch(table) -> bool:
    """A table of sweep's method "shooting" (rows in branch order, a stability column)."""
    return "stability" in table and table["stability"].isin(["stable", "unstable"]).any()


DOUBLED_COLOUR = "C0"  # a period-2 branch's lines on every panel
# How a legend names a table column where its name is not what it shows
HALF_LABEL = "K_v_half (more loaded half)"
SHOWN_AS = {"dte_p2p_um": "dte peak-to-peak", "K_v_half": HALF_LABEL}
HALF_COLOUR = "C1"  # K_v_half's line beside K_v's (black)


# the dots at a branch's orbits (points), small against the time sweeps' triangles (5)
ORBIT_MARKER_SIZE = 2.5


def draw_branch(axes, table, columns, along: str = "speed_rpm") -> None:
    """The branch in its order on each panel (one a column of `columns`) against the column
    `along`: stable stretches solid, unstable dashed, each with a small dot at every orbit
    computed (a straight stretch between two dots is no data), points found by time
    integration as open circles, folds as crosses; rows in branch order (a fold makes the
    speed turn back). A table with period-2 branches (its `branch` column) draws each of
    them so too, in DOUBLED_COLOUR, with the period doublings they start from as
    diamonds."""
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
                       lw=1.3, marker="o", ms=ORBIT_MARKER_SIZE,
                       label=_once(panel, f"{name}, {kind_label}{kind} orbits"))
        timed = stability == "time"
        if timed.any():
            panel.plot(abscissa[timed], values[timed], "o", mfc="none", color=colour, ms=5,
                       label=_once(panel, f"{name}, time integration (no orbit "
                                                 "converged)"))
        folds = table["event"].str.contains("fold").to_numpy()
        if folds.any():
            panel.plot(abscissa[folds], values[folds], "x", color="C3", ms=9, mew=2,
                       label=_once(panel, "fold (jump)"), zorder=4)


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


# K_v_half is drawn, and the sweep's summary names it, where it exceeds K_v by more than this
# share at some point: there K_v, of the whole mesh, reads the more loaded half's dynamic load
# short by that much
HALF_FACTOR_SPREAD = 0.01


def halves_differ(table) -> bool:
    """Whether K_v_half exceeds K_v by more than HALF_FACTOR_SPREAD at some row: the halves
    share the load unevenly (a lead error), K_v of their sum understates the more loaded
    half's peak, and the pictures draw K_v_half beside it."""
    return "K_v_half" in table and bool(
        (table["K_v_half"] > (1.0 + HALF_FACTOR_SPREAD) * table["K_v"]).any())


def draw_k_v(axes, table, along: str, branch: bool) -> None:
    """K_v against the column `along` on one panel (a branch as `draw_branch` draws it), with
    K_v_half in HALF_COLOUR where halves_differ, and an open square at each point where a
    helix half lost contact (mark_contact_loss)."""
    columns = [("K_v", "k")] + ([("K_v_half", HALF_COLOUR)] if halves_differ(table) else [])
    for column, colour in columns:
        if branch:
            draw_branch([axes], table, [(column, colour)], along=along)
        else:
            axes.plot(table[along], table[column], "o-" if column == "K_v" else "s--",
                      color=colour, ms=3, lw=1.0,
                      label="K_v = max F_mesh / F_static" if column == "K_v" else HALF_LABEL)
    mark_contact_loss(axes, table, along, "K_v")


def plot_resonance_curve(table, path, resonances, title, sweeps=None) -> None:
    """K_v (top; K_v_half beside it where the halves differ: draw_k_v) and dte peak-to-peak
    (bottom) against pinion speed, rpm (rad/s on top), the `resonances`
    (excitation.Resonance) marked and labelled (mark_resonances), a square at each point
    where a helix half lost contact. A branch table (sweep's method "shooting") is drawn as
    `draw_branch` says; `sweeps`: time sweeps drawn over it."""
    plt = _pyplot()
    branch = is_branch(table)
    if not branch:
        table = table.sort_values("w0_pinion")
    figure, axes = plt.subplots(2, 1, figsize=(12, 7.5), sharex=True)
    draw_k_v(axes[0], table, "speed_rpm", branch)
    if branch:
        draw_branch(axes[1:], table, [("dte_p2p_um", "C2")])
        draw_time_sweeps(axes, sweeps, [("K_v", "k"), ("dte_p2p_um", "C2")])
    else:
        rpm = table["speed_rpm"].to_numpy()
        axes[1].plot(rpm, table["dte_p2p_um"], "o-", color="C2", ms=3, lw=1.0,
                     label=SHOWN_AS["dte_p2p_um"])
        axes[1].plot(rpm, table["dte_rms_um"], "s-", color="C0", ms=3, lw=1.0, label="dte rms")
    mark_contact_loss(axes[1], table, "speed_rpm", "dte_p2p_um")
    axes[0].set_ylabel("dynamic factor K_v")
    axes[1].set_ylabel("dte, µm")
    axes[1].set_xlabel("pinion speed, rpm")
    mark_resonances(axes, resonances, table["w0_pinion"].min(), table["w0_pinion"].max())
    top = axes[0].secondary_xaxis(LABEL_STRIP, functions=(lambda n: n / RPM_PER_RAD_S,
                                                          lambda w: w * RPM_PER_RAD_S))
    top.set_xlabel("pinion speed, rad/s")
    for panel in axes:
        panel.grid(True, alpha=0.3)
        _legend_beside(panel)  # inside, its entries for the orders k hid the low speeds
    axes[0].set_title(title)
    _save(figure, path)


# rpm between two resonance labels, at least, as a share of the speeds swept; and at least a
# label's height at 7 pt and a gap (LABEL_POINTS) on the panel's width as drawn
LABEL_GAP = 0.018
LABEL_POINTS = 11.0
# the resonance labels stand in a strip above the top panel, off the data (inside the panel
# they cross the K_v curve, and moved apart, each other's lines: the reference scene's lie
# 17 rpm apart at 4102 and 4119 rpm), each joined to its line by a leader; shares of the
# panel's height: where a label's foot is, and where the rad/s axis goes, above the labels
LABEL_FOOT = 1.04
LABEL_STRIP = 1.24


def mark_resonances(axes, found, low, high) -> None:
    """Each resonance k·f_mesh = f_n of `found` (excitation.Resonance, by speed) between the
    speeds low and high (rad/s): a dashed line on every panel, one legend entry per order k
    on the first panel in the order of k, and f_n written above it (LABEL_FOOT), labels moved
    apart where lines lie close (a label's width on the panel as drawn, at least LABEL_GAP of
    the speeds), each joined to its line by a leader."""
    resonances = [(r.speed, r.order, r.frequency) for r in found if low <= r.speed <= high]
    for k in sorted({k for _, k, _ in resonances}):  # the legend's entries, in the order of k
        axes[0].plot([], [], color=f"C{3 + k}", lw=0.8, ls="--", label=f"k·f_mesh = f_n, k = {k}")
    rpm = [speed * RPM_PER_RAD_S for speed, _, _ in resonances]
    for (_, k, _), at in zip(resonances, rpm):
        for panel in axes:
            panel.axvline(at, color=f"C{3 + k}", lw=0.8, ls="--")
    left, right = axes[0].get_xlim()
    width = axes[0].get_position().width * axes[0].figure.get_figwidth() * 72.0  # pt
    gap = max(LABEL_GAP * (high - low) * RPM_PER_RAD_S, LABEL_POINTS / width * (right - left))
    places = spread_apart(rpm, gap, right - 0.5 * gap)
    for (_, k, f), at, place in zip(resonances, rpm, places):
        axes[0].annotate(f" {f:.0f} Hz", (at, 1.0), xytext=(place, LABEL_FOOT), rotation=90,
                         xycoords=("data", "axes fraction"),
                         textcoords=("data", "axes fraction"), fontsize=7, ha="center",
                         va="bottom", color=f"C{3 + k}", annotation_clip=False,
                         arrowprops={"arrowstyle": "-", "color": f"C{3 + k}", "lw": 0.6,
                                     "shrinkA": 0.0, "shrinkB": 0.0})


def plot_parameter_sweep(table, axes_names, path, title) -> None:
    """K_v against one swept quantity (a curve, K_v_half beside it where the halves differ:
    draw_k_v) or over two (a coloured grid map of K_v), a square at each point where a helix
    half lost contact."""
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(9, 5))
    if len(axes_names) == 1:
        name = axes_names[0]
        draw_k_v(axes, table, name, is_branch(table))
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
CONTACT_LOST_COLOUR = "0.55"  # grey: beside the folds' red and the time sweeps' colours


def mark_contact_loss(axes, table, x: str, y: str, colour: str = CONTACT_LOST_COLOUR) -> bool:
    """A small open square under the curve at each point of `table` where a helix half lost
    contact in its window or orbit (contact_lost_share > 0), at its columns (x, y); whether
    there was one. Without it the picture showed nothing of the loss the summary reported;
    drawn large, red and over the curve, it hid jump_resonance's unstable branch and folds."""
    if "contact_lost_share" not in table:
        return False
    lost = (table["contact_lost_share"] > 0).to_numpy()
    if lost.any():
        axes.plot(table[x].to_numpy()[lost], table[y].to_numpy()[lost], "s", ms=6,
                  mfc="none", mew=0.7, color=colour, ls="none", label=CONTACT_LOST, zorder=1.5)
    return bool(lost.any())


def _axis_label(name: str) -> str:
    """A swept quantity's axis label: its name and unit (w0_pinion, a parameter or a torque)."""
    unit = unit_of(name)
    return f"{name}, {unit}" if unit else name


# the frequency axis of a waterfall runs this far past its highest mode or mesh order drawn
WATERFALL_MARGIN = 1.1
# a waterfall's peaks are a few bins of its widest trace's (the Hann window's main lobe,
# 4/50 of a mesh order over a window of 50 mesh periods: 53 Hz at 4000 rpm), on an axis
# to the fastest mode (15 kHz on the reference scene): at 110 dpi that is 3 pixels, too
# few for a peak's fill to hide the rows behind it; at 200 dpi 6
WATERFALL_DPI = 200


def waterfall_top(rpm, nyquists, natural, z_pinion) -> tuple[float, list[float]]:
    """(the waterfall's top frequency, Hz; the natural frequencies above it): past the
    highest mesh order drawn at the top speed and the fastest mode, where the mesh force
    rings most (10.4 and 13.4 kHz on the reference scene, whose third order ends at 4.5 kHz
    at 9000 rpm), unless the fastest-sampled trace ends below: its Nyquist frequency (half
    its sampling rate; `nyquists`, Hz, one a trace) is then the top, and the modes above it
    are the ones no trace can show."""
    wanted = WATERFALL_MARGIN * max([HARMONICS[-1] * z_pinion * max(rpm) / 60.0,
                                     *(f for f in natural if f > 0)])
    top = min(wanted, max(nyquists))
    return top, [f for f in natural if f > top]


def waterfall_traces(axes, rpm, spectra, per_um, top) -> None:
    """Each spectrum (frequency, amplitude µm) as a trace at its speed (rpm), height per_um
    rpm a µm, up to `top` Hz or its own Nyquist frequency. The area under each trace is
    filled with the background, and the lower (nearer) rows drawn over the higher: a peak
    that rises past the rows above hides them where it stands (a hidden-line waterfall),
    instead of showing through as if they rang there. The reference lines lie behind."""
    for number, (n, (frequency, amplitude)) in enumerate(zip(rpm, spectra)):
        keep = frequency <= top
        depth = 2.0 * (len(rpm) - number)  # the lowest speed is the nearest row
        axes.fill_between(frequency[keep], n, n + per_um * amplitude[keep], color="white",
                          lw=0.0, zorder=depth)
        axes.plot(frequency[keep], n + per_um * amplitude[keep], color="k", lw=0.7,
                  zorder=depth + 1.0)


def waterfall_reference_lines(axes, rpm, natural, z_pinion, top) -> None:
    """The mesh orders k·z·n/60 (k in HARMONICS) and the natural frequencies up to `top` Hz,
    behind every trace (zorder 1)."""
    speeds = np.linspace(0.0, max(rpm), 50)
    for k in HARMONICS:
        axes.plot(k * z_pinion * speeds / 60.0, speeds, color=f"C{3 + k}", lw=0.9, ls="--",
                  label=f"mesh order k = {k} (k·z·n/60)", zorder=1)
    for number, f in enumerate(f for f in natural if 0 < f <= top):
        axes.axvline(f, color="C2", lw=0.8, ls=":", zorder=1,
                     label="natural frequencies" if number == 0 else None)


def waterfall_scale_bar(axes, low: float, per_um: float, largest: float) -> None:
    """A bar of 1, 2 or 5 × 10^n µm of amplitude beside the plot, from the row at `low` rpm
    (per_um rpm of trace height a µm), no longer than the largest peak (µm)."""
    from matplotlib.transforms import blended_transform_factory

    bar = 10.0 ** np.floor(np.log10(largest))
    bar *= max(m for m in (1, 2, 5) if m * bar <= largest)
    beside = blended_transform_factory(axes.transAxes, axes.transData)
    axes.plot([1.02, 1.02], [low, low + per_um * bar], color="k", lw=2.0,
              transform=beside, clip_on=False)
    axes.text(1.03, low + 0.5 * per_um * bar, f"{bar:g} µm\ndte amplitude",
              transform=beside, va="center", ha="left", fontsize=8)


def frequency_label(top, nyquists, beyond, rpm, z_pinion) -> str:
    """The waterfall's frequency axis label: where traces end at their Nyquist frequency
    before `top` (Hz), how many samples a mesh period that is, and the modes (`beyond`, Hz)
    that lie above every trace's."""
    label = "frequency, Hz"
    if min(nyquists) < top:
        samples = round(2.0 * nyquists[-1] / (z_pinion * rpm[-1] / 60.0))
        label += (f"\neach trace ends at its Nyquist frequency: {samples} samples a mesh "
                  f"period, {samples // 2} mesh orders")
    if beyond:
        label += (f"; modes at {', '.join(f'{f:.0f}' for f in beyond)} Hz above every "
                  "trace's")
    return label


def plot_waterfall(table, series, path, natural, z_pinion, title) -> None:
    """Each point's dte amplitude spectrum as a trace at its speed (rpm, upward), scaled so
    the largest peak spans two rows, filled beneath and drawn front (low speed) to back so
    that each hides what lies behind it (waterfall_traces), with a scale bar of amplitude
    beside the plot; mesh orders k·z·n/60 and natural frequencies drawn. The frequency axis
    reaches the fastest mode where the sampling resolves it (waterfall_top), and its label
    says where traces stop short of it. The speed axis spans the sweep's speeds."""
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
    nyquists = [float(frequency[-1]) for frequency, _ in spectra]
    top, beyond = waterfall_top(rpm, nyquists, natural, z_pinion)
    figure, axes = plt.subplots(figsize=(11, 7))
    waterfall_traces(axes, rpm, spectra, per_um, top)
    waterfall_reference_lines(axes, rpm, natural, z_pinion, top)
    axes.set_xlim(0, top)
    axes.set_ylim(rpm.min() - 0.5 * row, rpm.max() + 2.2 * row)  # room for the top trace
    axes.set_yticks([t for t in axes.get_yticks() if rpm.min() <= t <= rpm.max()])
    axes.spines["left"].set_bounds(rpm.min(), rpm.max())
    waterfall_scale_bar(axes, rpm.min(), per_um, largest)
    axes.set_xlabel(frequency_label(top, nyquists, beyond, rpm, z_pinion))
    axes.set_ylabel("pinion speed, rpm (each trace: the dte amplitude spectrum at that speed)")
    _legend_beside(axes)
    axes.grid(True, alpha=0.3)
    axes.set_title(title)
    _save(figure, path, dpi=WATERFALL_DPI)
