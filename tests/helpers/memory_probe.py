"""Running a probe of the compiled loop's memory in a fresh process, with numba's allocation
statistics on (tests/integrate/test_compiled_memory.py, test_kernel_sampling.py).

A probe is a script that takes (scene file, method, output interval) and prints, as its last
line, a JSON record of what numba's runtime allocated and freed and how many references of the
arrays it passed in changed. `probe(setup, body, given)` writes one: `setup` and `body` have a
`stepper` (the method's CompiledStepper of the scene's model), a `run` started at t = 0, the
`interval` and the scene's first `torques`; `body`, the calls measured, must set `before` and
`after` to rtsys's allocation statistics around them and `extra` to a dict of figures of its
own."""
from __future__ import annotations

import json
import os
import subprocess
import sys

from . import MODELS, ROOT

PRELUDE = r"""
import json, sys
import numpy as np
from numba.core.runtime import rtsys
import herringbone
from herringbone.integrate.compiled_stepper import CompiledStepper
from herringbone.integrate.contract import start_position
from herringbone.model.assembly import GearTrainModel

scene = herringbone.load_scene(sys.argv[1])
model = GearTrainModel(scene)
stepper = CompiledStepper(model, 1e-7, sys.argv[2])
run = stepper.start(start_position(model, scene.inputs.at(0.0)[0]))
interval, torques = float(sys.argv[3]), scene.inputs.at(0.0)

def arrays(value):
    if isinstance(value, np.ndarray):
        yield value
    elif isinstance(value, tuple):
        for item in value:
            yield from arrays(item)

def references(given):  # (one way of counting, before and after: a loop's own tuples hold one)
    return [sys.getrefcount(array) for array in given]
"""

REPORT = r"""
print(json.dumps({
    "allocated": after.alloc - before.alloc, "freed": after.free - before.free,
    "records_made": after.mi_alloc - before.mi_alloc,
    "records_freed": after.mi_free - before.mi_free,
    "references_changed": sum(now != then for now, then in zip(references(given), counted)),
    "arrays": len(given), **extra}))
"""


def probe(setup: str, body: str, given: str) -> str:
    """A probe's script: PRELUDE, `setup` (loads the kernels: the first call of what `body`
    measures), the arrays passed in (the stepper's and the run's, and the expression `given`,
    a tuple), their references counted, `body`, and REPORT."""
    return (PRELUDE + setup + "\ngiven = list(arrays((stepper.constants, stepper.exact_buffers, "
            "run.implicit, run.buffers, run.clock, run.place, run.state, run.loaded, "
            f"run.first_steps, run.outputs, tuple(run.workspace), {given})))\n"
            "counted = references(given)\n" + body + REPORT)


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
