"""Fan (quadratic) load as a pythonfmu co-simulation slave.

Input `w_load` (shaft speed, rad/s) -> output `M_load` = k_fan w |w| (N.m, opposes the motion:
positive for positive speed).  The output is a direct feedthrough of the input, evaluated
whenever the host reads it.  Default k_fan gives 1800 N.m at 157.08/3.6 = 43.63 rad/s, the
wheel speed of the reference gear train.
"""
import math

from fmi_units import RealWithUnit, bounds_problem
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability
from pythonfmu.enums import Fmi2Status
from pythonfmu_references import BalancedSlave


class FanLoad(BalancedSlave, Fmi2Slave):
    """Quadratic fan load: speed in, resisting torque out."""

    description = "Fan load M = k_fan w |w| (speed in, torque out)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.k_fan = 0.9454
        self.w_load = 0.0
        self.register_variable(RealWithUnit(
            "k_fan", unit="N.m.s2/rad2", description="fan torque coefficient (>= 0)", min=0.0,
            causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(RealWithUnit(
            "w_load", unit="rad/s", description="fan shaft speed",
            causality=Fmi2Causality.input, variability=Fmi2Variability.continuous))
        self.register_variable(RealWithUnit(
            "M_load", unit="N.m", description="torque the fan takes from its shaft",
            causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
            getter=self.torque))

    def torque(self) -> float:
        """Fan torque at the current input speed, N.m (NaN while k_fan is unusable)."""
        if self.problem() is not None:
            return math.nan
        return self.k_fan * self.w_load * abs(self.w_load)

    def problem(self) -> str | None:
        """Why the parameters are unusable, or None: k_fan outside the range it declares
        (fmi_units.bounds_problem; herringbone's SSP builder reads the same declaration)."""
        return bounds_problem(self)

    def do_step(self, current_time: float, step_size: float) -> bool:
        # Reported here rather than raised: see InductionMotor.do_step.
        problem = self.problem()
        if problem is not None:
            self.log(problem.replace("%", "%%"), Fmi2Status.error)
            return False
        return True
