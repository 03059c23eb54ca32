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

import os

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
    fmu), in the order of points. workers = 0 without a scheduler: here; else on Dask."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 0):
        raise ValueError(f"workers is {workers!r}; allowed: a whole number >= 0 "
                         "(0: no Dask, run here)")
    if scheduler is None and workers == 0:
        results = []
        with progress_bar(len(points), "sweep", progress, unit="point") as bar:
            for point in points:
                results.append(function(shared[0], point, *shared[1:]))
                bar.update()
        return results
    with _dask_client(workers, scheduler, shared[0]) as client:
        return _run_on(client, function, points, shared, progress)


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
            self.cluster = LocalCluster(n_workers=self.workers or os.cpu_count(),
                                        threads_per_worker=1, processes=True,
                                        host="127.0.0.1", dashboard_address=None,
                                        scheduler_kwargs={"dashboard_address": ":0"})
            self.client = Client(self.cluster)
        else:
            self.client = Client(_checked_address(self.scheduler), timeout="20s")
        self.client.submit(load_integrator, self.scene, pure=False).result()
        self.compiled = self.client.run(load_integrator, self.scene)
        return self.client

    def __exit__(self, *exc):
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


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
