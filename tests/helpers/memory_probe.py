"""Running a probe of the compiled loop's memory in a fresh process, with numba's allocation
statistics on (tests/integrate/test_compiled_memory.py, test_kernel_sampling.py).

A probe is a script that takes (scene file, method, output interval) and prints, as its last
line, a JSON record of what numba's runtime allocated and freed and how many references of the
arrays it passed in changed."""
from __future__ import annotations

import json
import os
import subprocess
import sys

from . import MODELS, ROOT


def run_probe(probe: str, scene: str, method: str, interval: float) -> dict:
    """The probe's record for models/<scene>.toml, run with `method` and output `interval` (s)
    in a process of its own (NUMBA_NRT_STATS=1, this checkout's package first on the path)."""
    environment = dict(os.environ, NUMBA_NRT_STATS="1",
                       PYTHONPATH=os.pathsep.join([str(ROOT / "fmu_src"),
                                                   os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run([sys.executable, "-c", probe, str(MODELS / f"{scene}.toml"), method,
                           str(interval)], capture_output=True, text=True, env=environment,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def assert_kept(figures: dict) -> None:
    """Every allocation and record freed, and no array passed in with its references changed."""
    assert figures["references_changed"] == 0, figures
    assert figures["allocated"] == figures["freed"], figures
    assert figures["records_made"] == figures["records_freed"], figures
