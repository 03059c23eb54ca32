"""The integrator's first start on a machine: compiled code carried in, a word before compiling.

numba compiles the integrator's loop (compiled/walk.py) once per machine, numba version and
version of the package, and caches it (compiling/cache.py). An FMU carries the compiled code
a run of its scene loads (`carry_for_scene`, in resources/numba_cache: `CARRIED_FOLDER`);
`prepare`, called as the slave is instantiated, adds to the user's cache folder what that
lacks of it (cache.seed_from), so an FMU started on a machine of the build machine's kind
loads its code in a fraction of a second.

Where numba must compile anyway (another CPU, another numba, no carried cache), `announce_compiles`
says so before it starts, with the reason and the time it will take (`estimate_seconds`), and
again when done; every compile's time is recorded beside the cache (`RECORD`) for the next
estimate.

The messages go through whatever `say` the caller hands over: the FMU's is a line straight to
its host's logger (fmu/pythonfmu_logger.py, HostLine), so that the host shows them while it
waits rather than when the FMI call returns.
"""
from __future__ import annotations

import json
import logging
import shutil
import sys
import threading
import time
from pathlib import Path

from numba.core import event

from ..compiling import cache, sources

CARRIED_FOLDER = "numba_cache"  # in an FMU's resources: a kernels-<digest> of the build machine's
RECORD = "compile_seconds.json"  # in a kernels folder: {kernel: {"seconds": s, "cpu": name}}
# Compile time of the whole integrator announced when nothing is recorded: what it takes with
# every cache empty on this project's 2-core machine (measured: docs/integrator.md)
DEFAULT_COMPILE_SECONDS = 90.0


def prepare(resources, say) -> None:
    """Called once as an FMU's slave is instantiated, before anything is compiled: adds the
    compiled code the FMU carries (in its `resources` folder, None where it has none) to the
    user's cache folder where that lacks it (cache.seed_from), and makes any compile that
    remains announce itself first, through `say(message, level)` (level a `logging` level:
    the FMU maps it to the host's status)."""
    carried = Path(resources) / CARRIED_FOLDER if resources else None
    if carried is not None and carried.is_dir():
        try:
            cache.seed_from(carried)
        except OSError as error:
            say(f"cannot copy the compiled integrator the FMU carries into "
                f"{cache.kernels_folder()} ({error}); it will be compiled instead. Set "
                "HERRINGBONE_CACHE_DIR to a writable folder to keep it", logging.WARNING)
    announce_compiles(say)


def estimate_seconds() -> float:
    """The compile time to expect for the integrator: the sum of its kernels' times last
    recorded for this version of the package (here or on the build machine), else the
    default."""
    seconds = [record.get("seconds") for record in _records().values()
               if isinstance(record, dict)]
    if _Announcer.LOOP not in _records() or not all(isinstance(s, (int, float)) for s in seconds):
        return DEFAULT_COMPILE_SECONDS
    return float(sum(s for s in seconds if isinstance(s, (int, float))))


def record_seconds(kernel: str, seconds: float) -> None:
    """Keep a kernel's compile time beside the cache, for the next estimate (best effort)."""
    records = _records()
    records[kernel] = {"seconds": round(seconds, 1), "cpu": _cpu_name()}
    try:
        cache.kernels_folder().mkdir(parents=True, exist_ok=True)
        (cache.kernels_folder() / RECORD).write_text(json.dumps(records, indent=1))
    except OSError:
        pass


def _records() -> dict:
    try:
        records = json.loads((cache.kernels_folder() / RECORD).read_text())
        return records if isinstance(records, dict) else {}
    except (OSError, ValueError):
        return {}


def _cpu_name() -> str:
    from numba.core.registry import cpu_target

    return cpu_target.target_context.codegen().magic_tuple()[1]


