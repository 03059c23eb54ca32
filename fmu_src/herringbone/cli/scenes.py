"""`herringbone scenes`: the shipped scenes, each with the first line of its header."""
from __future__ import annotations

NAME = "scenes"
HELP = "list the shipped scenes: name and what each tests"


def declare(parser) -> None:
    """`scenes` takes no arguments."""


def execute(args, parser) -> int:
    """Print one line per shipped scene."""
    from ..shipped import scene_list

    print("\n".join(scene_list()))
    return 0
