"""`herringbone info SCENE`: geometry, mesh phasing, natural modes and resonance speeds."""
from __future__ import annotations

from ..model.scene import load_scene
from .common import add_scene

NAME = "info"
HELP = "geometry, mesh phasing, natural modes and resonance speeds of a scene"


def declare(parser) -> None:
    """The arguments of `info`."""
    add_scene(parser)


def execute(args, parser) -> int:
    """Print the scene's report (analysis.report.scene_report)."""
    from ..analysis.report import scene_report

    print(scene_report(load_scene(args.scene)), end="")
    return 0
