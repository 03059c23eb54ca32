"""The shipped examples as a user runs them without an optional dependency: the libcosim
co-simulation of the drive train (examples/cosimulate_drivetrain.py) without the `cosim` extra.
Its runs with libcosimpy are tests/fmu/test_ssp.py's."""
import subprocess
import sys

import pytest
from helpers import MODELS

EXAMPLE = MODELS.parent / "examples" / "cosimulate_drivetrain.py"

# The example in a Python without libcosimpy (None in sys.modules: importlib finds no spec and
# an import fails, as where it is not installed), run as `python -m MODULE ARGS` or, for a
# file, as `python FILE ARGS` runs it (its folder first on sys.path)
WITHOUT_LIBCOSIMPY = """
import os, runpy, sys
sys.modules["libcosimpy"] = None
target, sys.argv = sys.argv[1], sys.argv[1:]
if target.endswith(".py"):
    sys.path.insert(0, os.path.dirname(target))
    runpy.run_path(target, run_name="__main__")
else:
    runpy.run_module(target, run_name="__main__", alter_sys=True)
"""


@pytest.mark.parametrize("command", [
    pytest.param(["herringbone.examples.cosimulate_drivetrain"], id="module-builds-the-ssp"),
    pytest.param([str(EXAMPLE), "absent.ssp"], id="checkout-file-given-an-ssp")])
def test_the_cosimulation_without_libcosimpy_says_what_to_install_before_any_build(tmp_path,
                                                                                    command):
    """Without libcosimpy the example says in one line that the co-simulation needs it and how
    to install it (herringbone.optional's words), exit code 2, before it builds
    dist/drivetrain.ssp or reads the SSP it was given (it built the SSP, then stopped with a
    ModuleNotFoundError traceback, exit code 1)."""
    run = subprocess.run([sys.executable, "-c", WITHOUT_LIBCOSIMPY, *command], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2, f"exit {run.returncode}:\n{run.stdout}\n{run.stderr[-3000:]}"
    assert run.stdout == "" and run.stderr.count("\n") == 1, run.stderr[-3000:]
    assert run.stderr.startswith("cosimulate_drivetrain.py: the co-simulation needs "
                                 "libcosimpy, which is not installed: pip install libcosimpy "
                                 "(or every dependency of the 'cosim' extra: pip install "
                                 "\".[cosim]\""), run.stderr
    assert not (tmp_path / "dist").exists()  # nothing built
