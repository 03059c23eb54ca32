"""Build pythonfmu co-simulation FMUs that pass `fmpy validate`: `build_gear_fmu` (the FMU of
a scene, FMI 2.0 or 3.0), `build_example_fmus` (the drive-train examples), and the generic
`build_slave_fmu`, `fix_model_description`, `validate`. The command is `herringbone build-fmu`
(herringbone.cli.build_fmu).

pythonfmu builds an FMU from a script, whose module name must be unique in a host process (two
FMUs whose scripts share a name clash in sys.modules): the slave's source is
herringbone/fmu/slave.py (FMI 2.0) or slave3.py (FMI 3.0), both thin adapters over
herringbone/fmu/core.py, and the builder hands pythonfmu(3) a copy named `GEAR_SLAVE_MODULE`
(FMI 2.0) or `GEAR_SLAVE3_MODULE` (FMI 3.0). The FMU carries the modules of the package its
run imports (carried.py) and the compiled code its run loads (carry_compiled_integrator).
"""
from __future__ import annotations

import hashlib
import html
import itertools
import os
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from .. import shipped
from ..arguments import FMU_SCENE_FILE
from ..files import replace_file
from . import carried as carried_package
from .resource_path import with_resource_path

GEAR_PACKAGE = carried_package.PACKAGE  # herringbone
GEAR_SLAVE = GEAR_PACKAGE / "fmu" / "slave.py"
GEAR_SLAVE_MODULE = "herringbone_gear_fmu"  # the script's name in the FMU (see above)
GEAR_SLAVE3 = GEAR_PACKAGE / "fmu" / "slave3.py"
GEAR_SLAVE3_MODULE = "herringbone_gear_fmu3"  # not the FMI 2.0 one's: both may share a process
FMI_VERSIONS = (2, 3)
# the binaries an FMU keeps: FMI 2.0's and FMI 3.0's names of Linux x86-64
LINUX_BINARIES = ("binaries/linux64/", "binaries/x86_64-linux/")
# shipped with every FMI 2.0 FMU as top-level modules (the examples import them so): see their
# docstrings
UNITS_MODULE = GEAR_PACKAGE / "fmu" / "units.py"
UNITS_MODULE_NAME = "fmi_units"
REFERENCES_MODULE = GEAR_PACKAGE / "fmu" / "pythonfmu_references.py"
REFERENCES_MODULE_NAME = "pythonfmu_references"
DEFAULT_SCENE = "reference"  # a shipped scene's name
# the pages of docs/ a gear FMU carries in its documentation folder (pyproject.toml ships them)
FMU_DOCUMENTS = {"model.md": "the model: its physics, conventions, variables and their units",
                 "hosts.md": "what a host needs, and how the FMU answers each host",
                 "fmi3.md": "what differs in the FMI 3.0 FMU",
                 "known-issues.md": "the faults of pythonfmu this FMU cures, and how"}
ENTRY_PAGE = """<!DOCTYPE html>
<html lang="en">
<head><meta charset="utf-8"><title>HerringboneGear: {scene}</title></head>
<body>
<h1>HerringboneGear: the scene {scene}</h1>
<p>{header}</p>
<p>A herringbone Novikov gear train (motor, pinion, wheel and load) as a co-simulation FMU,
built by the herringbone package from the scene in resources/scene.toml. Its pages, as
Markdown text:</p>
<ul>
{links}
</ul>
<h2>model.md</h2>
<pre>{model}</pre>
</body>
</html>
"""

# FMI 2.0 default `initial` (spec table p. 49), keyed by (causality, variability).
_DEFAULT_INITIAL = {
    ("parameter", "fixed"): "exact", ("parameter", "tunable"): "exact",
    ("calculatedParameter", "fixed"): "calculated",
    ("calculatedParameter", "tunable"): "calculated",
    ("output", "constant"): "exact", ("output", "discrete"): "calculated",
    ("output", "continuous"): "calculated",
    ("local", "constant"): "exact", ("local", "fixed"): "calculated",
    ("local", "tunable"): "calculated", ("local", "discrete"): "calculated",
    ("local", "continuous"): "calculated",
}
# Schema order of fmiModelDescription's children: UnitDefinitions must precede these.
_AFTER_UNIT_DEFINITIONS = ("TypeDefinitions", "LogCategories", "DefaultExperiment",
                           "VendorAnnotations", "ModelVariables", "ModelStructure")


