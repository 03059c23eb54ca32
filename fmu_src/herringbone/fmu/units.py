"""Units and ranges on pythonfmu variables: pythonfmu 0.7.0's Real takes no `unit`, and no
variable of it takes `min` or `max`.

builder.build_slave_fmu ships this module, as the module `fmi_units` (which the example slaves
import), with every FMU it builds and declares the units the
model description uses (<UnitDefinitions>), which `fmpy validate` requires.
"""
from pythonfmu import Integer, Real


def _set_bounds(node, tag, minimum, maximum):
    for attribute, bound in (("min", minimum), ("max", maximum)):
        if bound is not None:
            node.find(tag).set(attribute, repr(bound))


class RealWithUnit(Real):
    """A Real variable whose <Real> element carries a unit, and `min`/`max` where given."""

    def __init__(self, name, *, unit, min=None, max=None, **kwargs):
        super().__init__(name, **kwargs)
        self.unit, self.min, self.max = unit, min, max

    def to_xml(self):
        node = super().to_xml()
        node.find("Real").set("unit", self.unit)
        _set_bounds(node, "Real", self.min, self.max)
        return node


class BoundedInteger(Integer):
    """An Integer variable whose <Integer> element carries `min`/`max` where given."""

    def __init__(self, name, *, min=None, max=None, **kwargs):
        super().__init__(name, **kwargs)
        self.min, self.max = min, max

    def to_xml(self):
        node = super().to_xml()
        _set_bounds(node, "Integer", self.min, self.max)
        return node
