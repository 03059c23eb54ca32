"""What `herringbone sweep` prints and writes: the table as CSV, the resonance curve (speed
sweeps) or parameter plot, the waterfall of dte spectra (one-axis speed sweeps by time
integration: a branch of periodic orbits has no window to show)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..files import replace_file
from ..model.parameters import RPM_PER_RAD_S, name_with_unit, unit_of, with_unit
from .campbell import elastic_frequencies
from .excitation import resonances
from .sweep import SPEED, point_label, resonation_summary, swept_columns
from .sweep_plots import (
    halves_differ,
    is_branch,
    plot_parameter_sweep,
    plot_resonance_curve,
    plot_waterfall,
)
from .sweep_point import SETTLED_DRIFT


def write_outputs(scene, table, series, folder: Path, time_sweeps=None,
                  name: str | None = None) -> list[Path]:
    """CSV, then the plots that fit the sweep's axes; returns the paths written. `series`:
    each point's window (None for a branch: no waterfall); `time_sweeps`: {"up": table,
    "down": table} of chained time sweeps drawn over a branch's resonance curve; `name`: what
    the files and titles call the scene (None: its name)."""
    folder.mkdir(parents=True, exist_ok=True)
    names = swept_columns(table)
    name = scene.name if name is None else name
    stem = folder / f"{name}_sweep_{'_'.join(names)}"
    written = [_write_table(Path(f"{stem}.csv"), table, names)]
    # the chained time sweeps beside the branch: drawn on its curve, and their figures kept
    written += [_write_table(Path(f"{stem}_time_{direction}.csv"), swept, names)
                for direction, swept in (time_sweeps or {}).items()]
    natural, z = elastic_frequencies(scene), scene.parameters["z_pinion"]
    if names == [SPEED]:
        curve, waterfall = Path(f"{stem}_resonance.png"), Path(f"{stem}_waterfall.png")
        plot_resonance_curve(table, curve, ringing(scene, table),
                             f"{name}: dynamic factor against speed", sweeps=time_sweeps)
        written.append(curve)
        if series is not None:
            plot_waterfall(table, series, waterfall, natural, z,
                           f"{name}: dte spectra over the sweep (waterfall)")
            written.append(waterfall)
    else:
        picture = Path(f"{stem}.png")
        plot_parameter_sweep(table, names, picture, f"{name}: K_v over "
                             f"{' and '.join(names)}{fixed_speed(table)}")
        written.append(picture)
    return written


def _write_table(path: Path, table, names) -> Path:
    """The table as CSV at `path`, the swept columns (`names`) with their units (the others
    name theirs: speed_rpm, F_mesh_max_N); returns the path."""
    named = table.rename(columns={column: name_with_unit(column) for column in names})
    replace_file(path, lambda staging: named.to_csv(staging, index=False, float_format="%.10g"))
    return path


def fixed_speed(table) -> str:
    """" at 500 rad/s (4775 rpm)": the pinion speed of a sweep that holds it, for its
    picture's title; "" where the speed varies (one of the swept quantities)."""
    speeds = table["speed_rpm"].unique()
    if len(speeds) != 1:
        return ""
    rpm = float(speeds[0])
    return f" at {rpm / RPM_PER_RAD_S:.6g} rad/s ({rpm:.0f} rpm)"


def describe(scene, table, wall: float, through_fmu: bool = False, time_sweeps=None) -> str:
    """The summary printed after a sweep (`through_fmu`: its points ran through a gear FMU;
    `time_sweeps`: {"up": table, "down": table} of chained time sweeps run beside it)."""
    lines = [f"sweep of {scene.name}: {len(table)} points in {wall:.1f} s of wall time",
             *(_branch_lines(table) if by_shooting(table) else _time_lines(table)),
             *_k_v_lines(table)]
    lines += _unsettled_lines(table, "")
    for direction, swept in (time_sweeps or {}).items():
        lines += _unsettled_lines(swept, f" of the time sweep {direction}")
    if through_fmu:
        lines.append("through the FMU: the figures are those of the FMU's outputs at the "
                     "recorded samples, which read the ringing's peaks after each contact "
                     "switch low (without --through-fmu they resolve it)")
    if SPEED in swept_columns(table) and len(swept_columns(table)) == 1:
        lines += [f"resonance k·f_mesh = f_n at {r.speed * RPM_PER_RAD_S:.0f} rpm "
                  f"({r.speed:.1f} rad/s): k = {r.order}, f_n = {r.frequency:.1f} Hz, its "
                  f"harmonic {100 * r.strength:.1f} % of the static force"
                  + _unresolved(scene, table[SPEED].to_numpy(), r)
                  for r in ringing(scene, table)]
    if (table["contact_lost_share"] > 0).any():
        lost = int((table["contact_lost_share"] > 0).sum())
        lines.append(f"a helix half out of contact at {lost} point{'s' if lost != 1 else ''} "
                     "(contact_lost_share > 0)")
    return "\n".join(lines)


