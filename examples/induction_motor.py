"""Induction motor as a pythonfmu co-simulation slave: Kloss torque-speed curve.

Input `w_motor` (shaft speed, rad/s) -> output `M_motor` (air-gap torque, N.m):
    M = 2 M_k / (s/s_k + s_k/s) = 2 M_k s s_k / (s^2 + s_k^2),   s = (w_sync - w)/w_sync.
The second form is the same curve without the division by s = 0 (M = 0 at synchronous speed).
The output is a direct feedthrough of the input: it is evaluated whenever the host reads it.
Defaults pair with the reference gear train: 500 N.m at about 155.9 rad/s (slip 2.6 percent).
"""
import math

from fmi_units import RealWithUnit, bounds_problem
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability
from pythonfmu.enums import Fmi2Status
from pythonfmu_references import BalancedSlave


class InductionMotor(BalancedSlave, Fmi2Slave):
    """Kloss-curve induction motor: speed in, torque out."""

    description = "Induction motor, Kloss torque-speed curve (speed in, torque out)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.M_breakdown = 1500.0
        self.s_breakdown = 0.15
        self.w_sync = 160.0
        self.w_motor = 0.0
        # each parameter's range, declared once: the model description carries it (an
        # excluded bound as fmi_units marks it), problem() checks it, and herringbone's SSP
        # builder refuses a value outside it
        for name, unit, description, low, high in (
                ("M_breakdown", "N.m", "breakdown (pull-out) torque M_k, > 0", 0.0, None),
                ("s_breakdown", "1", "slip at breakdown torque s_k, in (0, 1]", 0.0, 1.0),
                ("w_sync", "rad/s", "synchronous speed of the stator field, > 0", 0.0, None)):
            self.register_variable(RealWithUnit(
                name, unit=unit, description=description, min=low, max=high,
                min_exclusive=True, causality=Fmi2Causality.parameter,
                variability=Fmi2Variability.tunable))
        self.register_variable(RealWithUnit(
            "w_motor", unit="rad/s", description="rotor shaft speed seen by the motor",
            causality=Fmi2Causality.input, variability=Fmi2Variability.continuous))
        self.register_variable(RealWithUnit(
            "M_motor", unit="N.m", description="torque the motor applies to its shaft",
            causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
            getter=self.torque))

    def torque(self) -> float:
        """Kloss torque at the current input speed, N.m (negative above synchronous speed).

        NaN while the parameters are unusable: a getter must not raise (see do_step).
        """
        if self.problem() is not None:
            return math.nan
        s = (self.w_sync - self.w_motor) / self.w_sync
        return 2.0 * self.M_breakdown * s * self.s_breakdown / (s * s + self.s_breakdown ** 2)

    def problem(self) -> str | None:
        """Why the parameters are unusable, or None: one outside the range it declares
        (fmi_units.bounds_problem: "need M_breakdown > 0, 0 < s_breakdown <= 1, w_sync > 0;
        got …")."""
        return bounds_problem(self)

    def do_step(self, current_time: float, step_size: float) -> bool:
        # Bad parameters are reported here, not by raising in a setter or in
        # exit_initialization_mode: a Python exception is fmi2Fatal, which aborts a libcosim
        # host; False is fmi2Discard, and the logged text reaches the host.  The host's logger
        # formats messages printf-style, hence the escaped '%'.
        problem = self.problem()
        if problem is not None:
            self.log(problem.replace("%", "%%"), Fmi2Status.error)
            return False
        return True
