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

`write_ssp(fmus, output, …)` packs FMUs that exist; `build_ssp(scene, output, …)` builds them
first (herringbone.fmu.builder) and packs them.  The connections need the gear's motor and load
(w_motor and w_load are theirs): `scene_problem` says why a scene has no SSP, before any build.
"""
from __future__ import annotations

import math
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from ..files import replace_file
from ..model.scene import Scene, load_scene

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
# SI exponents of every unit a connector may carry (ssc:BaseUnit's attributes).
BASE_UNITS = {
    "rad/s": {"rad": 1, "s": -1},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N.m.s2/rad2": {"kg": 1, "m": 2, "rad": -2},
    "1": {},
    "rad": {"rad": 1},
    "s": {"s": 1},
}
STOP_TIME = 0.1  # s: the train has settled after about 0.05 s (tests/fmu/test_cosimulation.py)
# s: the explicit coupling of the Kloss curve's slope to the motor inertia is stable for
# h < 2·I/|dM/dw| ≈ 8e-4 s; 1e-4 s keeps the hold of the inputs far inside that.
STEP = 1e-4

for _prefix, _uri in NAMESPACES.items():
    ET.register_namespace(_prefix, _uri)


def _tag(qualified: str) -> str:
    prefix, name = qualified.split(":")
    return f"{{{NAMESPACES[prefix]}}}{name}"


def build_ssp(scene: Path, output: Path, stop_time: float = STOP_TIME, step: float = STEP,
              parameters: dict[str, dict[str, float]] | None = None) -> Path:
    """The drive train as an SSP archive: the gear FMU of `scene` and the example motor and
    fan FMUs, connected by their SSD (write_ssp).

    Parameters
    ----------
    scene : str or pathlib.Path
        A scene file, or the name of a shipped scene.
    output : pathlib.Path
        The .ssp file to write (replaced if it exists).
    stop_time, step : float
        The default experiment the SSD carries: its stop time and communication step, s.
    parameters : dict or None
        {component: {name: value}}, replacing or adding to the default parameter set.

    Returns
    -------
    pathlib.Path
        `output`.

    Raises
    ------
    SceneError
        A bad scene.
    ValueError
        A scene without a motor or a load (scene_problem), before any build; a bad experiment
        or parameter (write_ssp).
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
    problem = scene_problem(load_scene(scene))
    if problem is not None:
        raise ValueError(problem)
    from .builder import build_example_fmus, build_gear_fmu

    with tempfile.TemporaryDirectory(prefix="drivetrain_ssp_") as tmp:
        folder = Path(tmp)
        gear = build_gear_fmu(scene=Path(scene), output=folder / FMU_FILES["gear"])
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


def write_ssp(fmus: dict[str, Path], output: Path, stop_time: float = STOP_TIME,
              step: float = STEP, parameters: dict[str, dict[str, float]] | None = None) -> Path:
    """Write the SSP archive `output` from existing FMUs: `fmus` maps each of `gear`, `motor`,
    `fan` to its file.  `parameters` ({component: {name: value}}) replaces values of, or adds
    to, the default parameter set (DEFAULT_PARAMETERS at the FMUs' start values); every name
    must be a Real parameter of that component's FMU.  The archive's entries are in name order
    with fixed timestamps: the same FMUs and values give the same bytes.  Returns `output`.
    Raises ValueError naming a missing component, an unknown parameter or a bad experiment;
    RuntimeError if `output` cannot be written."""
    check_experiment(stop_time, step)
    missing = sorted(set(FMU_FILES) - set(fmus))
    if missing:
        raise ValueError(f"no FMU for {', '.join(missing)}: give one for each of "
                         f"{', '.join(FMU_FILES)}")
    variables = {name: _variables(Path(fmus[name])) for name in FMU_FILES}
    values = parameter_values(variables, parameters or {})
    ssd = system_structure(variables, values, stop_time, step)
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


def _variables(fmu: Path) -> dict:
    """The FMU's model variables by name (fmpy's ScalarVariable objects)."""
    from fmpy import read_model_description

    return {v.name: v for v in read_model_description(str(fmu)).modelVariables}


