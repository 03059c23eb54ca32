"""`herringbone info SCENE`: geometry, mesh phasing, natural modes and resonance speeds."""
from __future__ import annotations

from .common import NO_BAR, add_progress, add_scene, add_settings, scene_of

NAME = "info"
HELP = "geometry, mesh phasing, natural modes and resonance speeds of a scene"


def declare(parser) -> None:
    """The arguments of `info`."""
    add_scene(parser)
    add_settings(parser)
    add_progress(parser, NO_BAR)


def execute(args, parser) -> int:
    """Print the scene's report (analysis.report.scene_report)."""
    from ..analysis.report import scene_report

    print(scene_report(scene_of(args, parser)), end="")
    return 0
