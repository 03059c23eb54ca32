"""The package's layout and the installed package as the product: the
stepping contract both integrators keep, no import cycles, an FMU runtime guard that imports
nothing heavy, shipped scenes by name, `herringbone scenes` and `build-fmu`, what the wheel
and the sdist carry. The install itself (non-editable, commands run from a temporary folder)
is .ci/installed_package's."""
import ast
import re
import shutil
import subprocess
import sys
import tarfile
import tomllib
from pathlib import Path

import pytest
from helpers import MODELS

import herringbone
from herringbone import cli, shipped
from herringbone.fmu import builder
from herringbone.integrate.compiled_stepper import CompiledStepper
from herringbone.integrate.contract import Stepper
from herringbone.integrate.stepping import ScipyStepper
from herringbone.model.assembly import GearTrainModel

ROOT = MODELS.parent
PACKAGE = Path(herringbone.__file__).resolve().parent


def test_both_steppers_satisfy_the_stepping_contract(reference_scene):
    model = GearTrainModel(reference_scene)
    for stepper in (ScipyStepper(model, 1e-10), CompiledStepper(model, 1e-7)):
        assert isinstance(stepper, Stepper)


def module_imports(path: Path, package: str) -> set[str]:
    """The herringbone modules a module imports anywhere: at its top level and inside its
    functions (a function-level import hides a cycle until the function runs)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")[:len(package.split(".")) - node.level + 1] \
                if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            found |= {module} | {f"{module}.{alias.name}" for alias in node.names}
        elif isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
    return found


def test_no_import_cycles_not_even_inside_functions():
    modules = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        package = ".".join(parts[:-1])
        if parts[-1] == "__init__":
            parts, package = parts[:-1], ".".join(parts[:-1])
        modules[".".join(parts)] = (path, package)
    graph = {}
    for name, (path, package) in modules.items():
        edges = set()
        for imported in module_imports(path, package):
            while imported:  # importing a.b.c runs a and a.b first
                # but not the packages that hold this module: their __init__ ran before it
                if imported in modules and not (name + ".").startswith(imported + "."):
                    edges.add(imported)
                imported = imported.rpartition(".")[0]
        graph[name] = edges
    done, on_path = set(), []

    def visit(name):
        if name in on_path:
            raise AssertionError(f"import cycle: {' -> '.join(on_path[on_path.index(name):])}"
                                 f" -> {name}")
        if name in done:
            return
        on_path.append(name)
        for imported in sorted(graph[name]):
            visit(imported)
        on_path.pop()
        done.add(name)

    for name in sorted(graph):
        visit(name)


MOST_LINES, MOST_PARAMETERS = 60, 12


def _function_sizes():
    """(where, lines, parameters) of every function and method of the package."""
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                parameters = (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                              + (a.vararg is not None) + (a.kwarg is not None))
                yield (f"{path.relative_to(PACKAGE).as_posix()}:{node.name}",
                       node.end_lineno - node.lineno + 1, parameters)


def test_every_function_fits_on_a_screen():
    """At most 60 lines (decorators aside, docstring included) and 12 parameters."""
    over = {where: (lines, parameters) for where, lines, parameters in _function_sizes()
            if lines > MOST_LINES or parameters > MOST_PARAMETERS}
    assert not over, f"over {MOST_LINES} lines or {MOST_PARAMETERS} parameters: {over}"


def test_the_library_imports_nothing_of_the_command_line():
    """herringbone.cli imports the library, never the other way round. (A `__main__.py`,
    what `python -m` runs, belongs to the command line: it is run, never imported.)"""
    importers = []
    for path in PACKAGE.rglob("*.py"):
        relative = path.relative_to(PACKAGE)
        if relative.parts[0] == "cli" or relative.name == "__main__.py":
            continue
        parts = list(relative.parent.parts)
        package = ".".join(["herringbone", *parts])
        if any(name == "herringbone.cli" or name.startswith("herringbone.cli.")
               for name in module_imports(path, package)):
            importers.append(str(relative))
    assert not importers, importers


# The package's floors, lowest first: a module imports from its own floor and those below it
FLOORS = ("compiling", "model", "integrate", "fmu", "analysis", "cli")


def test_no_subpackage_imports_from_a_floor_above_its_own():
    """How kernels are compiled (compiling) under the model and its equations, under the
    integrators, under the FMU, under the analysis that runs it, under the command line."""
    upward = []
    for path in PACKAGE.rglob("*.py"):
        relative = path.relative_to(PACKAGE)
        if relative.parts[0] not in FLOORS:
            continue
        floor = FLOORS.index(relative.parts[0])
        package = ".".join(["herringbone", *relative.parent.parts])
        for name in module_imports(path, package):
            parts = name.split(".")
            if len(parts) > 1 and parts[0] == "herringbone" and parts[1] in FLOORS \
                    and FLOORS.index(parts[1]) > floor:
                upward.append(f"{relative} imports {name}")
    assert not upward, upward


def _undocumented(tree, path, nested=False):
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            if not (node.name.startswith("_") or nested or ast.get_docstring(node)):
                yield f"{path}:{node.lineno} {node.name}"
            yield from _undocumented(node, path, nested or isinstance(node, ast.FunctionDef))


def test_every_public_function_class_and_kernel_has_a_docstring():
    """Module-level functions (the compiled kernels among them), classes and their methods;
    not functions nested inside a function."""
    missing = [entry for path in sorted(PACKAGE.rglob("*.py"))
               for entry in _undocumented(ast.parse(path.read_text()),
                                          path.relative_to(PACKAGE))]
    assert not missing, "no docstring: " + ", ".join(missing)


def test_the_fmu_runtime_guard_imports_no_numpy():
    """The slave imports herringbone.fmu.runtime before numpy, so that a missing dependency is
    named: importing it (and the packages' __init__.py on the way) must not import numpy."""
    program = ("import sys, herringbone.fmu.runtime\n"
               "heavy = sorted(m for m in sys.modules if m.split('.')[0] in "
               "('numpy', 'scipy', 'numba'))\n"
               "assert not heavy, heavy")
    run = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr


def test_version_is_pyprojects():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert herringbone.__version__ == pyproject["project"]["version"]


def test_a_shipped_scenes_name_loads_it_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scene = herringbone.load_scene("reference")
    assert Path(scene.source).resolve() == (MODELS / "reference.toml").resolve()
    assert scene.parameters == herringbone.load_scene(MODELS / "reference.toml").parameters
    assert herringbone.load_scene("parametric_resonance").name == "parametric_resonance"


def test_a_file_wins_over_a_shipped_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "reference").write_text('[parameters]\nstagger = 0.5\n', encoding="utf-8")
    assert herringbone.load_scene("reference").parameters["stagger"] == 0.5


