"""The drive train as an SSP (System Structure and Parameterization 1.0): `drivetrain.ssp`.

The archive holds `SystemStructure.ssd` and, under `resources/`, the gear FMU of a scene and the
example motor and fan FMUs (examples/).  The SSD names three Components (`gear`, `motor`,
`fan`), their connectors with units, the four connections (speeds from the gear to the motor
and the fan, their torques back), the units' SI exponents, one parameter set per component
(inline ParameterValues: the motor's Kloss curve and the fan's coefficient, their FMUs' start
values unless overridden) and a DefaultExperiment with the Open Simulation Platform's
fixed-step annotation, which libcosim reads as its base step.

Written for what libcosim's SSP parser reads: it matches the literal prefixes `ssd:`, `ssc:`,
`ssv:` and `osp:` (boost property_tree, not a namespace-aware parser), so those are the
prefixes used.  The SSD also passes the SSP 1.0 schema as fmpy checks it.

A parameter set may give any parameter of a component's FMU (ssv:Real, ssv:Integer,
ssv:Boolean or ssv:String, as the FMU declares its type), each value checked before anything
is written: of that type, finite, and within what the FMU declares (`min`, `max`, a bound made
exclusive as herringbone.fmu.units marks it; for the gear, herringbone's own ranges, which its
FMU applies).  The units' SI exponents are those of the FMUs' <UnitDefinitions>.

`write_ssp(fmus, output, …)` packs FMUs that exist; `build_ssp(scene, output, …)` builds them
first (herringbone.fmu.builder) and packs them.  The connections need the gear's motor and load
(w_motor and w_load are theirs): `scene_problem` says why a scene has no SSP, before any build.
"""
from __future__ import annotations

import math
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from ..arguments import FMU_MAX_STEP, FMU_SOLVER_METHOD, FMU_SOLVER_TOLERANCE
from ..files import replace_file
from ..model.parameters import PARAMETERS, Range, check_value, is_flag, number_problem
from ..model.scene import Scene, load_scene
from .units import exclusive_bounds, xs_double

NAMESPACES = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
}
# Component name → the FMU's file name in resources/.
FMU_FILES = {"gear": "HerringboneGear.fmu", "motor": "InductionMotor.fmu", "fan": "FanLoad.fmu"}
# (from component, output) → (to component, input): speed and torque both ways.
CONNECTIONS = (
    (("gear", "w_motor"), ("motor", "w_motor")),
    (("motor", "M_motor"), ("gear", "M_motor")),
    (("gear", "w_load"), ("fan", "w_load")),
    (("fan", "M_load"), ("gear", "M_load")),
)
# The gear's components the connections need: w_motor and w_load are outputs of these.
CONNECTED_COMPONENTS = ("motor", "load")
# The parameters put in each component's parameter set by default: those that fix the
# operating point (the motor's Kloss curve, the fan's coefficient).
DEFAULT_PARAMETERS = {"motor": ("M_breakdown", "s_breakdown", "w_sync"), "fan": ("k_fan",)}
PARAMETER_SET = "drivetrain"
# The FMI types a parameter set gives values of: each is also the name of its element in
# SSP 1.0 (ssv:Real, … in a parameter set; ssc:Real, … on a connector).
SETTABLE_TYPES = ("Real", "Integer", "Boolean", "String")
PYTHON_TYPES: dict[str, type] = {"Real": float, "Integer": int, "Boolean": bool, "String": str}
INT32 = (-2.0**31, 2.0**31 - 1)  # fmi2Integer's values, where the FMU declares no range
# ssc:BaseUnit's attributes, as fmpy reads them from <UnitDefinitions>: the SI exponents, then
# the factor and offset to SI, each written where it is not its default
BASE_UNIT_EXPONENTS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
BASE_UNIT_DEFAULTS = {"factor": 1.0, "offset": 0.0}
STOP_TIME = 0.1  # s: the train has settled after about 0.05 s (tests/fmu/test_cosimulation.py)
# s: the explicit coupling of the Kloss curve's slope to the motor inertia is stable for
# h < 2·I/|dM/dw| ≈ 8e-4 s; 1e-4 s keeps the hold of the inputs far inside that.
STEP = 1e-4

for _prefix, _uri in NAMESPACES.items():
    ET.register_namespace(_prefix, _uri)