def _unresolved(scene, speeds, resonance) -> str:
    """Where the sweep's computed `speeds` (rad/s) about a `resonance` lie further apart than
    its width (±ζ of its speed, ζ its mode's damping ratio): that its peak may lie between
    them, and a sweep about it that would resolve it; '' where they do not."""
    below, above = speeds[speeds <= resonance.speed], speeds[speeds >= resonance.speed]
    if not len(below) or not len(above):
        return ""
    low, high = below.max(), above.min()
    if high - low <= 2.0 * resonance.damping * resonance.speed:
        return ""
    around = (f"{resonance.speed * (1 - RESOLVE_SPAN):.4g} "
              f"{resonance.speed * (1 + RESOLVE_SPAN):.4g} {RESOLVE_COUNT}")
    return (f"; the nearest points computed, {low:.4g} and {high:.4g} rad/s, lie further apart "
            f"than its width (±{100 * resonance.damping:.2g} %): its peak may lie between "
            f"them (`herringbone sweep {scene.name} --speeds {around}` looks there)")


# the sweep an unresolved resonance's line proposes: ±RESOLVE_SPAN of its speed (a peak of
# the nonlinear train lies up to a few per cent off the linear estimate), RESOLVE_COUNT speeds
RESOLVE_SPAN = 0.05
RESOLVE_COUNT = 20


def ringing(scene, table):
    """The resonances in the sweep's speeds that ring (excitation.resonances: the mesh force's
    harmonic there 2 % of the static force or more, k up to 16), by speed."""
    return resonances(scene, table[SPEED].min(), table[SPEED].max())


def _unsettled_lines(table, which: str) -> list[str]:
    """The points of a table (`which`: of which sweep, in words) whose window had not settled
    (window_drift over SETTLED_DRIFT): their figures are of a transient, not a steady state."""
    if "window_drift" not in table:
        return []
    unsettled = table[table["window_drift"] > SETTLED_DRIFT]
    if unsettled.empty:
        return []
    names = swept_columns(table)
    where = "; ".join(point_label(row, names, rpm=False) for _, row in unsettled.iterrows())
    return [f"not settled at {len(unsettled)} point{'s' if len(unsettled) > 1 else ''}{which} "
            f"({where}): the mesh force still changed by more than {SETTLED_DRIFT:.0%} of the "
            "static force over the window, so their figures are of a transient; give a longer "
            "--settle-time"]


def _k_v_lines(table) -> list[str]:
    """K_v's range and where it is largest, over what a run settles on: on a branch its stable
    orbits (and the points by time integration), not the unstable ones; and the more loaded
    helix half's factor (`_half_lines`)."""
    where = ""
    gaps = _lost_gaps(_single_branch(table), table.attrs.get("continued", SPEED)) \
        if by_shooting(table) else []
    if is_branch(table) and (table["stability"] != "unstable").any():
        table = table[table["stability"] != "unstable"]
        where = (" (stable orbits and points by time integration)"
                 if (table["stability"] == "time").any() else " (stable orbits)")
    unseen = "".join(f"; nothing computed from {lost} to {found}, where the branch was lost: a "
                     "peak there is not in these figures" for lost, found in gaps)
    return [f"K_v from {table['K_v'].min():.4f} to {table['K_v'].max():.4f}{where}; "
            f"largest at {resonation_summary(table)}{unseen}", *_peak_lines(table),
            *_half_lines(table, where)]


def _peak_lines(table) -> list[str]:
    """The peaks of K_v over the speed of a speed sweep (rows as _k_v_lines took them, along
    the mesh-periodic branch or by speed): the rows whose K_v exceeds both neighbours',
    largest first, at most PEAKS_LISTED; none for another sweep, or where there is no such
    row."""
    if swept_columns(table) != [SPEED]:
        return []
    ordered = _single_branch(table) if is_branch(table) else table.sort_values(SPEED)
    k_v, speeds = ordered["K_v"].to_numpy(), ordered[SPEED].to_numpy()
    peaks = [i for i in range(1, len(k_v) - 1) if k_v[i - 1] < k_v[i] >= k_v[i + 1]]
    peaks = sorted(peaks, key=lambda i: -k_v[i])[:PEAKS_LISTED]
    if not peaks:
        return []
    return ["peaks of K_v (largest first; a peak between the points computed is not among "
            "them): " + ", ".join(f"{k_v[i]:.4f} at {speeds[i]:.6g} rad/s" for i in peaks)]