def test_an_unknown_name_says_which_names_there_are(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(herringbone.SceneError) as error:
        herringbone.load_scene("referense")
    message = str(error.value)
    assert "no such scene file" in message and "reference, " in message
    assert "\n" not in message
    with pytest.raises(herringbone.SceneError) as error:  # a path is not taken for a name
        herringbone.load_scene(tmp_path / "absent.toml")
    assert "shipped" not in str(error.value)


def test_build_fmu_command_refuses_a_bad_scene_in_one_line(tmp_path, capsys):
    assert cli.main(["build-fmu", "referense", "-o", str(tmp_path / "x.fmu")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("herringbone build-fmu: ") and err.count("\n") == 1
    assert "no such scene file" in err
    assert not (tmp_path / "x.fmu").exists()


def test_build_fmu_command_builds_a_shipped_scene(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)

    assert cli.main(["build-fmu", "torsional", "-o", "t.fmu"]) == 0
    assert builder.validate(tmp_path / "t.fmu") == []
    assert f"built {tmp_path / 't.fmu'}" in capsys.readouterr().out


def test_the_wheel_ships_the_scenes_examples_and_the_fmus_pages():
    """pyproject.toml maps models/, examples/ and the pages a gear FMU carries (docs/) into
    the package as data."""
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    setuptools = pyproject["tool"]["setuptools"]
    assert setuptools["package-dir"]["herringbone.scenes"] == "models"
    assert setuptools["package-dir"]["herringbone.examples"] == "examples"
    assert setuptools["package-dir"]["herringbone.docs"] == "docs"
    assert set(setuptools["package-data"]["herringbone.docs"]) == set(builder.FMU_DOCUMENTS)
    data = {"herringbone.scenes", "herringbone.examples", "herringbone.docs"}
    packages = {".".join(path.relative_to(PACKAGE.parent).parent.parts)
                for path in PACKAGE.rglob("__init__.py")}
    assert packages | data == set(setuptools["packages"])
    assert shipped.scene_files()["reference"].resolve() == (MODELS / "reference.toml").resolve()


# What the source distribution carries beside the package (MANIFEST.in), and what a checkout
# generates, which it must not carry
SDIST_FOLDERS = ("docs", "tests", "benchmarks", ".ci", "models", "examples")
SDIST_FILES = ("README.md", "CHANGELOG.md", "build_fmu.py", "mkdocs.yml", "pyproject.toml",
               "MANIFEST.in")
GENERATED = (".git", ".venv", "dist", "build", "results", "site", "*.egg-info", "__pycache__",
             "*.py[cod]", "*.fmu", ".pytest_cache", ".hypothesis", ".mypy_cache", ".ruff_cache")
DECOYS = ("dist/reference-fmi2.fmu", "results/reference.csv", "site/index.html",
          "tests/__pycache__/conftest.cpython-311.pyc", "tests/.pytest_cache/v/cache/nodeids",
          "tests/fmu/reference.fmu", "fmu_src/herringbone/__pycache__/files.cpython-311.pyc")


def test_the_sdist_carries_the_docs_tests_and_tools_and_nothing_generated(tmp_path):
    """The source distribution of the checkout (setuptools' own, as `python -m build --sdist`
    makes it; a copy of the checkout with generated files added): the pages and the picture
    the README links, every test file (tests/helpers included), the benchmarks, the CI
    scripts, the CHANGELOG and build_fmu.py; no build, result, cache or FMU."""
    checkout = tmp_path / "checkout"
    shutil.copytree(ROOT, checkout, ignore=shutil.ignore_patterns(*GENERATED))
    for decoy in DECOYS:
        (checkout / decoy).parent.mkdir(parents=True, exist_ok=True)
        (checkout / decoy).write_text("generated\n")
    program = ("import sys; from setuptools import build_meta; "
               "print(build_meta.build_sdist(sys.argv[1]))")
    run = subprocess.run([sys.executable, "-c", program, str(tmp_path / "sdist")],
                         cwd=checkout, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-3000:]
    with tarfile.open(tmp_path / "sdist" / run.stdout.split()[-1]) as archive:
        shipped_files = {name.partition("/")[2] for name in archive.getnames()}
    wanted = {path.relative_to(checkout).as_posix() for folder in SDIST_FOLDERS
              for path in (checkout / folder).rglob("*") if path.is_file()}
    wanted -= set(DECOYS)
    assert {"tests/helpers/__init__.py", "benchmarks/common.py", ".ci/run"} <= wanted
    linked = set(re.findall(r"\]\(((?:docs/|CHANGELOG)[^)#]+)",
                            (ROOT / "README.md").read_text(encoding="utf-8")))
    assert len(linked) > 10 and "docs/images/run_reference.png" in linked
    assert not (wanted | set(SDIST_FILES) | linked) - shipped_files
    assert not set(DECOYS) & shipped_files


def test_the_package_tells_no_history():
    """The package says what is and why, not what happened: no "issue N" (history goes to the
    CHANGELOG, measurements to docs/)."""
    cited = [f"{path.relative_to(PACKAGE)}:{number}"
             for path in sorted(PACKAGE.rglob("*.py"))
             for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             if re.search(r"\bissues? \d+", line)]
    assert not cited, cited
