"""The variational run's fixed step (integrate/variational.multiplier_step): each mode's
multiplier e^{λ·T} within the error asked, and no overflow where a mode decays by more than
e^709 over the period (a long period at low speed: `herringbone sweep reference --speeds 10 30
2` printed numpy's "overflow encountered in exp")."""
import warnings

import numpy as np
import pytest

from herringbone.integrate.variational import error_constant, multiplier_step


def direct_step(modes, duration, error):
    """The step by the formula as written, for modes that do not overflow it."""
    allowed = error * np.exp(-modes.real * duration) / duration
    return float(((allowed / (error_constant() * np.abs(modes) ** 9)) ** (1.0 / 8.0)).min())


MODES = np.array([0.0, -20.0 + 3000.0j, -20.0 - 3000.0j, -400.0 + 2.0e4j, -400.0 - 2.0e4j])


def test_the_step_is_the_formulas_where_nothing_overflows():
    for duration in (1e-3, 1e-2):
        assert multiplier_step(MODES, duration, 1e-6) == pytest.approx(
            direct_step(MODES[1:], duration, 1e-6), rel=1e-12)


def test_a_mode_damped_beyond_the_floats_bounds_nothing_and_warns_nothing():
    """At T = 20 s the fast pair decays by e^8000 (the formula's e^{…} overflows): the slow
    pair sets the step, as it does where the fast pair's bound is merely large; without the
    slow pair, the fast pair's bound (about e^990 s) is past the floats: no mode bounds the
    step (inf)."""
    duration = 20.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        step = multiplier_step(MODES, duration, 1e-6)
        unbounded = multiplier_step(MODES[[0, 3, 4]], duration, 1e-6)
    assert step == pytest.approx(direct_step(MODES[1:3], duration, 1e-6), rel=1e-12)
    assert unbounded == np.inf