def parameter_values(variables: dict, overrides: dict) -> dict[str, dict[str, float]]:
    """Each component's parameter set: DEFAULT_PARAMETERS at their start values, then
    `overrides`.  Raises ValueError for a name that is not a Real parameter of the FMU."""
    values = {name: {p: float(variables[name][p].start) for p in DEFAULT_PARAMETERS.get(name, ())}
              for name in FMU_FILES}
    for component, given in overrides.items():
        if component not in FMU_FILES:
            raise ValueError(f"parameters for {component!r}: allowed components: "
                             f"{', '.join(FMU_FILES)}")
        allowed = sorted(n for n, v in variables[component].items()
                         if v.causality == "parameter" and v.type == "Real")
        for name, value in given.items():
            if name not in allowed:
                raise ValueError(f"{component}.{name} is not a Real parameter of "
                                 f"{FMU_FILES[component]}; allowed: {', '.join(allowed)}")
            values[component][name] = float(value)
    return values


def system_structure(variables: dict, values: dict, stop_time: float, step: float) -> bytes:
    """The SystemStructure.ssd document (UTF-8 bytes)."""
    root = ET.Element(_tag("ssd:SystemStructureDescription"), version="1.0", name="drivetrain")
    system = ET.SubElement(root, _tag("ssd:System"), name="drivetrain",
                           description="motor (Kloss curve) - herringbone gear train - fan")
    elements = ET.SubElement(system, _tag("ssd:Elements"))
    units = set()
    for name in FMU_FILES:
        units |= _component(elements, name, variables[name], values[name])
    connections = ET.SubElement(system, _tag("ssd:Connections"))
    for (start, output), (end, input_) in CONNECTIONS:
        ET.SubElement(connections, _tag("ssd:Connection"), startElement=start,
                      startConnector=output, endElement=end, endConnector=input_)
    unit_list = ET.SubElement(root, _tag("ssd:Units"))
    for unit in sorted(units):
        node = ET.SubElement(unit_list, _tag("ssc:Unit"), name=unit)
        ET.SubElement(node, _tag("ssc:BaseUnit"),
                      {k: str(v) for k, v in BASE_UNITS[unit].items()})
    _default_experiment(root, stop_time, step)
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _component(elements: ET.Element, name: str, variables: dict, values: dict) -> set[str]:
    """Add the Component `name` (connectors, parameter set); returns the units it uses."""
    component = ET.SubElement(elements, _tag("ssd:Component"), name=name,
                              source=f"resources/{FMU_FILES[name]}",
                              type="application/x-fmu-sharedlibrary")
    connectors = ET.SubElement(component, _tag("ssd:Connectors"))
    wanted = [v for (a, out), (b, in_) in CONNECTIONS for c, v in ((a, out), (b, in_)) if c == name]
    units = set()
    for variable_name in dict.fromkeys(wanted + list(values)):
        variable = variables[variable_name]
        unit = variable.unit or "1"
        if unit not in BASE_UNITS:
            raise ValueError(f"{name}.{variable_name} has unit {unit!r}; known units: "
                             f"{', '.join(BASE_UNITS)}")
        units.add(unit)
        connector = ET.SubElement(connectors, _tag("ssd:Connector"), name=variable_name,
                                  kind=variable.causality)
        ET.SubElement(connector, _tag("ssc:Real"), unit=unit)
    if values:
        binding = ET.SubElement(ET.SubElement(component, _tag("ssd:ParameterBindings")),
                                _tag("ssd:ParameterBinding"))
        parameter_set = ET.SubElement(ET.SubElement(binding, _tag("ssd:ParameterValues")),
                                      _tag("ssv:ParameterSet"), version="1.0", name=PARAMETER_SET)
        parameters = ET.SubElement(parameter_set, _tag("ssv:Parameters"))
        for parameter_name, value in values.items():
            parameter = ET.SubElement(parameters, _tag("ssv:Parameter"), name=parameter_name)
            ET.SubElement(parameter, _tag("ssv:Real"), value=repr(value),
                          unit=variables[parameter_name].unit or "1")
    return units


def _default_experiment(root: ET.Element, stop_time: float, step: float) -> None:
    experiment = ET.SubElement(root, _tag("ssd:DefaultExperiment"), startTime="0",
                               stopTime=repr(float(stop_time)))
    annotation = ET.SubElement(ET.SubElement(experiment, _tag("ssd:Annotations")),
                               _tag("ssc:Annotation"), type="com.opensimulationplatform")
    ET.SubElement(ET.SubElement(annotation, _tag("osp:Algorithm")),
                  _tag("osp:FixedStepAlgorithm"), baseStepSize=repr(float(step)))
