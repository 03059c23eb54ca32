"""Units and ranges on pythonfmu variables: pythonfmu 0.7.0's Real takes no `unit`, writes its
start value to 16 digits only, and no variable of it takes `min` or `max`.

builder.build_slave_fmu ships this module with every FMI 2.0 FMU it builds, as the module
`fmi_units` (which the example slaves import), and declares the units the model description
uses (<UnitDefinitions>), which `fmpy validate` requires.

FMI 2.0's `min` and `max` include their value. A bound that excludes it (s_breakdown in
(0, 1]) is written as `min`/`max` and marked exclusive in the variable's <Annotations>, under
the tool name BOUNDS_TOOL (`<Tool name="herringbone"><Bounds minExclusive="true"/></Tool>`):
herringbone.fmu.ssp reads it there (`exclusive_bounds`), and the example slaves check their
parameters against the same declarations (`bounds_problem`).
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

from pythonfmu import Integer, Real

BOUNDS_TOOL = "herringbone"


def xs_double(value: float) -> str:
    """`value` as an xs:double that parses back to the same float: repr where finite (every
    bit), else INF, -INF or NaN (the only spellings XML Schema allows)."""
    value = float(value)
    if math.isnan(value):
        return "NaN"
    if math.isinf(value):
        return "INF" if value > 0 else "-INF"
    return repr(value)


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
    <UnitDefinitions> declares, e.g. "N.m"), its start value with every bit, and `min`/`max`
    (in that unit), each where given; `min_exclusive`/`max_exclusive`: the bound itself is not
    allowed (marked in the variable's <Annotations>, see the module's docstring)."""

    def __init__(self, name: str, *, unit: str | None, min: float | None = None,
                 max: float | None = None, min_exclusive: bool = False,
                 max_exclusive: bool = False, **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        self.unit, self.min, self.max = unit, min, max
        self.min_exclusive, self.max_exclusive = min_exclusive, max_exclusive

    def to_xml(self) -> ET.Element:
        """pythonfmu's <ScalarVariable>, its <Real> with the exact start value, the unit and
        the bounds, and the bounds' annotation where one is exclusive."""
        node: ET.Element = super().to_xml()
        real = _child(node, "Real")
        if self.start is not None:
            # FMI 2.0's start is the value fmi2GetReal returns before initialization:
            # pythonfmu's 16 digits can miss it by an ulp (J_wheel's 0.024809948427469804)
            real.set("start", xs_double(self.start))
        if self.unit is not None:
            real.set("unit", self.unit)
        _set_bounds(node, "Real", self.min, self.max)
        exclusive = {attribute: "true" for attribute, flag in (
            ("minExclusive", self.min_exclusive and self.min is not None),
            ("maxExclusive", self.max_exclusive and self.max is not None)) if flag}
        if exclusive:
            tool = ET.SubElement(ET.SubElement(node, "Annotations"), "Tool", name=BOUNDS_TOOL)
            ET.SubElement(tool, "Bounds", exclusive)
        return node

    @property
    def bounded(self) -> bool:
        """Whether the variable declares a `min` or a `max`."""
        return self.min is not None or self.max is not None

    def allows(self, value: float) -> bool:
        """Whether `value` is a number inside the bounds (NaN is not)."""
        low_ok = self.min is None or (value > self.min if self.min_exclusive
                                      else value >= self.min)
        high_ok = self.max is None or (value < self.max if self.max_exclusive
                                       else value <= self.max)
        return bool(low_ok and high_ok)

    def rule(self) -> str:
        """The bounds in words, as the slaves' messages write them: "0 < s_breakdown <= 1",
        "k_fan >= 0" (for a variable with bounds)."""
        below = {False: "<=", True: "<"}
        if self.max is None:  # a lower bound alone reads from the name
            return f"{self.local_name} {'>' if self.min_exclusive else '>='} {self.min:g}"
        low = "" if self.min is None else f"{self.min:g} {below[self.min_exclusive]} "
        return f"{low}{self.local_name} {below[self.max_exclusive]} {self.max:g}"


def bounds_problem(slave: Any) -> str | None:
    """Why `slave`'s values are unusable, or None: where one of its RealWithUnit variables
    with bounds holds a value outside them, "<instance>: need <rule>, …; got <value>, …" over
    all of those variables, in the order they were registered (values read as pythonfmu reads
    them, the slave's attributes of the variables' names)."""
    bounded = [v for v in slave.vars.values() if isinstance(v, RealWithUnit) and v.bounded]
    values = [getattr(slave, v.local_name) for v in bounded]
    if all(v.allows(value) for v, value in zip(bounded, values)):
        return None
    return (f"{slave.instance_name}: need {', '.join(v.rule() for v in bounded)}; "
            f"got {', '.join(str(value) for value in values)}")


def exclusive_bounds(model_description: ET.Element) -> dict[str, tuple[bool, bool]]:
    """{variable name: (min exclusive, max exclusive)} for every variable of an FMI 2.0
    `model_description` (its root element) that marks a bound exclusive (RealWithUnit)."""
    found = {}
    for variable in model_description.iterfind("ModelVariables/ScalarVariable"):
        bounds = variable.find(f"Annotations/Tool[@name='{BOUNDS_TOOL}']/Bounds")
        if bounds is not None:
            found[variable.get("name", "")] = (bounds.get("minExclusive") == "true",
                                               bounds.get("maxExclusive") == "true")
    return found


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
