"""`herringbone stability SCENE`: the Floquet chart of a scene's linear mesh against pinion
speed, with its unstable bands."""
from __future__ import annotations

import math
from pathlib import Path

from ..model.parameters import RPM_PER_RAD_S
from ..optional import require
from .common import (
    add_output,
    add_progress,
    add_scene,
    add_settings,
    add_speeds,
    changed_name,
    default_output,
    progress_of,
    scene_of,
    speeds_of,
)

NAME = "stability"
HELP = ("Floquet chart: the largest Floquet exponent of the linear mesh (1/s: > 0 grows, < 0 "
        "decays) against pinion speed, with its unstable bands (a picture and a list of the "
        "bands)")
PICTURES = (".png", ".pdf", ".svg")


def declare(parser) -> None:
    """The options of `stability`."""
    add_scene(parser)
    add_settings(parser)
    add_speeds(parser, (50.0, 3000.0, 300), "the chart's speeds")
    add_output(parser, "the chart; an existing file is replaced",
               "results/<scene>_stability.png", PICTURES)
    add_progress(parser)


def execute(args, parser) -> int:
    """Chart the speeds, write the picture, print the bands."""
    from ..analysis.progress_bar import progress_bar
    from ..analysis.stability import plot_stability_chart, stability_chart

    sweep = speeds_of(args, parser)
    assert sweep is not None  # the command has default speeds
    scene = scene_of(args, parser)
    name = changed_name(scene, args)
    output = default_output(parser, args.output, Path("results") / f"{name}_stability.png",
                            PICTURES)
    require("matplotlib", "the stability chart")
    speeds = sweep.speeds()
    with progress_bar(len(speeds), f"stability {scene.name}", progress_of(args),
                      unit="speed") as bar:
        chart = stability_chart(scene, speeds, on_progress=bar.update)
    output.parent.mkdir(parents=True, exist_ok=True)
    plot_stability_chart(chart, output, title=f"{name}: parametric stability")
    print("\n".join(summary(chart)))
    print(f"chart written to {output}")
    return 0


def summary(chart) -> list[str]:
    """The chart in lines: the exponent's span, what it means at the speeds (decay, neither
    growth nor decay within rounding, growth), the unstable bands (to the digits their
    bisection holds)."""
    exponent, speeds, neutral = chart.largest_exponent, chart.speeds, chart.neutral
    decaying = ~neutral & (chart.largest_modulus < 1.0)
    lines = [f"largest Floquet exponent from {exponent.min():.6g} to {exponent.max():.6g} 1/s "
             f"over {speeds[0]:g}-{speeds[-1]:g} rad/s (|λ|max per mesh period from "
             f"{chart.largest_modulus.min():.6g} to {chart.largest_modulus.max():.6g})"]
    if decaying.all():
        lines.append("below zero at every speed: every disturbance decays")
    else:
        if decaying.any():
            lines.append(f"below zero at {decaying.sum()} of {len(speeds)} speeds: there every "
                         "disturbance decays")
        if neutral.any():
            lines.append(f"zero within rounding (at most {chart.exponent_resolution.max():.2g} "
                         f"1/s) at {neutral.sum()} of {len(speeds)} speeds: there the slowest "
                         "disturbance neither grows nor decays, no damping reaches it (in a "
                         "train without damping nothing decays)")
    # the digits the edges hold: an edge is bisected to within edge_tolerance/2
    places = max(0, round(-math.log10(chart.edge_tolerance)))
    rpm_places = max(0, round(-math.log10(chart.edge_tolerance * RPM_PER_RAD_S)))
    for low, high in chart.unstable_bands:
        lines.append(f"unstable: {low:.{places}f}-{high:.{places}f} rad/s "
                     f"({low * RPM_PER_RAD_S:.{rpm_places}f}-{high * RPM_PER_RAD_S:.{rpm_places}f}"
                     f" rpm; edges to ±{0.5 * chart.edge_tolerance:g} rad/s)")
    if not chart.unstable_bands:
        lines.append("no unstable band: every multiplier inside the unit circle"
                     + ("" if decaying.all() else " or on it within rounding"))
    return lines + grid_lines(chart)


def grid_lines(chart) -> list[str]:
    """Where the chart's speeds may hide a band or merge two: the speeds it probed between
    them (stability.refined_speeds and unstable_midpoints) and what they cost, and the
    widths of band and stable gap that its spacing, and the probes', can miss."""
    from ..analysis.stability import REFINE_MARGIN

    step = chart.grid_step
    if step <= 0.0:
        return []
    probed = len(chart.probed_speeds)
    lines = [f"probed {probed} speeds besides the {len(chart.speeds)} charted (a monodromy "
             f"each): beside the unstable speeds and the peaks of |λ|max within "
             f"{REFINE_MARGIN:g} of 1, and between neighbouring unstable ones"] if probed else []
    finer = (f" ({step / chart.refine_split:.3g} rad/s where the chart probed)"
             if probed else "")
    return lines + [f"a band, or a stable gap between two, narrower than the grid step, "
                    f"{step:.3g} rad/s{finer}, may be missed or merged: give more speeds to "
                    "see finer"]