class _Announcer(event.Listener):
    """Says, before numba compiles this package's kernels (those called from Python: the loop
    `advance`, last, and a few small ones before it), why and for how long, once, and when
    the loop is done. One per process; `say` is swapped for the newest caller's."""

    LOOP = "advance"
    SAMPLED_LOOP = "advance_sampled"  # walk's other entry, herringbone.simulate's: the loop in it

    def __init__(self, say):
        self.say, self.depth, self.started, self.kernel_started = say, 0, None, None

    def on_start(self, ev):
        """numba begins to compile a kernel: the first of this package's announces it."""
        self.depth += 1
        dispatcher = ev.data["dispatcher"]
        if self.depth > 1 or dispatcher.py_func.__module__ not in _KERNEL_MODULES:
            return
        self.kernel_started = time.perf_counter()
        if self.started is None:
            self.started = self.kernel_started
            reason = cache.why_not_cached(dispatcher, tuple(ev.data["args"]))
            self.say(f"compiling the integrator for this machine ({reason}): about "
                     f"{estimate_seconds():.0f} s, once; later starts load it from "
                     f"{cache.kernels_folder()}")

    def on_end(self, ev):
        """numba is done with a kernel: record its time; the loop's end is announced."""
        self.depth -= 1
        kernel = ev.data["dispatcher"].py_func.__name__
        if self.depth > 0 or self.kernel_started is None:
            return
        record_seconds(kernel, time.perf_counter() - self.kernel_started)
        self.kernel_started = None
        if kernel in (self.LOOP, self.SAMPLED_LOOP) and self.started is not None:
            seconds, self.started = time.perf_counter() - self.started, None
            self.say(f"compiled the integrator in {seconds:.1f} s; cached in "
                     f"{cache.kernels_folder()}")


_KERNEL_MODULES = frozenset(sources.kernel_modules())
_announcer = None
_announcer_lock = threading.Lock()


def announce_compiles(say) -> None:
    """From now on, `say(message)` before and after numba compiles a kernel of this package."""
    global _announcer
    with _announcer_lock:
        if _announcer is None:
            _announcer = _Announcer(say)
            event.register("numba:compile", _announcer)
        _announcer.say = say


def compile_for_scene(scene_path, say=print, progress_every=10.0) -> float | None:
    """Load or compile the integrator as an FMU of the scene will run it at its default
    settings (the method "auto" picks for the scene), in this process, saying before a compile
    what it will cost and how far it is every `progress_every` seconds. Returns the seconds
    spent compiling, None if everything came from the cache."""
    from ..model.assembly import GearTrainModel
    from ..model.scene import load_scene
    from .compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper, warm_up
    from .contract import start_position

    scene = load_scene(scene_path)
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, DEFAULT_TOLERANCE)
    position = start_position(model, scene.inputs.at(0.0)[0])
    done, compiled = threading.Event(), []

    def tell(message):
        if message.startswith("compiling"):
            compiled.append(time.perf_counter())
            threading.Thread(target=_progress, args=(done, progress_every, say),
                             daemon=True).start()
        say(message)

    announce_compiles(tell)
    try:
        warm_up(stepper, position)
        run = stepper.start(position)
        stepper.run_to(run, position.time + 1e-6, scene.inputs.at(0.0))
    finally:
        done.set()
        announce_compiles(lambda message: print(message, file=sys.stderr))
    return time.perf_counter() - compiled[0] if compiled else None


def _progress(done, every, say):
    started = time.perf_counter()
    while not done.wait(every):
        say(f"  ... {time.perf_counter() - started:.0f} s of about {estimate_seconds():.0f} s")


def carry_for_scene(scene_path, folder) -> list[str]:
    """What an FMU of the scene carries, put into `folder` (its resources/CARRIED_FOLDER): the
    compiled code compile_for_scene loads or compiles, as cache.carry_loaded copies it, and the
    compile times recorded beside it (RECORD). Only what this process has loaded is carried,
    so the builder runs this in a fresh one. Returns the index files written."""
    compile_for_scene(scene_path, say=lambda message: print(message, flush=True))
    written = cache.carry_loaded(Path(folder))
    if (cache.kernels_folder() / RECORD).is_file():
        shutil.copyfile(cache.kernels_folder() / RECORD,
                        Path(folder) / cache.kernels_folder().name / RECORD)
    return written


# python -m herringbone.integrate.first_start SCENE [FOLDER]: what the builder runs, in a fresh
# process (carry_for_scene into FOLDER)
if __name__ == "__main__":
    if len(sys.argv) > 2:
        carry_for_scene(sys.argv[1], sys.argv[2])
    else:
        compile_for_scene(sys.argv[1], say=lambda message: print(message, flush=True))
