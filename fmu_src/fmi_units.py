"""Units on pythonfmu variables: pythonfmu 0.7.0's Real takes no `unit`.

build_fmu.build_slave_fmu ships this module with every FMU it builds and declares the units the
model description uses (<UnitDefinitions>), which `fmpy validate` requires.
"""
from pythonfmu import Real


class RealWithUnit(Real):
    """A Real variable whose <Real> element carries a unit."""

    def __init__(self, name, *, unit, **kwargs):
        super().__init__(name, **kwargs)
        self.unit = unit

    def to_xml(self):
        node = super().to_xml()
        node.find("Real").set("unit", self.unit)
        return node