def build_slave_fmu(slave_script: Path, project_files: list[Path], output: Path,
                    handle_state: bool = True, serialize_state: bool = False,
                    no_feedthrough: bool = False, fmi_version: int = 2,
                    documentation: Path | None = None) -> Path:
    """Build `slave_script` (one pythonfmu Fmi2Slave class, or for `fmi_version` 3 one
    pythonfmu3 Fmi3Slave class) into the FMU file `output`.

    `project_files` (files or package directories, copied recursively) land in the FMU's
    `resources/`, which the FMU puts on `sys.path` at run time; the folders that hold its
    directories and .py files go on the build's PYTHONPATH, so that they import there too (the
    builder imports the script to write the model description). For FMI 2.0 this module's
    `UNITS_MODULE` and `REFERENCES_MODULE` go with them, as `fmi_units` and
    `pythonfmu_references`. `handle_state` declares
    canGetAndSetFMUstate; `serialize_state` declares canSerializeFMUstate (the slave's state
    must then be JSON data, or the slave must override pythonfmu's `_fmu_state_to_bytes`);
    `no_feedthrough`: see `fix_model_description`.  `documentation`: a folder that becomes
    the FMU's documentation/ (FMI 2.0: with _main.html; 3.0: index.html).  An FMI 2.0 FMU gets
    its own library in front of pythonfmu's (`resource_path.with_resource_path`: a
    ResourcePathWarning where no C compiler is found). The model description is then fixed by
    `fix_model_description`.
    `output` (its parent directories are created) is replaced only once the FMU is complete and
    valid.  Needs pythonfmu (pythonfmu3) and fmpy importable by `sys.executable`.  Returns
    `output`.  Raises RuntimeError if pythonfmu fails or `fmpy validate` finds problems.
    """
    slave_script, output = Path(slave_script).resolve(), Path(output).resolve()
    with tempfile.TemporaryDirectory(prefix="build_fmu_") as tmp:
        project_files = [Path(p).resolve() for p in project_files]
        if fmi_version == 2:  # pythonfmu's variables with units; its references balanced
            (Path(tmp) / "shipped").mkdir()
            for module, name in ((UNITS_MODULE, UNITS_MODULE_NAME),
                                 (REFERENCES_MODULE, REFERENCES_MODULE_NAME)):
                shutil.copyfile(module, Path(tmp) / "shipped" / f"{name}.py")
                project_files.append(Path(tmp) / "shipped" / f"{name}.py")
        # A separate interpreter: pythonfmu's builder imports the script and leaves it in
        # sys.modules and its folder on sys.path; an FMU loaded later in the same process would
        # then run that source copy instead of the packaged one.
        builder = {2: "pythonfmu", 3: "pythonfmu3"}[fmi_version]
        command = [sys.executable, "-m", builder, "build", "-f", str(slave_script),
                   "-d", tmp, *map(str, project_files)]
        command += [option for option, wanted in (("--handle-state", handle_state),
                                                  ("--serialize-state", serialize_state))
                    if wanted]
        command += ["--doc", str(documentation)] if documentation is not None else []
        import_paths = [str(p.parent) for p in project_files if p.is_dir() or p.suffix == ".py"]
        if os.environ.get("PYTHONPATH"):
            import_paths.append(os.environ["PYTHONPATH"])
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(import_paths)}
        run = subprocess.run(command, env=env, capture_output=True, text=True)
        built = sorted(Path(tmp).glob("*.fmu"))
        if run.returncode != 0 or len(built) != 1:
            raise RuntimeError(f"{builder} build of {slave_script} failed:\n{run.stderr}")
        if fmi_version == 2:
            with_resource_path(built[0])
        fix_model_description(fmu_path=built[0], no_feedthrough=no_feedthrough)
        problems = validate(fmu_path=built[0])
        if problems:
            raise RuntimeError(f"{slave_script.name}: fmpy validate found\n" + "\n".join(problems))
        output.parent.mkdir(parents=True, exist_ok=True)
        replace_file(target=output, write=lambda staging: shutil.copyfile(built[0], staging))
    return output


