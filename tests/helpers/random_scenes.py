"""Random scenes for property tests: `scenes()`, a hypothesis strategy, and `random_scene(seed)`,
the plain seeded generator (numpy only, what benchmarks/random_scenes.py runs). Both draw from
the one distribution in scene_distribution.draw_scene_data; hypothesis supplies the numbers here,
so that it can shrink a failing scene towards simpler values (its own choice of values favours
the ends of each span more than the seeded generator does)."""
from __future__ import annotations

import math

from hypothesis import strategies as st

import herringbone
from helpers.scene_distribution import draw_scene_data, random_scene  # noqa: F401 (re-exported)


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
    """A random, valid herringbone.Scene (scene_distribution's spans), named "hypothesis"."""
    return herringbone.scene_from_dict(draw_scene_data(HypothesisSampler(draw)),
                                       name="hypothesis", source="<hypothesis scene>")
