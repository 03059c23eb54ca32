"""The integrator's first start on a machine: compiled code carried in, a word before compiling.

numba compiles the integrator's loop (compiled/walk.py's `advance`, which the FMU, the sweeps,
herringbone.simulate and `herringbone run` all step with) for each method on its first use on a
machine, numba version and version of the package, and caches it (compiling/cache.py). An FMU
carries the compiled code a run of its scene loads (`carry_for_scene`, in
resources/numba_cache: `CARRIED_FOLDER`); `prepare`, called as the slave is instantiated, adds
to the user's cache folder what that lacks of it (cache.seed_from), so an FMU started on a
machine of the build machine's kind loads its code in a fraction of a second.

Where numba must compile anyway (another CPU, another numba, no carried cache), the compile
is announced (compiling/announce.py: on stderr unless a caller hands over its own `say`) before
it starts, with the reason, and again when done; every compile's time is recorded beside the
cache (`RECORD`) for the next announcement.

The FMU's `say` is a line straight to its host's logger (fmu/pythonfmu_logger.py, HostLine),
so that the host shows the messages while it waits rather than when the FMI call returns.
"""
from __future__ import annotations

import logging
import shutil
import sys
import time
from pathlib import Path

from ..compiling import cache
from ..compiling.announce import RECORD, announce_compiles

CARRIED_FOLDER = "numba_cache"  # in an FMU's resources: a kernels-<digest> of the build machine's


def prepare(resources, say) -> None:
    """Called once as an FMU's slave is instantiated, before anything is compiled: adds the
    compiled code the FMU carries (in its `resources` folder, None where it has none) to the
    user's cache folder where that lacks it (cache.seed_from; where that folder cannot be
    written, to the temporary one that stands in for it in this process), and makes any
    compile that remains announce itself first, through `say(message, level)` (level a
    `logging` level: the FMU maps it to the host's status). Its progress lines come from
    another thread: HostLine writes them to stderr at once, and the host's log has them
    after the FMI call."""
    carried = Path(resources) / CARRIED_FOLDER if resources else None
    if carried is not None and carried.is_dir():
        try:
            cache.seed_from(carried)
        except OSError as error:
            say(f"cannot copy the compiled integrator the FMU carries into "
                f"{cache.kernels_folder()} ({error}); it will be compiled instead. Set "
                "HERRINGBONE_CACHE_DIR to a writable folder to keep it", logging.WARNING)
    announce_compiles(say)


def compile_for_scene(scene_path, say=print, progress_every=10.0) -> float | None:
    """Load or compile the integrator as an FMU of the scene will run it at its default
    settings (the method "auto" picks for the scene), in this process, saying before a compile
    why, how far it is every `progress_every` seconds, and when it is done
    (announce_compiles). Returns the seconds spent compiling, None if everything came from the
    cache."""
    from ..model.assembly import GearTrainModel
    from ..model.scene import load_scene
    from .compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper, warm_up
    from .contract import start_position

    scene = load_scene(scene_path)
    model = GearTrainModel(scene)
    stepper = CompiledStepper(model, DEFAULT_TOLERANCE)
    position = start_position(model, scene.inputs.at(0.0)[0])
    compiled = []

    def tell(message):
        if message.startswith("compiling"):
            compiled.append(time.perf_counter())
        say(message)

    announce_compiles(tell, every=progress_every)
    try:
        warm_up(stepper, position)
        run = stepper.start(position)
        stepper.run_to(run, position.time + 1e-6, scene.inputs.at(0.0))
    finally:
        announce_compiles()  # on stderr again
    return time.perf_counter() - compiled[0] if compiled else None


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
