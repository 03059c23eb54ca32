"""Units and ranges on pythonfmu variables: pythonfmu 0.7.0's Real takes no `unit`, and no
variable of it takes `min` or `max`.

builder.build_slave_fmu ships this module with every FMI 2.0 FMU it builds, as the module
`fmi_units` (which the example slaves import), and declares the units the model description
uses (<UnitDefinitions>), which `fmpy validate` requires.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from pythonfmu import Integer, Real


def _set_bounds(node: ET.Element, tag: str, minimum: float | None,
                maximum: float | None) -> None:
    """Set `min`/`max` on the `tag` child of a variable's <ScalarVariable> `node`, each where
    given, written with every bit (repr)."""
    for attribute, bound in (("min", minimum), ("max", maximum)):
        if bound is not None:
            _child(node, tag).set(attribute, repr(bound))


def _child(node: ET.Element, tag: str) -> ET.Element:
    """The `tag` child of `node`, which pythonfmu always writes."""
    child = node.find(tag)
    if child is None:
        raise ValueError(f"pythonfmu wrote no <{tag}> in {ET.tostring(node)!r}")
    return child


class RealWithUnit(Real):
    """A Real variable whose <Real> element carries a unit (a name the model description's
    <UnitDefinitions> declares, e.g. "N.m") and `min`/`max` (in that unit), each where given."""

    def __init__(self, name: str, *, unit: str | None, min: float | None = None,
                 max: float | None = None, **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        self.unit, self.min, self.max = unit, min, max

    def to_xml(self) -> ET.Element:
        """pythonfmu's <ScalarVariable>, its <Real> with the unit and the bounds."""
        node: ET.Element = super().to_xml()
        if self.unit is not None:
            _child(node, "Real").set("unit", self.unit)
        _set_bounds(node, "Real", self.min, self.max)
        return node


class BoundedInteger(Integer):
    """An Integer variable whose <Integer> element carries `min`/`max` where given."""

    def __init__(self, name: str, *, min: int | None = None, max: int | None = None,
                 **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        self.min, self.max = min, max

    def to_xml(self) -> ET.Element:
        """pythonfmu's <ScalarVariable>, its <Integer> with the bounds."""
        node: ET.Element = super().to_xml()
        _set_bounds(node, "Integer", self.min, self.max)
        return node