PEAKS_LISTED = 8  # the peaks of K_v a speed sweep's summary names


def _half_lines(table, where: str) -> list[str]:
    """K_v_half's range and the left half's share of the load, where at some point K_v_half
    exceeds K_v by more than HALF_FACTOR_SPREAD (sweep_plots.halves_differ): the halves share
    the load unevenly (a lead error), and K_v, of the two halves' sum, understates the more
    loaded half's peak. `where`: which rows, in words, as _k_v_lines took them."""
    if not halves_differ(table):
        return []
    half, share = table["K_v_half"], 100.0 * table["load_share_left"]
    shares = (f"{share.min():.1f}" if f"{share.min():.1f}" == f"{share.max():.1f}"
              else f"{share.min():.1f}-{share.max():.1f}")
    return [f"K_v_half from {half.min():.4f} to {half.max():.4f}{where}, largest at "
            f"{resonation_summary(table, 'K_v_half')}: the more loaded helix half, its peak over "
            f"half the static force (what a tooth bears, where K_v, of the two halves' sum, may "
            f"fall); the left half carries {shares} % of the load (load_share_left)"]


def by_shooting(table) -> bool:
    """Whether a table is sweep's method "shooting" (a branch table: on_grid, attrs
    "continued"), whatever its rows' stability: where no orbit converged at any point, all
    its rows are "time" and it still has no settle or window columns."""
    return "on_grid" in table or "continued" in table.attrs or is_branch(table)


def _time_lines(table) -> list[str]:
    if not {"settle_time_s", "window_time_s", "samples"} <= set(table.columns):
        return []  # a table of other figures: nothing to say about settling
    settle, window = table["settle_time_s"], table["window_time_s"]
    return [f"settle {settle.min():.4g}-{settle.max():.4g} s per point (start-up transient of "
            "the least-damped mode decayed, and longer where the window had not yet repeated), "
            "then a window of "
            f"{int(table['samples'].iloc[0])} samples, {window.min():.4g}-{window.max():.4g} s"]


def _branch_lines(table) -> list[str]:
    doubled = ((table["mesh_periods"] > 1).to_numpy() if "mesh_periods" in table
               else np.zeros(len(table), dtype=bool))
    counts = table["stability"][~doubled].value_counts()
    name = table.attrs.get("continued", SPEED)
    unconverged = counts.get("time", 0)
    lines = [f"periodic steady state by shooting and continuation: {counts.get('stable', 0)} "
             f"stable, {counts.get('unstable', 0)} unstable orbits"
             + (f"; {unconverged} points where no orbit converged, run by time integration"
                if unconverged else "")]
    lines += _values_line(f"folds (jumps) in {name}", table.attrs.get("folds", []), name)
    lines += [f"the branch was lost past {lost}: no orbit followed on to {found}, where "
              "shooting began again (nothing computed between them)"
              for lost, found in _lost_gaps(_single_branch(table), name)]
    doublings = table.attrs.get("period_doublings", [])
    if len(doublings):
        counts = table["stability"][doubled].value_counts()
        lines += _values_line(f"period doublings in {name}", doublings, name)
        lines.append(f"their 2T branches: {counts.get('stable', 0)} stable, "
                     f"{counts.get('unstable', 0)} unstable orbits")
        lines += _values_line("folds of the 2T branches", table.attrs.get("folds_2T", []),
                              name)
    return lines


def _single_branch(table):
    """A shooting table's rows of the mesh-periodic branch (not the period-doubled ones)."""
    if "mesh_periods" not in table:
        return table
    return table[(table["mesh_periods"] <= 1).to_numpy()]


def _lost_gaps(table, name: str) -> list[tuple[str, str]]:
    """Where the branch (rows in its order) was lost, as (lost, found) values of the quantity
    `name` with their unit: from the furthest of its orbits before each "restart" row (where
    it could not go on, or turned back at a fold) to that row, where shooting began again;
    nothing was computed between."""
    gaps = []
    stability, values = table["stability"].to_numpy(), table[name].to_numpy()
    for row in np.flatnonzero(table["event"].str.contains("restart").to_numpy()):
        orbits = np.flatnonzero(np.isin(stability[:row], ("stable", "unstable")))
        if len(orbits):
            lost, found = (with_unit(f"{value:.6g}", unit_of(name))
                           for value in (values[orbits].max(), values[row]))
            gaps.append((lost, found))
    return gaps


def _values_line(what: str, values, name: str) -> list[str]:
    """"<what> at v1, v2 (unit)" for the values of the quantity `name`, or nothing."""
    if not len(values):
        return []
    return [f"{what} at " + ", ".join(with_unit(f"{value:.6g}", unit_of(name))
                                      for value in values)]
