"""Running the points of a sweep: here one after the other, on a Dask LocalCluster, or on an
existing Dask cluster, with a progress bar (tqdm: points done, rate, time left).

The results are the same wherever a point runs: every point is a pure function of the scene,
the point and the protocol, and each process runs the same compiled code single-threaded
(BLAS threads are set to one before workers start: small matrices only, and thread counts
must not change rounding between a serial and a parallel run).

Workers load the compiled integrator from the numba cache (compiling/cache.py) rather than each
compiling it: the integrator is made ready here first (compiled into the cache if it is not
there), then every worker loads it once before the points are handed out. On a cluster whose
machines do not share this machine's cache, one worker compiles first and the rest of that
machine's workers load what it wrote.
"""
from __future__ import annotations

import ast
import contextlib
import logging
import os
import signal
import sys
import threading
import types
from pathlib import Path

from ..optional import require
from .progress_bar import progress_bar

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def load_integrator(scene) -> bool:
    """Make the compiled integrator ready in this process; True if it had to be compiled
    (not in the cache), False if it was loaded."""
    from ..integrate.compiled_stepper import CompiledStepper, warm_up
    from ..integrate.contract import start_position
    from ..model.assembly import GearTrainModel

    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, 1e-7)
    return warm_up(stepper, start_position(model, scene.inputs.at(0.0)[0])) is not None


def map_points(function, points, shared, workers=None, scheduler=None, progress=True):
    """[function(scene, point, protocol, fmu) for point in points], shared = (scene, protocol,
    fmu), in the order of points. workers = 0 without a scheduler: here; else on Dask.
    `workers` and `scheduler` as sweep.check_options checked them."""
    if scheduler is None and workers == 0:
        results = []
        with progress_bar(len(points), "sweep", progress, unit="point") as bar:
            for point in points:
                results.append(function(shared[0], point, *shared[1:]))
                bar.update()
        return results
    if scheduler is None:
        check_workers_can_start(workers)
    with _dask_client(workers, scheduler, shared[0]) as client:
        return _run_on(client, function, points, shared, progress)


def check_workers_can_start(workers) -> None:
    """Before a LocalCluster starts: RuntimeError, one message saying what to do, where its
    worker processes could not start. Dask starts them as multiprocessing's spawn does, each
    importing the main script again (as __mp_main__, where `__name__ == "__main__"` is
    false): a script that starts the sweep from its top level outside such a guard would start
    it again in every worker, and a script read from stdin cannot be imported. Both ended in
    seconds of tracebacks from every worker and "Nanny failed to start"."""
    script = main_script()
    if script is None:
        return
    what = f"a sweep on {local_workers(workers)} worker processes"
    also = "or workers=0 (the points here, one after the other)"
    if not script.is_file():
        raise RuntimeError(f"{what}: the main script {script} is no file that the workers "
                           f"can import (each imports it as it starts); allowed: a script "
                           f"file, {also}")
    line = top_level_line()
    if line is not None and not guarded(script, line):
        raise RuntimeError(f"{what}: {script} starts it from its top level (line {line}), "
                           f"which every worker would run again as it starts (each imports "
                           f"the main script); allowed: that line under "
                           f"`if __name__ == \"__main__\":`, {also}")


def local_workers(workers) -> int:
    """How many worker processes a LocalCluster of `workers` starts: None, one per core."""
    return workers or os.cpu_count() or 1


def main_script() -> Path | None:
    """The file that multiprocessing's spawn runs again in a new process, as it decides
    (spawn.get_preparation_data, _fixup_main_from_name and _from_path): the main module's,
    none for a package's __main__, an interactive session or IPython."""
    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    if spec is not None and spec.name is not None:
        runs_again = spec.name != "__main__" and not spec.name.endswith(".__main__")
        return Path(spec.origin) if runs_again and spec.origin else None
    path = getattr(main, "__file__", None)
    if path is None or Path(path).stem == "ipython":
        return None
    return Path(os.path.abspath(path))


def top_level_line() -> int | None:
    """The line of the main module's top level that is running now (that led to this call),
    or None where the main module is not running (an interactive session)."""
    main, line = vars(sys.modules["__main__"]), None
    frame: types.FrameType | None = sys._getframe(1)
    while frame is not None:
        if frame.f_code.co_name == "<module>" and frame.f_globals is main:
            line = frame.f_lineno
        frame = frame.f_back
    return line


