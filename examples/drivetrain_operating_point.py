"""Where the example drive train settles: the motor's Kloss curve meets the fan curve through
the gear ratio.  One home for the formula: examples/cosimulate_drivetrain.py, tests/fmu/test_ssp.py
and tests/fmu/test_cosimulation.py all use it.

In steady running the gear is a lossless ratio u = z_wheel/z_pinion (M_load = u·M_motor,
w_load = w_motor/u), so the train runs where Kloss(w) = k_fan·(w/u)²/u.  Needs only scipy; it
must not import `herringbone` (a process that runs the gear FMU would then use this source
tree's package instead of the copy the FMU carries).
"""
import math

from scipy.optimize import brentq


def kloss_torque(w, M_breakdown, s_breakdown, w_sync):
    """The motor's curve (examples/induction_motor.py): M = 2·M_k·s·s_k/(s² + s_k²),
    s = (w_sync − w)/w_sync."""
    s = (w_sync - w) / w_sync
    return 2.0 * M_breakdown * s * s_breakdown / (s * s + s_breakdown ** 2)


def fan_torque(w, k_fan):
    """The fan's curve (examples/fan_load.py): M = k_fan·w·|w|."""
    return k_fan * w * abs(w)


def operating_point(M_breakdown, s_breakdown, w_sync, k_fan, z_pinion, z_wheel):
    """The intersection on the motor's stable branch, as {w_motor, w_load, M_motor, M_load}
    (rad/s, N·m) plus `ratio` and `mesh_period` (s, one tooth of the pinion at w_motor).

    Between breakdown slip and synchronous speed the motor torque falls from M_k to 0 while
    the reflected fan torque rises: one sign change, found to 1e-12 rad/s.  Raises ValueError
    if the curves do not cross there (e.g. a fan too heavy for the motor)."""
    ratio = z_wheel / z_pinion

    def surplus(w):
        return (kloss_torque(w, M_breakdown, s_breakdown, w_sync)
                - fan_torque(w / ratio, k_fan) / ratio)

    w_breakdown = w_sync * (1.0 - s_breakdown)
    if not surplus(w_breakdown) > 0:
        raise ValueError(f"the fan (k_fan = {k_fan}) needs more than the motor's breakdown "
                         f"torque {M_breakdown} N·m at {w_breakdown} rad/s: no stable "
                         "operating point; allowed: a smaller k_fan or a larger M_breakdown")
    if not surplus(w_sync) <= 0:  # a fan that drives the train (k_fan < 0)
        raise ValueError(f"the motor's and the fan's curves (k_fan = {k_fan}) do not cross "
                         f"below the synchronous speed {w_sync} rad/s: no operating point; "
                         "allowed: k_fan >= 0")
    w_motor = brentq(surplus, w_breakdown, w_sync, xtol=1e-12, rtol=1e-14)
    return {"w_motor": w_motor, "w_load": w_motor / ratio,
            "M_motor": kloss_torque(w_motor, M_breakdown, s_breakdown, w_sync),
            "M_load": fan_torque(w_motor / ratio, k_fan), "ratio": ratio,
            "mesh_period": 2.0 * math.pi / (z_pinion * w_motor)}
