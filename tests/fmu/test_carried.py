"""What a gear FMU carries of the package: the modules its run imports (herringbone.fmu.carried)."""
import shutil
import subprocess
import sys
import zipfile

from herringbone import installed, shipped
from herringbone.compiling import sources
from herringbone.fmu import carried

# A host process that has never imported herringbone runs the FMU (a state round trip, then a
# bad parameter, whose message is an error path), and prints the herringbone modules it
# imported: the FMU's own copy of them.
RUN_IN_A_HOST = """
import sys, fmpy
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
fmu = sys.argv[1]
fmpy.simulate_fmu(fmu, stop_time=0.002, output_interval=1e-4)
description, folder = read_model_description(fmu), extract(fmu)
slave = FMU2Slave(guid=description.guid, unzipDirectory=folder, instanceName="round_trip",
                  modelIdentifier=description.coSimulation.modelIdentifier)
slave.instantiate()
slave.setupExperiment(startTime=0.0)
slave.enterInitializationMode()
slave.exitInitializationMode()
slave.doStep(0.0, 1e-3)
state = slave.deSerializeFMUstate(slave.serializeFMUstate(slave.getFMUstate()))
slave.setFMUstate(state)
slave.doStep(1e-3, 1e-3)
slave.terminate()
slave.freeInstance()
try:
    fmpy.simulate_fmu(fmu, stop_time=0.002, start_values={"zeta_mesh": -1.0})
except Exception:
    pass
# the FMU's own copy, not one this interpreter could find elsewhere
assert all("/resources/herringbone/" in module.__file__
           for name, module in sys.modules.items() if name.startswith("herringbone."))
print(" ".join(sorted(name for name in sys.modules if name.split(".")[0] == "herringbone")))
"""


def test_what_a_host_imports_of_the_fmu_is_among_the_modules_it_carries(built_fmus):
    run = subprocess.run([sys.executable, "-c", RUN_IN_A_HOST, str(built_fmus["reference"])],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    imported = set(run.stdout.split())
    assert "herringbone.fmu.core" in imported and "herringbone.integrate.compiled.walk" in imported
    assert imported <= carried.runtime_modules()


def test_an_fmu_carries_the_modules_its_run_imports_and_not_the_analysis(built_fmus):
    for fmu in (built_fmus["reference"], built_fmus["staggered"]):
        names = {name.removeprefix("resources/") for name in zipfile.ZipFile(fmu).namelist()
                 if name.startswith("resources/herringbone/")
                 and not name.endswith(f"/{installed.MARKER}")}
        expected = {carried._file_of(module).relative_to(carried.PACKAGE.parent).as_posix()
                    for module in carried.runtime_modules()}
        assert names == expected
    # the compiled code's key is every kernel file, whatever a run imports
    keyed = {path.relative_to(carried.PACKAGE.parent).as_posix()
             for path in sources.kernel_files()}
    assert {"herringbone/model/equations.py", "herringbone/compiling/counting.py",
            "herringbone/integrate/compiled/walk.py"} <= keyed
    assert keyed <= names
    assert not {name.split("/")[1] for name in names} & {"analysis", "cli"}
    assert "herringbone/integrate/reference.py" not in names


def test_an_import_names_its_module_and_the_packages_above_it_inside_functions_too():
    # integrate/first_start.py: `from ..compiling import cache` at the top, `from
    # ..model.assembly import GearTrainModel` and `from ..model.scene import load_scene`
    # inside a function (names imported from a module are not modules)
    imported = carried._imported("herringbone.integrate.first_start")
    assert {"herringbone.compiling", "herringbone.compiling.cache",
            "herringbone.model.assembly", "herringbone.model.scene",
            "herringbone", "herringbone.model"} <= imported
    assert not any(name.endswith(("load_scene", "GearTrainModel")) for name in imported)
    assert "herringbone.analysis" not in carried.runtime_modules()


def test_each_slaves_run_imports_its_own_fmi_package_alone():
    """The FMI 3.0 FMU carries pythonfmu3 and the FMI 2.0 one pythonfmu (in their resources):
    what each slave's run imports, inside functions too, names its own package and not the
    other (a host of the FMI 3.0 FMU need not have pythonfmu: docs/fmi3.md)."""
    fmi2 = carried.outside_imports(carried.runtime_modules(["herringbone.fmu.slave"]))
    fmi3 = carried.outside_imports(carried.runtime_modules(["herringbone.fmu.slave3"]))
    assert "pythonfmu" in fmi2 and "pythonfmu3" not in fmi2
    assert "pythonfmu3" in fmi3 and "pythonfmu" not in fmi3
    # the closure follows core.py to the logger; the kernels' imports are numba's and numpy's
    assert "herringbone.fmu.pythonfmu_logger" in carried.runtime_modules(["herringbone.fmu.slave3"])
    assert {"numpy", "numba", "scipy"} <= fmi3


# A host process with the package installed (not editable: its finder, which would find the
# rest of the package on its own, is left out), which had not imported herringbone before the
# FMU: after a run of the FMU, the process uses the package, its modules and its data
INSTALLED_AFTER_AN_FMU = """
import sys
sys.meta_path = [f for f in sys.meta_path if "editable" not in getattr(f, "__module__", "").lower()]
sys.path.append(sys.argv[2])
import fmpy
fmpy.simulate_fmu(sys.argv[1], stop_time=0.001)
import herringbone.fmu.core
try:
    from herringbone.fmu.ssp import build_ssp
    import herringbone.analysis.sweep
    print(herringbone.fmu.core.__file__, herringbone.analysis.sweep.__file__,
          herringbone.load_scene("jump_resonance").source)
except ModuleNotFoundError as error:
    print(error)
"""


def test_a_host_that_ran_an_fmu_uses_the_installed_package_after(built_fmus, tmp_path):
    """The FMU's copy of the package carries only what its run imports, and its files go when
    the host deletes the unpacked FMU: where the installed package is the one the FMU was
    built from, it is the process's herringbone (its modules, its shipped scenes); where it is
    not, a module the copy leaves out is refused with a message naming both and what to do."""
    site = tmp_path / "site"
    shutil.copytree(carried.PACKAGE, site / "herringbone",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(shipped.scenes_folder(), site / "herringbone" / "scenes")
    command = [sys.executable, "-c", INSTALLED_AFTER_AN_FMU, str(built_fmus["reference"]),
               str(site)]
    run = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stdout.split() == [str(site / "herringbone" / "fmu" / "core.py"),
                                  str(site / "herringbone" / "analysis" / "sweep.py"),
                                  str(site / "herringbone" / "scenes" / "jump_resonance.toml")]
    with open(site / "herringbone" / "fmu" / "core.py", "a") as changed:
        changed.write("# another version\n")
    run = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stdout.startswith("No module named 'herringbone.fmu.ssp': this process "
                                 "imported herringbone from an FMU's resources")
    assert "import herringbone before the FMU is loaded" in run.stdout
