"""The gear FMU in a host that is not Python: tests/fmu/c_host/c_host.c, compiled with the
system's C compiler against the FMI headers fmpy ships, run by tests/fmu/c_host/run.sh (the
recipe of docs/hosts.md)."""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest
from helpers.fmu_host import outputs_in_a_process

HOST_FOLDER = Path(__file__).resolve().parent / "c_host"
OUTPUTS = ["F_mesh", "F_brg_pinion_left", "F_brg_wheel_right", "dte"]
STOP, STEP = 0.01, 1e-3
RUNS = 5  # each a process; the stress run (benchmarks/host_lifecycles.py) runs 200
NO_INSTANCE = 3  # c_host's exit status when fmi2Instantiate returns NULL

pytestmark = pytest.mark.skipif(sys.platform != "linux" or not shutil.which("cc"),
                                reason="the C host is built for Linux with the system's cc")


@pytest.fixture(scope="module")
def c_host(tmp_path_factory):
    """The host, compiled as README says."""
    executable = tmp_path_factory.mktemp("c_host") / "c_host"
    headers = Path(fmpy.__file__).parent / "c-code"
    subprocess.run(["cc", "-O2", "-Wall", "-I", str(headers), "-o", str(executable),
                    str(HOST_FOLDER / "c_host.c"), "-ldl"], check=True)
    return executable


@pytest.fixture(scope="module")
def unzipped(scene_fmu, tmp_path_factory):
    """The reference scene's FMU, unzipped, and the value references of OUTPUTS."""
    fmu = scene_fmu("reference")
    folder = Path(fmpy.extract(str(fmu), str(tmp_path_factory.mktemp("unzipped"))))
    description = fmpy.read_model_description(str(fmu))
    references = {v.name: v.valueReference for v in description.modelVariables}
    return fmu, folder, description, [references[name] for name in OUTPUTS]


def run_host(c_host, unzipped, **environment):
    fmu, folder, description, references = unzipped
    command = [str(HOST_FOLDER / "run.sh"), sys.executable, str(c_host), str(folder),
               description.coSimulation.modelIdentifier, description.guid, str(STOP),
               str(STEP), *map(str, references)]
    return subprocess.run(command, capture_output=True, text=True, timeout=120,
                          env={**os.environ, **environment})


def fmpy_outputs(fmu):
    """fmpy's run of the same experiment, in a fresh process (as a host would be)."""
    return outputs_in_a_process(fmu, STOP, STEP, OUTPUTS)


def test_repeated_runs_exit_cleanly_with_fmpys_outputs_bit_for_bit(c_host, unzipped):
    expected = fmpy_outputs(unzipped[0])
    assert expected.shape == (round(STOP / STEP) + 1, 1 + len(OUTPUTS))
    failures = []
    for run_number in range(RUNS):
        run = run_host(c_host, unzipped)
        if run.returncode != 0:
            failures.append((run_number, run.returncode, run.stderr[-2000:]))
            continue
        rows = np.array([[float.fromhex(x) for x in line.split()]
                         for line in run.stdout.splitlines()])
        assert rows.shape == expected.shape
        assert np.array_equal(rows, expected), f"run {run_number}: outputs differ from fmpy's"
    assert failures == [], f"{len(failures)} of {RUNS} runs failed: {failures[:2]}"


def without_active_environment():
    """This process's environment variables less an activated virtual environment: an
    embedded interpreter that is given no program path looks for `python3` on PATH, and from
    an activated environment's bin folder it takes that environment's packages."""
    env = {name: value for name, value in os.environ.items() if name != "VIRTUAL_ENV"}
    own = Path(sys.prefix).resolve()
    env["PATH"] = os.pathsep.join(
        folder for folder in env.get("PATH", "").split(os.pathsep)
        if folder and own not in Path(folder).resolve().parents)
    return env


def test_a_missing_dependency_is_named_and_the_host_lives(c_host, unzipped, tmp_path):
    # README's recipe on an environment without numba: a bare venv of the same interpreter
    # (the embedded interpreter still sees the base installation's own site-packages)
    if subprocess.run([sys._base_executable, "-c", "import numba"],
                      capture_output=True).returncode == 0:
        pytest.skip("the base interpreter has numba: no environment without it to try")
    bare = tmp_path / "bare"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(bare)], check=True)
    fmu, folder, description, references = unzipped
    command = [str(HOST_FOLDER / "run.sh"), str(bare / "bin" / "python"), str(c_host),
               str(folder), description.coSimulation.modelIdentifier, description.guid,
               str(STOP), str(STEP), *map(str, references)]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120,
                         env=without_active_environment())
    assert run.returncode == NO_INSTANCE, run.stderr[-2000:]  # not a crash
    assert re.search(r"herringbone FMU: [a-z, ]*numba cannot be imported by the Python", run.stderr)
    assert "set PYTHONPATH to the site-packages folder" in run.stderr


def test_every_form_of_the_resource_location_is_taken(c_host, unzipped, tmp_path):
    """FMI 2.0 passes the resources folder as a file URI (RFC 3986, RFC 8089), percent-encoded;
    pythonfmu 0.7 alone decodes only %20 and crashed the host on any other escape and on
    file:/path (fmu/resource_path.c). The FMU unpacked under a folder with a letter, a # and a %
    that a URI escapes, each form of its location gives fmpy's outputs."""
    folder = tmp_path / "über #100%"
    shutil.copytree(unzipped[1], folder)
    resources = folder / "resources"
    encoded = resources.as_uri()  # file:///…/%C3%BCber%20%23100%25/resources
    assert "%C3%BC" in encoded and "%23" in encoded and "%25" in encoded
    locations = [encoded, encoded.replace("file:///", "file://localhost/"),
                 encoded.replace("file:///", "file:/"), str(resources)]
    moved = (unzipped[0], folder, *unzipped[2:])
    expected = fmpy_outputs(unzipped[0])
    for location in locations:
        run = run_host(c_host, moved, C_HOST_RESOURCES=location)
        assert run.returncode == 0, f"{location}: {run.returncode} {run.stderr[-2000:]}"
        rows = np.array([[float.fromhex(x) for x in line.split()]
                         for line in run.stdout.splitlines()])
        assert np.array_equal(rows, expected), location
