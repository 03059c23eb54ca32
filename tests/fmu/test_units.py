"""Units, ranges and start values on pythonfmu variables (herringbone.fmu.units, shipped with
every FMI 2.0 FMU as `fmi_units`): the start values a built FMU declares are the values it
returns, and an exclusive bound is declared where the SSP builder and the slave both read it."""
import math
import xml.etree.ElementTree as ET
from types import SimpleNamespace

import pytest
from fmpy import read_model_description
from pythonfmu import Fmi2Causality, Fmi2Variability

from herringbone.fmu.units import RealWithUnit, bounds_problem, exclusive_bounds


@pytest.fixture(scope="module")
def fmi2_fmus(scene_fmu, tmp_path_factory):
    """The reference scene's gear FMU (FMI 2.0) and the example motor and fan FMUs."""
    from herringbone.fmu import builder

    motor, fan = builder.build_example_fmus(tmp_path_factory.mktemp("examples"))
    return {"gear": scene_fmu("reference"), "motor": motor, "fan": fan}


@pytest.mark.parametrize("name", ["gear", "motor", "fan"])
def test_every_real_start_is_what_fmi2GetReal_returns_before_initialization(fmi2_fmus, name):
    """FMI 2.0: a Real's start attribute is its initial value, every bit of it: pythonfmu's
    own 16 digits make the gear's derived J_wheel, 0.024809948427469804 kg·m², an ulp off
    (0.0248099484274698)."""
    from helpers.fmu_host import Instance

    description = read_model_description(str(fmi2_fmus[name]))
    starts = {v.name: v for v in description.modelVariables
              if v.type == "Real" and v.start is not None}
    instance = Instance(fmi2_fmus[name], name=name, initialize=False)
    try:
        instance.slave.enterInitializationMode()
        values = instance.slave.getReal([v.valueReference for v in starts.values()])
    finally:
        instance.free()
    differing = {n: (v.start, value) for (n, v), value in zip(starts.items(), values)
                 if float(v.start) != value}
    assert not differing, differing
    if name == "gear":
        assert starts["J_wheel"].start == repr(0.024809948427469804)


def variable(**kwargs):
    """A parameter like the example slaves' (RealWithUnit), its value reference set."""
    real = RealWithUnit(kwargs.pop("name", "s_breakdown"), unit="1",
                        causality=Fmi2Causality.parameter,
                        variability=Fmi2Variability.tunable, **kwargs)
    real.value_reference = 0
    return real


def test_start_is_written_with_every_bit():
    real = variable()
    real.start = 0.024809948427469804
    written = real.to_xml().find("Real").get("start")
    assert float(written) == 0.024809948427469804, written


def test_an_exclusive_bound_is_annotated_and_read_back():
    """FMI 2.0's min includes its value: s_breakdown in (0, 1] is min 0, max 1 and an
    annotation that min excludes 0, which exclusive_bounds reads from a model description."""
    node = variable(min=0.0, max=1.0, min_exclusive=True).to_xml()
    assert (node.find("Real").get("min"), node.find("Real").get("max")) == ("0.0", "1.0")
    root = ET.Element("fmiModelDescription")
    ET.SubElement(root, "ModelVariables").extend([node, variable(name="k_fan", min=0.0).to_xml()])
    assert exclusive_bounds(root) == {"s_breakdown": (True, False)}


@pytest.mark.parametrize("value, allowed", [(0.0, False), (1e-300, True), (1.0, True),
                                            (1.0000000000000002, False), (math.nan, False)])
def test_the_declared_bounds_are_the_ones_checked(value, allowed):
    """The slaves check their parameters against the same declaration (bounds_problem), in
    the words their messages have always had."""
    slave = SimpleNamespace(instance_name="motor", s_breakdown=value,
                            vars={0: variable(min=0.0, max=1.0, min_exclusive=True)})
    problem = bounds_problem(slave)
    assert (problem is None) == allowed
    if not allowed:
        assert problem == f"motor: need 0 < s_breakdown <= 1; got {value}"
