"""The FMI 2.0 FMU's own library in front of pythonfmu's (fmu/resource_path.py and .c): an FMU
loads from a folder whose path a URI must escape, where pythonfmu 0.7's library alone crashed
the host in fmi2Instantiate."""
import sys
import zipfile

import fmpy
import numpy as np
import pytest
from helpers.fmu_host import outputs_in_a_process

from herringbone.fmu import resource_path
from herringbone.fmu.pythonfmu_references import PYTHONFMU_LIBRARY_PREFIX

pytestmark = pytest.mark.skipif(sys.platform != "linux" or resource_path.c_compiler() is None,
                                reason="the FMU's library is built for Linux with a C compiler")

STOP, STEP = 0.003, 1e-3


def f_mesh_in_a_process(location) -> np.ndarray:
    """F_mesh of fmpy's run of the FMU or unpacked folder `location`, in a process of its own."""
    return outputs_in_a_process(location, STOP, STEP, ["F_mesh"])[:, 1]


@pytest.mark.parametrize("folder", ["über", "issue#24", "100%", "a%20b c"])
def test_the_fmu_runs_from_a_folder_a_uri_escapes(scene_fmu, tmp_path, folder):
    fmu = scene_fmu("reference")
    unpacked = tmp_path / folder
    fmpy.extract(str(fmu), str(unpacked))
    expected = f_mesh_in_a_process(fmu)
    assert len(expected) == round(STOP / STEP) + 1
    assert np.array_equal(f_mesh_in_a_process(unpacked), expected)


def fake_fmu(path, library=b"pythonfmu's library"):
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("modelDescription.xml", "<fmiModelDescription/>")
        zf.writestr("binaries/linux64/Model.so", library)
    return path


def test_pythonfmus_library_goes_behind_the_fmus_own(tmp_path):
    fmu = fake_fmu(tmp_path / "model.fmu")
    assert resource_path.with_resource_path(fmu) is True
    with zipfile.ZipFile(fmu) as zf:
        entries = {name: zf.read(name) for name in zf.namelist()}
    assert entries[f"binaries/linux64/{PYTHONFMU_LIBRARY_PREFIX}Model.so"] == \
        b"pythonfmu's library"
    own = entries["binaries/linux64/Model.so"]
    assert own.startswith(b"\x7fELF") and b"fmi2Instantiate" in own
    assert f"{PYTHONFMU_LIBRARY_PREFIX}Model.so".encode() in own  # the library it opens


def test_without_a_c_compiler_the_fmu_stays_and_a_warning_says_what_that_leaves(tmp_path,
                                                                              monkeypatch):
    fmu = fake_fmu(tmp_path / "model.fmu")
    before = fmu.read_bytes()
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    with pytest.warns(resource_path.ResourcePathWarning,
                      match=r"no C compiler .* crashes in fmi2Instantiate; install a C compiler"):
        assert resource_path.with_resource_path(fmu) is False
    assert fmu.read_bytes() == before