def fix_model_description(fmu_path: Path, no_feedthrough: bool = False) -> None:
    """Rewrite the modelDescription.xml inside the FMU zip `fmu_path` in place.

    pythonfmu 0.7.0 writes no `<InitialUnknowns>`, cannot declare units, and stamps every
    build with a new GUID and the time. For an FMI 3.0 FMU (pythonfmu3) see
    `_fix_fmi3_description`.  This regenerates `<ModelStructure>` (Outputs and
    InitialUnknowns, 1-based indices into ModelVariables, per FMI 2.0 section 3.4.8; an output
    depends on no input directly: in co-simulation the outputs at a communication point follow
    from the state, so `dependencies=""`), adds a `<UnitDefinitions>` entry for every
    `unit`/`displayUnit` used by a variable (a slave sets them on the `<Real>` element, see
    examples/), drops generationDateAndTime and sets the GUID to a hash of the FMU's content
    (_content_guid). It drops the binaries of every platform but Linux x86-64 (pythonfmu's
    and pythonfmu3's Windows ones): the FMU is built and tested on Linux only (docs/hosts.md),
    and a host elsewhere should say so rather than load an untried library.
    The zip is rewritten in name order with fixed timestamps and permissions, so that the same
    content makes the same bytes.  Idempotent; all other entries' contents are unchanged.
    """
    fmu_path = Path(fmu_path)
    with zipfile.ZipFile(fmu_path) as zf:
        entries = {info: zf.read(info) for info in zf.infolist()}
    root = ET.fromstring(entries[next(i for i in entries if i.filename == "modelDescription.xml")])
    token = "guid"
    if root.get("fmiVersion", "").startswith("3"):
        _fix_fmi3_description(root, no_feedthrough)
        token = "instantiationToken"
    else:
        _rebuild_model_structure(root, no_feedthrough)
    _add_unit_definitions(root)
    root.attrib.pop("generationDateAndTime", None)
    root.set(token, "")
    for element in root.iter():  # pythonfmu3 pretty-prints: start from bare elements
        element.text = element.tail = None
    ET.indent(root, space="  ")
    contents = {info.filename: data for info, data in entries.items()
                if not info.filename.startswith("binaries/")
                or info.filename.startswith(LINUX_BINARIES)}
    contents["modelDescription.xml"] = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    root.set(token, "{" + _content_guid(contents) + "}")
    contents["modelDescription.xml"] = ET.tostring(root, encoding="UTF-8", xml_declaration=True)

    def write(staging: Path) -> None:
        with zipfile.ZipFile(staging, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            for name in sorted(contents):
                info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
                info.external_attr = (0o40755 << 16 | 0x10) if name.endswith("/") \
                    else 0o644 << 16
                zf.writestr(info, contents[name], compress_type=zipfile.ZIP_DEFLATED)

    replace_file(target=fmu_path, write=write)


def _content_guid(contents: dict[str, bytes]) -> str:
    """A GUID (8-4-4-4-12 hex digits) from the SHA-256 of every entry's name and content (the
    model description with an empty guid) but the compiled code carried for a first start
    (resources/numba_cache): FMUs of the same model, code and scene share it, any change to
    those moves it. The carried code is compiled for the build machine's kind
    (carry_compiled_integrator), and the FMI's GUID is the fingerprint of the model
    description and the model it belongs to."""
    from ..integrate.first_start import CARRIED_FOLDER

    cache = f"resources/{CARRIED_FOLDER}/"
    digest = hashlib.sha256()
    for name in sorted(name for name in contents if not name.startswith(cache)):
        for part in (name.encode(), contents[name]):
            digest.update(len(part).to_bytes(8, "little") + part)
    hex_digits = digest.hexdigest()[:32]
    return "-".join(hex_digits[a:b] for a, b in ((0, 8), (8, 12), (12, 16), (16, 20), (20, 32)))


def _rebuild_model_structure(root: ET.Element, no_feedthrough: bool) -> None:
    """An FMI 2.0 model description's <ModelStructure>, written anew from its variables: see
    `fix_model_description`."""
    variables = root.findall("ModelVariables/ScalarVariable")
    outputs, initial_unknowns = [], []
    for index, var in enumerate(variables, start=1):
        causality = var.get("causality", "local")
        initial = var.get("initial") or _DEFAULT_INITIAL.get(
            (causality, var.get("variability", "continuous")))
        if causality == "output":
            outputs.append(index)
        if (causality == "output" and initial in ("approx", "calculated")) \
                or causality == "calculatedParameter":
            initial_unknowns.append(index)
    # pythonfmu FMUs are co-simulation only: no Derivatives to carry over.
    for old in root.findall("ModelStructure"):
        root.remove(old)
    structure = ET.SubElement(root, "ModelStructure")
    # InitialUnknowns keep FMI's default dependencies: on every known (the outputs at the start
    # follow from the parameters and the inputs' start values)
    for tag, indices, extra in (("Outputs", outputs,
                                 {"dependencies": ""} if no_feedthrough else {}),
                                ("InitialUnknowns", initial_unknowns, {})):
        if indices:
            node = ET.SubElement(structure, tag)
            for index in indices:
                ET.SubElement(node, "Unknown", {"index": str(index), **extra})


def _fix_fmi3_description(root: ET.Element, no_feedthrough: bool) -> None:
    """What pythonfmu3 0.3.4 leaves out of an FMI 3.0 model description or gets wrong: the
    outputs' dependencies (`no_feedthrough`: none, `dependencies=""`, as for FMI 2.0), and the
    co-simulation capabilities it writes from a stray loop variable
    (canHandleVariableCommunicationStepSize: the slave takes any step). Units: see
    `_add_unit_definitions`; the instantiation token: `fix_model_description`."""
    cosimulation = root.find("CoSimulation")
    if cosimulation is not None:
        cosimulation.set("canHandleVariableCommunicationStepSize", "true")
    structure = root.find("ModelStructure")
    if no_feedthrough and structure is not None:
        for output in structure.findall("Output"):
            output.set("dependencies", "")


# The SI base units of every unit the FMUs name, as FMI's <BaseUnit> exponents (FMI 2.0
# section 2.2.2, 3.0 section 2.4.3), so that a host can check and convert what it connects
# ("1": a pure number, no exponent).
BASE_UNITS = {
    "1": {}, "s": {"s": 1}, "m": {"m": 1}, "kg": {"kg": 1}, "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1}, "kg.m2": {"kg": 1, "m": 2},
    "N": {"kg": 1, "m": 1, "s": -2}, "N.m": {"kg": 1, "m": 2, "s": -2},
    "N/m": {"kg": 1, "s": -2}, "N.s/m": {"kg": 1, "s": -1},
    "N.m/rad": {"kg": 1, "m": 2, "s": -2, "rad": -1},
    "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
    "N.m.s2/rad2": {"kg": 1, "m": 2, "rad": -2},
}


def _add_unit_definitions(root: ET.Element) -> None:
    """A <Unit> (with its <BaseUnit> from BASE_UNITS and its <DisplayUnit>s) in
    <UnitDefinitions> for every unit a real variable names that is not declared yet;
    <UnitDefinitions> is created where needed, in its place in the schema's order."""
    used: dict[str, set[str]] = {}
    for real in [*root.iter("Real"), *root.iter("Float64")]:  # FMI 2.0, FMI 3.0
        unit_name, display_name = real.get("unit"), real.get("displayUnit")
        if unit_name:
            used.setdefault(unit_name, set())
            if display_name:
                used[unit_name].add(display_name)
    definitions = root.find("UnitDefinitions")
    if definitions is None:
        if not used:
            return
        position = next((i for i, child in enumerate(root) if child.tag in _AFTER_UNIT_DEFINITIONS),
                        len(root))
        definitions = ET.Element("UnitDefinitions")
        root.insert(position, definitions)
    declared = {unit.get("name"): unit for unit in definitions.findall("Unit")}
    for name in sorted(used):
        unit = declared.get(name)
        if unit is None:  # not `or`: an Element without children is falsy
            unit = ET.SubElement(definitions, "Unit", name=name)
            if name in BASE_UNITS:  # first: the schema puts it before the display units
                ET.SubElement(unit, "BaseUnit",
                              {dimension: str(power)
                               for dimension, power in BASE_UNITS[name].items()})
        known = {d.get("name") for d in unit.findall("DisplayUnit")}
        for display in sorted(used[name] - known):
            ET.SubElement(unit, "DisplayUnit", name=display)


def validate(fmu_path: Path) -> list[str]:
    """Problems `fmpy validate` reports for `fmu_path` (schema, structure, start values, units).

    An empty list means valid.
    """
    from fmpy.validation import validate_fmu

    return list(validate_fmu(str(fmu_path)))


def build_example_fmus(output_dir: Path) -> list[Path]:
    """Build examples/induction_motor.py and examples/fan_load.py (shipped with the package:
    herringbone.shipped.examples_folder) into `output_dir`.

    Returns the FMU paths (InductionMotor.fmu, FanLoad.fmu); existing files of those names in
    `output_dir` are replaced.
    """
    output_dir = Path(output_dir)
    return [build_slave_fmu(slave_script=shipped.examples_folder() / script, project_files=[],
                            output=output_dir / fmu_name, handle_state=True)
            for script, fmu_name in (("induction_motor.py", "InductionMotor.fmu"),
                                     ("fan_load.py", "FanLoad.fmu"))]


def build_gear_fmu(scene, output: Path, fmi_version: int = 2) -> Path:
    """Build the gear train's co-simulation FMU of a scene: the slave, the modules of the
    herringbone package its run imports (carried.py), the compiled code its run loads and the
    scene (as resources/scene.toml) go into it; its variables are exactly the scene's.

    Parameters
    ----------
    scene : str, pathlib.Path or Scene
        A scene file, the name of a shipped scene, or a Scene (`herringbone.load_scene`,
        changed by its `with_parameters` or `with_inputs`).
    output : pathlib.Path
        The .fmu file to write (replaced if it exists).
    fmi_version : int
        2 (FMI 2.0, pythonfmu) or 3 (FMI 3.0, pythonfmu3).

    Returns
    -------
    pathlib.Path
        `output`.

    Raises
    ------
    SceneError
        A bad scene, in the scene's own words, before any build.
    ValueError
        Another `fmi_version`.

    Examples
    --------
    >>> from pathlib import Path
    >>> import fmpy
    >>> from herringbone.fmu.builder import build_gear_fmu
    >>> fmu = build_gear_fmu("reference", Path("reference.fmu"))
    >>> result = fmpy.simulate_fmu(str(fmu), stop_time=0.005, output_interval=1e-3)
    >>> len(result), round(float(result["F_mesh"][-1]), 1)  # samples, N at 5 ms
    (6, 21864.8)
    """
    if fmi_version not in FMI_VERSIONS:
        raise ValueError(f"fmi_version {fmi_version!r}; allowed: 2 or 3")
    with tempfile.TemporaryDirectory(prefix="gear_scene_") as tmp:
        scene = scene_file(scene, Path(tmp))
        scene_copy = Path(tmp) / FMU_SCENE_FILE
        shutil.copyfile(scene, scene_copy)
        carried = carry_compiled_integrator(scene, Path(tmp))
        source, module = ((GEAR_SLAVE, GEAR_SLAVE_MODULE) if fmi_version == 2
                          else (GEAR_SLAVE3, GEAR_SLAVE3_MODULE))
        slave = Path(tmp) / "slave" / f"{module}.py"
        slave.parent.mkdir()
        shutil.copyfile(source, slave)
        package = carried_package.stage_package(Path(tmp) / "package")
        documentation = write_documentation(scene, Path(tmp) / "documentation", fmi_version)
        return build_slave_fmu(slave_script=slave,
                               project_files=[package, scene_copy, carried],
                               output=output, handle_state=True, serialize_state=True,
                               no_feedthrough=True, fmi_version=fmi_version,
                               documentation=documentation)


def write_documentation(scene: Path, folder: Path, fmi_version: int) -> Path:
    """The gear FMU's documentation folder, made in `folder`: the pages of FMU_DOCUMENTS as
    they are, and the entry page the standard names (FMI 2.0: _main.html, 3.0: index.html),
    which says what the FMU is (its scene file's opening comment) and shows the model's page.
    Returns `folder`."""
    folder.mkdir(parents=True)
    pages = shipped.docs_folder()
    for name in FMU_DOCUMENTS:
        shutil.copyfile(pages / name, folder / name)
    lines = scene.read_text(encoding="utf-8").splitlines()
    header = [line[1:].strip()
              for line in itertools.takewhile(lambda line: line.startswith("#"), lines)]
    links = "\n".join(f'<li><a href="{name}">{name}</a>: {what}</li>'
                      for name, what in FMU_DOCUMENTS.items())
    model = html.escape((pages / "model.md").read_text(encoding="utf-8"))
    entry = ENTRY_PAGE.format(scene=html.escape(scene.stem), header=html.escape(" ".join(header)),
                              links=links, model=model)
    (folder / ("_main.html" if fmi_version == 2 else "index.html")).write_text(
        entry, encoding="utf-8")
    return folder


def scene_file(scene, folder: Path) -> Path:
    """The scene file of `scene`: a Scene written into `folder`, named as the scene; a scene
    file, or a shipped scene's name, checked (a bad scene is reported here, in the scene's own
    words) and as it is."""
    from ..model.scene import Scene, load_scene, scene_file_text

    if isinstance(scene, Scene):
        path = folder / "given" / f"{scene.name}.toml"  # apart from the FMU's own scene.toml
        path.parent.mkdir()
        path.write_text(scene_file_text(scene, f"{scene.name}, as handed to the FMU's build"),
                        encoding="utf-8")
        return path
    load_scene(scene)
    return shipped.resolve_scene(scene)


def carry_compiled_integrator(scene: Path, folder: Path) -> Path:
    """Compile the integrator for this machine as the scene's FMU runs it (once: later builds
    load it from the user's cache, herringbone.compiling.cache), saying so first and
    showing progress on stderr (apart from what a caller prints), and copy the compiled code
    that a run of the FMU loads into `folder`/numba_cache, which the FMU carries in its resources
    (herringbone.integrate.first_start.carry_for_scene). Returns that folder. Raises
    RuntimeError if the cache folder lacks what was compiled (it could not be written)."""
    from ..compiling import cache
    from ..integrate import first_start
    from ..integrate.compiled import walk

    # in this process: a build after the first (the test suite's) finds the code loaded
    first_start.compile_for_scene(scene, say=lambda message: print(message, file=sys.stderr,
                                                                   flush=True))
    cache.require_on_disk(walk.advance)  # before a fresh process would compile it again
    # what a run loads, taken in a fresh process: a compile caches every kernel the loop
    # calls as well (its own code holds them), and this process may hold other scenes' code
    carried = Path(folder) / first_start.CARRIED_FOLDER
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join(  # the package built from
        [str(GEAR_PACKAGE.parent), *filter(None, [os.environ.get("PYTHONPATH")])])}
    run = subprocess.run([sys.executable, "-m", "herringbone.integrate.first_start",
                          str(scene), str(carried)],
                         env=environment, capture_output=True, text=True)
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or [f"exit status {run.returncode}"])[-1]
        raise RuntimeError(f"cannot carry the compiled integrator into the FMU: {last}")
    return carried


def default_fmu_name(scene_name: str, fmi_version: int) -> str:
    """The file name of a scene's FMU unless told otherwise, "<scene>-fmi<N>.fmu": each scene
    and FMI version its own file."""
    return f"{scene_name}-fmi{fmi_version}.fmu"
