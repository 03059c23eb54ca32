"""The scipy reference's screening of a step for events (integrate/stepping.py), compiled.

The reference reads every event function at the nodes of each accepted step and asks, node
interval by interval, whether a function may rise through zero there: its own rule, kept apart
from the compiled integrator's (walk.py never imports this module), so that the two can check
each other. Only the arithmetic is compiled here, where numpy's work on arrays of a few dozen
numbers cost more than the scipy step itself; stepping.py says what the rule is and why.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...compiling.counting import COUNTED


@njit(**COUNTED)
def bumps(values, slopes, times):
    """Per event (row) and interval between nodes: whether the function, below zero at both
    nodes, may bulge up between them more than halfway to zero. It rises at the interval's
    start and falls at its end, and the tangents there meet that high: they meet above the top
    of a concave bulge, so none is missed that the nodes' slopes show."""
    events, nodes = values.shape
    flagged = np.zeros((events, nodes - 1), dtype=np.bool_)
    for k in range(nodes - 1):
        span = times[k + 1] - times[k]
        for e in range(events):
            g0, g1 = values[e, k], values[e, k + 1]
            d0, d1 = slopes[e, k] * span, slopes[e, k + 1] * span
            higher = max(g0, g1)
            if d0 > 0.0 and d1 < 0.0 and higher <= 0.0:
                flagged[e, k] = g0 + d0 * ((g1 - d1 - g0) / (d0 - d1)) > 0.5 * higher
    return flagged


@njit(**COUNTED)
def crossing_candidates(values, slopes, times):
    """(candidates, bumps): per event and node interval, whether the function may rise through
    zero there: it rises through zero between the nodes (in the first interval it need only
    end above zero: the step's start is on the near side, since had it been past, the step
    before would have ended there), or `bumps` flags a bulge."""
    flagged = bumps(values, slopes, times)
    candidates = flagged.copy()
    events, nodes = values.shape
    for k in range(nodes - 1):
        for e in range(events):
            if values[e, k + 1] > 0.0 and (values[e, k] <= 0.0 or k == 0):
                candidates[e, k] = True
    return candidates, flagged


@njit(**COUNTED)
def near_zero(values, factor):
    """Per row: whether the function comes within `factor` times its largest change between
    two nodes of zero (its largest value above −factor·max|Δ|)."""
    rows, nodes = values.shape
    near = np.zeros(rows, dtype=np.bool_)
    for e in range(rows):
        top = values[e, 0]
        change = 0.0
        for k in range(1, nodes):
            top = max(top, values[e, k])
            change = max(change, abs(values[e, k] - values[e, k - 1]))
        near[e] = top > -factor * change
    return near