@dataclass(frozen=True)
class ComponentFmu:
    """What the SSD takes from a component's FMU: its file name in resources/, its model
    variables by name (fmpy's), its units by name as ssc:BaseUnit attributes (from its
    <UnitDefinitions>), and which bounds of its variables are exclusive
    (fmi_units.exclusive_bounds: {name: (min, max)})."""

    file: str
    variables: dict
    units: dict[str, dict[str, str]]
    exclusive: dict[str, tuple[bool, bool]]


def _tag(qualified: str) -> str:
    prefix, name = qualified.split(":")
    return f"{{{NAMESPACES[prefix]}}}{name}"


def build_ssp(scene, output: Path, stop_time: float = STOP_TIME, step: float = STEP,
              parameters: dict[str, dict[str, object]] | None = None) -> Path:
    """The drive train as an SSP archive: the gear FMU of `scene` and the example motor and
    fan FMUs, connected by their SSD (write_ssp).

    Parameters
    ----------
    scene : str, pathlib.Path or Scene
        A scene file, the name of a shipped scene, or a Scene (`herringbone.load_scene`).
    output : pathlib.Path
        The .ssp file to write (replaced if it exists).
    stop_time, step : float
        The default experiment the SSD carries: its stop time and communication step, s.
    parameters : dict or None
        {component: {name: value}}, replacing or adding to the default parameter set: any
        parameter of the component's FMU (Real, Integer, Boolean or String), in the unit the
        FMU declares, within the range it declares (write_ssp).

    Returns
    -------
    pathlib.Path
        `output`.

    Raises
    ------
    SceneError
        A bad scene.
    ValueError
        A scene without a motor or a load (scene_problem), an unknown component or a bad
        experiment, before any build; an unknown parameter or a value its FMU does not allow
        (write_ssp), before `output` is written.
    RuntimeError
        An FMU's build failed, or `output` cannot be written.

    Examples
    --------
    >>> import zipfile
    >>> from pathlib import Path
    >>> from herringbone.fmu.ssp import build_ssp
    >>> archive = build_ssp("reference", Path("drivetrain.ssp"))
    >>> zipfile.ZipFile(archive).namelist()
    ['SystemStructure.ssd', 'resources/FanLoad.fmu', 'resources/HerringboneGear.fmu',
     'resources/InductionMotor.fmu']
    """
    check_experiment(stop_time, step)
    check_components(parameters or {})
    problem = scene_problem(scene if isinstance(scene, Scene) else load_scene(scene))
    if problem is not None:
        raise ValueError(problem)
    from .builder import build_example_fmus, build_gear_fmu

    with tempfile.TemporaryDirectory(prefix="drivetrain_ssp_") as tmp:
        folder = Path(tmp)
        gear = build_gear_fmu(scene=scene, output=folder / FMU_FILES["gear"])
        motor, fan = build_example_fmus(output_dir=folder)
        return write_ssp({"gear": gear, "motor": motor, "fan": fan}, output,
                         stop_time=stop_time, step=step, parameters=parameters)


def scene_problem(scene: Scene) -> str | None:
    """Why the gear FMU of `scene` cannot be connected in the SSP (one line), or None: the
    connections take the motor's and the load's speeds, which a scene without them lacks."""
    missing = [c for c in CONNECTED_COMPONENTS if not scene.has(c)]
    if not missing:
        return None
    has = "neither" if len(missing) == len(CONNECTED_COMPONENTS) else f"no {missing[0]}"
    return (f"the SSP connects the motor and the load: scene {scene.name} has {has} (its "
            "[components]); allowed: a scene with motor and load")


def check_experiment(stop_time: float, step: float) -> None:
    """Raise ValueError unless 0 < step <= stop_time, both finite."""
    if not (math.isfinite(stop_time) and math.isfinite(step) and 0 < step <= stop_time):
        raise ValueError(f"stop time {stop_time!r} s and step {step!r} s: allowed: both finite, "
                         "0 < step <= stop time")


def check_components(parameters: Mapping) -> None:
    """Raise ValueError unless `parameters` maps components of the SSP to {name: value}
    mappings: what can be checked before the FMUs exist."""
    if not isinstance(parameters, Mapping):
        raise ValueError(f"parameters {parameters!r}: allowed: {{component: {{name: value}}}}")
    for component, given in parameters.items():
        if component not in FMU_FILES:
            raise ValueError(f"parameters for {component!r}: allowed components: "
                             f"{', '.join(FMU_FILES)}")
        if not isinstance(given, Mapping):
            raise ValueError(f"parameters for {component}: {given!r}; allowed: {{name: value}}")


