"""Random scenes for property tests: `scenes()`, a hypothesis strategy, and `random_scene(seed)`,
the plain seeded generator (numpy only, what benchmarks/random_scenes.py runs). Both draw from
the one distribution in scene_distribution.draw_scene_data; hypothesis supplies the numbers here,
so that it can shrink a failing scene towards simpler values (its own choice of values favours
the ends of each span more than the seeded generator does)."""
from __future__ import annotations

import math

from hypothesis import strategies as st

import herringbone
from helpers.scene_distribution import (  # noqa: F401 (random_scene re-exported)
    draw_scene_data,
    random_scene,
    turned_backwards,
)

# The chance that a drawn scene is turned backwards (scene_distribution.turned_backwards),
# under reversed torques or braked, even odds; Hypothesis, which favours the ends of a span,
# turns about a third of its scenes (74 of 200 draws)
BACKWARDS = 0.2


class HypothesisSampler:
    """scene_distribution's sampler contract (uniform, log_uniform, integer, chance) on
    hypothesis's `draw`."""

    def __init__(self, draw):
        self.draw = draw

    def uniform(self, low: float, high: float) -> float:
        return self.draw(st.floats(low, high, allow_nan=False, allow_infinity=False))

    def log_uniform(self, low: float, high: float) -> float:
        # exp(log(x)) may land an ulp outside [low, high]: clamp
        value = math.exp(self.uniform(math.log(low), math.log(high)))
        return min(max(value, low), high)

    def integer(self, low: int, high: int) -> int:
        return self.draw(st.integers(low, high))

    def chance(self, probability: float) -> bool:
        return self.uniform(0.0, 1.0) < probability


@st.composite
def scenes(draw):
    """A random, valid herringbone.Scene (scene_distribution's spans), named "hypothesis";
    some turned backwards (BACKWARDS)."""
    sampler = HypothesisSampler(draw)
    scene = herringbone.scene_from_dict(draw_scene_data(sampler), name="hypothesis",
                                        source="<hypothesis scene>")
    if sampler.chance(BACKWARDS):
        scene = turned_backwards(scene, torques_too=sampler.chance(0.5))
    return scene
