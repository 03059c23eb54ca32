"""Every lifecycle a host puts the gear FMU through ends in a clean exit of the host's process.

benchmarks/host_lifecycles.py holds the cases (one instance, several at once, two scenes at once,
re-instantiation, reloading the library, another thread, a Fatal call, logging, the FMI 3.0 FMU,
libcosim, the C host); each case checks its own results and must exit 0. Here every case runs
RUNS fresh processes, two at a time: a bounded sample on every push. The stress run of the same
cases (hundreds of processes each) is `python benchmarks/host_lifecycles.py --runs 200`.
"""
import shutil
import sys
from pathlib import Path

import pytest
from helpers import benchmark_module

RUNS = 3
lifecycles = benchmark_module("host_lifecycles")


@pytest.fixture(scope="module")
def lifecycle_fmus(built_fmus, tmp_path_factory):
    """The FMUs the cases load, the FMI 2.0 ones shared with the other tests."""
    from herringbone.fmu import builder

    folder = tmp_path_factory.mktemp("lifecycles")
    fmi3 = builder.build_gear_fmu(Path(lifecycles.ROOT / "models" / "reference.toml"),
                                  folder / "reference_fmi3.fmu", fmi_version=3)
    fmus = {"reference": str(built_fmus["reference"]), "torsional": str(built_fmus["torsional"]),
            "reference_fmi3": str(fmi3)}
    return fmus, folder


@pytest.mark.parametrize("case", lifecycles.ALL_CASES)
def test_every_process_of_the_lifecycle_exits_cleanly(case, lifecycle_fmus):
    if case == lifecycles.C_CASE and (sys.platform != "linux" or not shutil.which("cc")):
        pytest.skip("the C host is built for Linux with the system's cc")
    fmus, folder = lifecycle_fmus
    failed = lifecycles.run_case(case, fmus, folder, runs=RUNS, parallel=2)
    assert not failed, (f"{len(failed)} of {RUNS} processes failed; the first: exit "
                        f"{failed[0].returncode}\n{failed[0].stderr[-3000:]}")