def write_ssp(fmus: dict[str, Path], output: Path, stop_time: float = STOP_TIME,
              step: float = STEP, parameters: dict[str, dict[str, object]] | None = None) -> Path:
    """Write the SSP archive `output` from existing FMUs: `fmus` maps each of `gear`, `motor`,
    `fan` to its file.  `parameters` ({component: {name: value}}) replaces values of, or adds
    to, the default parameter set (DEFAULT_PARAMETERS at the FMUs' start values); every name
    must be a parameter of that component's FMU, every value one it allows (value_problem).
    The archive's entries are in name order with fixed timestamps: the same FMUs and values
    give the same bytes.  Returns `output`.  Raises ValueError naming a missing component, an
    unknown parameter, a value that is not allowed or a bad experiment, before anything is
    written; RuntimeError if `output` cannot be written."""
    check_experiment(stop_time, step)
    check_components(parameters or {})
    missing = sorted(set(FMU_FILES) - set(fmus))
    if missing:
        raise ValueError(f"no FMU for {', '.join(missing)}: give one for each of "
                         f"{', '.join(FMU_FILES)}")
    described = {name: read_component(Path(fmus[name]), FMU_FILES[name]) for name in FMU_FILES}
    values = parameter_values(described, parameters or {})
    check_gear_scene(Path(fmus["gear"]), values["gear"])
    ssd = system_structure(described, values, stop_time, step)
    entries = {"SystemStructure.ssd": ssd}
    entries.update({f"resources/{FMU_FILES[name]}": Path(fmus[name]).read_bytes()
                    for name in FMU_FILES})
    output = Path(output)
    try:
        output.parent.mkdir(parents=True, exist_ok=True)
        _write_zip(entries, output)
    except OSError as error:
        raise RuntimeError(f"cannot write {output}: {error}; give a file in a folder you can "
                           "write in") from error
    return output


def _write_zip(entries: dict[str, bytes], output: Path) -> None:
    """Write the archive whole or not at all (files.replace_file)."""
    def write(staging: Path) -> None:
        with zipfile.ZipFile(staging, "w") as archive:
            for name in sorted(entries):
                info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
                info.external_attr = 0o644 << 16
                # an FMU is a zip already: deflating it again gains nothing
                kind = zipfile.ZIP_DEFLATED if name.endswith(".ssd") else zipfile.ZIP_STORED
                archive.writestr(info, entries[name], compress_type=kind)

    replace_file(output, write)


def read_component(fmu: Path, file: str) -> ComponentFmu:
    """The ComponentFmu of the FMU `fmu`, to be packed as resources/`file`: its model
    description as fmpy reads it, and the bounds' annotations fmpy leaves out."""
    from fmpy import read_model_description

    description = read_model_description(str(fmu))
    with zipfile.ZipFile(fmu) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    units = {}
    for unit in description.unitDefinitions:
        base = unit.baseUnit
        attributes = {} if base is None else {
            **{key: str(getattr(base, key)) for key in BASE_UNIT_EXPONENTS if getattr(base, key)},
            **{key: xs_double(getattr(base, key)) for key, default in BASE_UNIT_DEFAULTS.items()
               if getattr(base, key) != default}}
        units[unit.name] = attributes
    return ComponentFmu(file, {v.name: v for v in description.modelVariables}, units,
                        exclusive_bounds(root))


def parameter_values(described: dict[str, ComponentFmu], overrides: Mapping) -> dict[str, dict]:
    """Each component's parameter set: DEFAULT_PARAMETERS at their start values, then
    `overrides` ({component: {name: value}}), each value as its FMI type's Python type.
    Raises ValueError for a name that is not a settable parameter of the FMU (the message
    lists those that are) or a value it does not allow (value_problem)."""
    values: dict[str, dict] = {
        name: {p: float(described[name].variables[p].start)
               for p in DEFAULT_PARAMETERS.get(name, ())} for name in FMU_FILES}
    for component, given in overrides.items():
        fmu = described[component]
        parameters = {n: v for n, v in fmu.variables.items() if v.causality == "parameter"}
        allowed = sorted(n for n, v in parameters.items() if v.type in SETTABLE_TYPES)
        for name, value in given.items():
            if name not in allowed:
                kind = f"an {parameters[name].type} parameter, which an SSP parameter set " \
                       "does not set" if name in parameters else "not a parameter"
                raise ValueError(f"{component}.{name} is {kind} of {fmu.file}; allowed: "
                                 f"{', '.join(allowed)}")
            problem = value_problem(component, fmu, name, value)
            if problem is not None:
                raise ValueError(f"{component}.{name} {problem}")
            values[component][name] = PYTHON_TYPES[parameters[name].type](value)
    return values