def guarded(script: Path, line: int) -> bool:
    """Whether `line` of `script` lies inside an `if` that tests `__name__` (the guard
    `if __name__ == "__main__":` and its variants), which a worker's import skips; True
    also where the script cannot be read, which is no reason to refuse the sweep."""
    try:
        tree = ast.parse(script.read_text(encoding="utf-8"))
    except (OSError, SyntaxError, UnicodeDecodeError, ValueError):
        return True
    return any(isinstance(node, ast.If) and node.lineno <= line <= (node.end_lineno or 0)
               and any(isinstance(name, ast.Name) and name.id == "__name__"
                       for name in ast.walk(node.test))
               for node in ast.walk(tree))


class _dask_client:
    """A Client of the given scheduler, or of a LocalCluster of `workers` processes on
    127.0.0.1 (None: one per core), closed on exit, with the integrator loaded on every
    worker."""

    def __init__(self, workers, scheduler, scene):
        self.workers, self.scheduler, self.scene = workers, scheduler, scene
        self.cluster = None

    def __enter__(self):
        distributed = require("dask.distributed", "a sweep on Dask (or give workers=0)")
        Client, LocalCluster = distributed.Client, distributed.LocalCluster

        if self.scheduler is None:
            load_integrator(self.scene)  # fills the cache that the workers then load from
            for name in THREAD_VARIABLES:
                os.environ.setdefault(name, "1")
            # no dashboard; the scheduler's own HTTP routes (health, metrics) on a free port,
            # not on 8787, which another cluster on the machine may hold (Dask then warns)
            with interrupts_ignored():
                self.cluster = LocalCluster(n_workers=local_workers(self.workers),
                                            threads_per_worker=1, processes=True,
                                            host="127.0.0.1", dashboard_address=None,
                                            scheduler_kwargs={"dashboard_address": ":0"})
            self.client = Client(self.cluster)
        else:
            self.client = Client(_checked_address(self.scheduler), timeout="20s")
        self.client.submit(load_integrator, self.scene, pure=False).result()
        self.compiled = self.client.run(load_integrator, self.scene)
        return self.client

    def __exit__(self, kind, error, trace):
        if self.cluster is not None and kind is not None:
            # the points running are cancelled as their workers close, which each worker
            # would log as a warning after the command's own message; a worker gone (the
            # error may be that) has nothing to say, and what ends the sweep is the error
            with contextlib.suppress(Exception):
                self.client.run(quiet_cancellations, on_error="ignore")
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def quiet_cancellations() -> None:
    """On a worker of the sweep's own cluster, closing after an error or an interrupt: its
    tasks' cancellation, which Dask logs as a warning, is what the command asked for; and a
    heartbeat that meets the scheduler already closed, which the worker logs as an error with
    a page of traceback (seen once, in CI, in the test of Ctrl-C on a sweep on two workers), is
    that closing too."""
    logging.getLogger("distributed.worker.state_machine").setLevel(logging.ERROR)
    logging.getLogger("distributed.worker").setLevel(logging.CRITICAL)


@contextlib.contextmanager
def interrupts_ignored():
    """SIGINT ignored here while the LocalCluster starts its processes, which inherit that
    (an ignored signal stays ignored across exec, and Python, asyncio and Dask then install no
    handler of their own): Ctrl-C at a terminal signals every process of its group, and the
    sweep then stops here (the cluster closed, the command's one line) instead of in every
    worker, each with a page of traceback. Nothing where this is not the main thread, which
    alone may set a handler, nor where the handler was not set from Python (an embedding
    program's), which could not be put back."""
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or previous is None:
        yield
        return
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _checked_address(address: str) -> str:
    if not isinstance(address, str) or "://" not in address:
        raise ValueError(f"scheduler is {address!r}; allowed: a Dask scheduler address "
                         "PROTOCOL://HOST:PORT, e.g. tcp://127.0.0.1:8786")
    return address


def _run_on(client, function, points, shared, progress):
    from dask.distributed import as_completed

    scene, *rest = shared
    futures = client.map(function, [scene] * len(points), points,
                         *([value] * len(points) for value in rest), pure=False)
    with progress_bar(len(points), "sweep", progress, unit="point") as bar:
        for _ in as_completed(futures):
            bar.update()
    return client.gather(futures)
