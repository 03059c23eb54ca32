"""`herringbone campbell SCENE`: the Campbell diagram, natural frequencies against pinion speed
with the mesh orders, and their crossings (the resonance speeds)."""
from __future__ import annotations

from pathlib import Path

from ..model.parameters import RPM_PER_RAD_S
from ..optional import require
from .common import (
    NO_BAR,
    add_output,
    add_progress,
    add_scene,
    add_settings,
    add_speeds,
    changed_name,
    default_output,
    scene_of,
    speeds_of,
)

NAME = "campbell"
HELP = "Campbell diagram: natural frequencies against speed with the mesh orders, crossings listed"
PICTURES = (".png", ".pdf", ".svg")


def declare(parser) -> None:
    """The options of `campbell`."""
    add_scene(parser)
    add_settings(parser)
    add_speeds(parser, (50.0, 3000.0, 2), "the diagram's span (its lines and crossings are "
               "exact: FROM and TO matter, COUNT only takes the common form)")
    add_output(parser, "the diagram; an existing file is replaced",
               "results/<scene>_campbell.png", PICTURES)
    add_progress(parser, NO_BAR)


def execute(args, parser) -> int:
    """Draw the diagram and list the crossings."""
    from ..analysis.campbell import plot_campbell
    from ..analysis.excitation import HARMONICS_CONSIDERED, resonance_lines, resonances

    sweep = speeds_of(args, parser)
    assert sweep is not None  # the command has default speeds
    speeds = sweep.speeds()
    low, high = float(speeds[0]), float(speeds[-1])
    scene = scene_of(args, parser)
    name = changed_name(scene, args)
    output = default_output(parser, args.output, Path("results") / f"{name}_campbell.png",
                            PICTURES)
    require("matplotlib", "the Campbell diagram")
    output.parent.mkdir(parents=True, exist_ok=True)
    ringing = resonances(scene, low, high)
    found = plot_campbell(scene, low, high, output, f"{name}: Campbell diagram", ringing)
    print(f"crossings k·f_mesh = f_n between {low * RPM_PER_RAD_S:.0f} and "
          f"{high * RPM_PER_RAD_S:.0f} rpm ({low:g}-{high:g} rad/s):")
    for c in found:
        print(f"  {c.speed * RPM_PER_RAD_S:8.0f} rpm ({c.speed:8.1f} rad/s)  k = {c.order}  "
              f"f_n = {c.frequency:9.2f} Hz")
    if not found:
        print("  none")
    print(f"of these and the higher harmonics (k up to {HARMONICS_CONSIDERED}), those that "
          "ring: the mesh force's k-th harmonic there, a share of the static force (a "
          "first-order estimate):")
    print("\n".join(resonance_lines(ringing) or ["  none of 2 % or more"]))
    print(f"diagram written to {output}")
    return 0