def value_problem(component: str, fmu: ComponentFmu, name: str, value) -> str | None:
    """Why `value` cannot be the parameter `name` of `component` ("is -1.0 N.m.s2/rad2;
    allowed: >= 0 N.m.s2/rad2 and finite"), or None: it must be of the parameter's FMI type,
    a number finite and within the range its FMU declares (`min`, `max`, and their
    exclusiveness as fmi_units marks it).  The gear's parameters and solver settings are
    checked first against herringbone's own ranges, which the gear FMU applies and which
    exclude some bounds its model description can only include (a mass of 0 kg)."""
    if component == "gear":
        problem = _gear_problem(name, value)
        if problem is not None:
            return problem
    variable = fmu.variables[name]
    if variable.type == "Boolean":
        return None if is_flag(value) \
            else f"must be true or false, got {type(value).__name__} {value!r}"
    if variable.type == "String":
        return None if isinstance(value, str) \
            else f"must be a string, got {type(value).__name__} {value!r}"
    whole = variable.type == "Integer"
    return number_problem(value, declared_range(variable, fmu.exclusive.get(name)),
                          "" if whole else variable.unit or "1", whole=whole)


def declared_range(variable, exclusive: tuple[bool, bool] | None = None) -> Range:
    """The values a numeric variable (fmpy's) allows: its `min` and `max` (or its declared
    type's), each `exclusive` as (min, max) say; an Integer's within fmi2Integer's 32 bits."""
    bounds = [getattr(variable, key) if getattr(variable, key) is not None
              else getattr(variable.declaredType, key, None) for key in ("min", "max")]
    low, high = (None if bound is None else float(bound) for bound in bounds)
    if variable.type == "Integer":  # also where the FMU declares no range
        low = INT32[0] if low is None else max(low, INT32[0])
        high = INT32[1] if high is None else min(high, INT32[1])
    low_open, high_open = exclusive or (False, False)
    return Range(low, high, low_open=low_open and low is not None,
                 high_open=high_open and high is not None)


def check_gear_scene(fmu: Path, values: dict) -> None:
    """Raise ValueError naming the gear's parameter where `values` ({name: value}) give its
    FMU's scene parameters that do not go together (an edge ramp over half a face: what
    Scene.with_parameters refuses, and the FMU with it), each value allowed on its own."""
    import tomllib

    from ..arguments import FMU_SCENE_MEMBER
    from ..model.scene import SceneError, scene_from_dict

    given = {name: value for name, value in values.items() if name in PARAMETERS}
    if not given:
        return
    with zipfile.ZipFile(fmu) as archive:
        tables = tomllib.loads(archive.read(FMU_SCENE_MEMBER).decode("utf-8"))
    try:
        scene_from_dict(tables, source=f"{fmu}:{FMU_SCENE_MEMBER}").with_parameters(**given)
    except SceneError as error:
        raise ValueError(f"gear.{error.key} {error.problem.removeprefix(f'{error.key} ')}"
                         if error.key else f"gear: {error.problem}") from None


def _gear_problem(name: str, value) -> str | None:
    """Why `value` is not allowed for the gear's parameter or solver setting `name` by
    herringbone's ranges (model.parameters, arguments), or None (also for another name)."""
    settings = {a.name: a for a in (FMU_SOLVER_TOLERANCE, FMU_MAX_STEP, FMU_SOLVER_METHOD)}
    if name in settings:
        return settings[name].problem(value)
    if name in PARAMETERS:
        return check_value(PARAMETERS[name], value)
    return None


def system_structure(described: dict[str, ComponentFmu], values: dict, stop_time: float,
                     step: float) -> bytes:
    """The SystemStructure.ssd document (UTF-8 bytes)."""
    root = ET.Element(_tag("ssd:SystemStructureDescription"), version="1.0", name="drivetrain")
    system = ET.SubElement(root, _tag("ssd:System"), name="drivetrain",
                           description="motor (Kloss curve) - herringbone gear train - fan")
    elements = ET.SubElement(system, _tag("ssd:Elements"))
    used: set[str] = set()
    for name in FMU_FILES:
        used |= _component(elements, name, described[name], values[name])
    connections = ET.SubElement(system, _tag("ssd:Connections"))
    for (start, output), (end, input_) in CONNECTIONS:
        ET.SubElement(connections, _tag("ssd:Connection"), startElement=start,
                      startConnector=output, endElement=end, endConnector=input_)
    unit_list = ET.SubElement(root, _tag("ssd:Units"))
    for unit in sorted(used):
        node = ET.SubElement(unit_list, _tag("ssc:Unit"), name=unit)
        ET.SubElement(node, _tag("ssc:BaseUnit"), base_unit(unit, described))
    _default_experiment(root, stop_time, step)
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def base_unit(unit: str, described: dict[str, ComponentFmu]) -> dict[str, str]:
    """ssc:BaseUnit's attributes of `unit`, as the FMUs' <UnitDefinitions> declare it (the
    unit "1", a pure number, also where none does).  Raises ValueError where two FMUs declare
    it differently."""
    declared = {c.file: c.units[unit] for c in described.values() if unit in c.units}
    if not declared and unit == "1":
        return {}
    first, *others = declared.items()  # _component made sure that one declares it
    for file, attributes in others:
        if attributes != first[1]:
            raise ValueError(f"unit {unit!r} is {first[1]} in {first[0]} and {attributes} in "
                             f"{file}; allowed: FMUs that define a unit alike")
    return first[1]


def _component(elements: ET.Element, name: str, fmu: ComponentFmu, values: dict) -> set[str]:
    """Add the Component `name` (connectors, parameter set); returns the units it uses.
    Raises ValueError for a unit the FMU's <UnitDefinitions> lacks."""
    component = ET.SubElement(elements, _tag("ssd:Component"), name=name,
                              source=f"resources/{fmu.file}",
                              type="application/x-fmu-sharedlibrary")
    connectors = ET.SubElement(component, _tag("ssd:Connectors"))
    wanted = [v for (a, out), (b, in_) in CONNECTIONS for c, v in ((a, out), (b, in_)) if c == name]
    units = set()
    for variable_name in dict.fromkeys(wanted + list(values)):
        variable = fmu.variables[variable_name]
        connector = ET.SubElement(connectors, _tag("ssd:Connector"), name=variable_name,
                                  kind=variable.causality)
        if variable.type != "Real":
            ET.SubElement(connector, _tag(f"ssc:{variable.type}"))
            continue
        unit = variable.unit or "1"
        if unit not in fmu.units and unit != "1":
            raise ValueError(f"{name}.{variable_name} has unit {unit!r}, which {fmu.file} does "
                             "not define; allowed: units of its <UnitDefinitions>")
        units.add(unit)
        ET.SubElement(connector, _tag("ssc:Real"), unit=unit)
    if values:
        binding = ET.SubElement(ET.SubElement(component, _tag("ssd:ParameterBindings")),
                                _tag("ssd:ParameterBinding"))
        parameter_set = ET.SubElement(ET.SubElement(binding, _tag("ssd:ParameterValues")),
                                      _tag("ssv:ParameterSet"), version="1.0", name=PARAMETER_SET)
        parameters = ET.SubElement(parameter_set, _tag("ssv:Parameters"))
        for parameter_name, value in values.items():
            _parameter(parameters, parameter_name, fmu.variables[parameter_name], value)
    return units


def _parameter(parameters: ET.Element, name: str, variable, value) -> None:
    """Add the ssv:Parameter `name` of the FMU's `variable` at `value` (checked): a Real with
    every bit and its unit, an Integer, a Boolean or a String."""
    parameter = ET.SubElement(parameters, _tag("ssv:Parameter"), name=name)
    if variable.type == "Real":
        ET.SubElement(parameter, _tag("ssv:Real"), value=xs_double(value),
                      unit=variable.unit or "1")
    else:
        text = str(value).lower() if variable.type == "Boolean" else str(value)
        ET.SubElement(parameter, _tag(f"ssv:{variable.type}"), value=text)


def _default_experiment(root: ET.Element, stop_time: float, step: float) -> None:
    experiment = ET.SubElement(root, _tag("ssd:DefaultExperiment"), startTime="0",
                               stopTime=repr(float(stop_time)))
    annotation = ET.SubElement(ET.SubElement(experiment, _tag("ssd:Annotations")),
                               _tag("ssc:Annotation"), type="com.opensimulationplatform")
    ET.SubElement(ET.SubElement(annotation, _tag("osp:Algorithm")),
                  _tag("osp:FixedStepAlgorithm"), baseStepSize=repr(float(step)))
