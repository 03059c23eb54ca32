"""A word before numba compiles kernels of this package, while it does, and after.

numba says nothing while it compiles, and the integrator's loop takes minutes on two cores
(docs/integrator.md, First start). So every compile of this package's kernels is announced, by
a listener of numba's compile events that counting.py puts in place before the first kernel
is defined: a line as the first starts, with what is compiled and why (cache.why_not_cached);
a line every `every` seconds while compiles go on, naming the kernel being compiled and how
long its last compile took, where that is recorded (RECORD, beside the cache: the FMU carries
the build machine's); and a line when they are done, with the time. Compiles that follow one
another (the model's kernels, then the loop) are one announcement: it ends as the loop's
compile does, or QUIET_SECONDS after the last one.

The lines go to stderr unless a caller hands over its own `say` (announce_compiles): the FMU
its host's logger (integrate/first_start.py), the builder stdout.
"""
from __future__ import annotations

import atexit
import json
import sys
import threading
import time
from pathlib import Path

from numba.core import event

from . import cache, sources

RECORD = "compile_seconds.json"  # in a kernels folder: {kernel: {"seconds": s, "cpu": name}}
PROGRESS_SECONDS = 10.0  # between the lines said while compiles go on, by default
# an announcement ends this long after a compile where no other has started (s): the next
# kernel a run compiles follows within milliseconds
QUIET_SECONDS = 1.0
LOOP = "walk.advance"  # the integrator's loop: last to compile
_KERNEL_MODULES = frozenset(sources.kernel_modules())


def announce_compiles(say=None, every: float | None = PROGRESS_SECONDS) -> None:
    """From now on, `say(message)` before, while (every `every` seconds; None: never) and
    after numba compiles kernels of this package; `say` None: a line on stderr, as from the
    start (install)."""
    with _lock:
        _announcer.say = say or _on_stderr
        _announcer.every = every


def install() -> None:
    """Listen to numba's compiles (once per process), saying on stderr until a caller says
    otherwise (announce_compiles); a process that ends within QUIET_SECONDS of its last
    compile says that compile's end as it exits."""
    global _registered
    with _lock:
        if not _registered:
            event.register("numba:compile", _announcer)
            atexit.register(_announcer.at_exit)
            _registered = True


def finish() -> None:
    """Say now the end of an announcement whose compiles are done, which would come
    QUIET_SECONDS later or as the process exits: a command calls it before its last line
    (an interrupt's, an error's), which then stays last."""
    _announcer.at_exit()


def _on_stderr(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def record_seconds(kernel: str, seconds: float) -> None:
    """Keep a kernel's compile time beside the cache, for the next announcement (best
    effort)."""
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


def last_compile(kernel: str) -> tuple[float, str] | None:
    """How long `kernel`'s last recorded compile took (s), and on which CPU where that is not
    this one (", on a znver4"); None where none is recorded."""
    record = _records().get(kernel)
    if not isinstance(record, dict) or not isinstance(record.get("seconds"), (int, float)):
        return None
    cpu = record.get("cpu")
    return record["seconds"], (f", on a {cpu}" if isinstance(cpu, str) and cpu != _cpu_name()
                               else "")


def _cpu_name() -> str:
    from numba.core.registry import cpu_target

    return cpu_target.target_context.codegen().magic_tuple()[1]


def _name(dispatcher) -> str:
    """A kernel as its cache files are named: module.function (walk.advance)."""
    return f"{dispatcher.py_func.__module__.rpartition('.')[2]}.{dispatcher.py_func.__qualname__}"


class _Session:
    """One announcement: the compiles from the first to the last that follows it."""

    def __init__(self, folder, say, every):
        self.started = self.last_end = time.perf_counter()
        self.folder = folder  # where the kernels' code goes
        self.say, self.every = say, every  # as announce_compiles set them when it began
        self.kernel: str | None = None  # being compiled, None between two
        self.kernel_started = self.started
        self.took: dict[str, float] = {}  # s, by kernel
        self.ended = threading.Event()


class _Announcer(event.Listener):
    """Says when numba compiles kernels of this package (those called from Python: numba
    compiles what they call into them): the first's start, progress from a thread of the
    session's, the end. One per process; announce_compiles swaps `say` and `every`."""

    def __init__(self):
        self.say, self.every = _on_stderr, PROGRESS_SECONDS
        self.depth = 0
        self.session: _Session | None = None
        self.warned = False  # of a cache folder that cannot be written

    def on_start(self, ev):
        """numba begins to compile a kernel: the first of a session announces it."""
        self.depth += 1
        dispatcher = ev.data["dispatcher"]
        if self.depth > 1 or dispatcher.py_func.__module__ not in _KERNEL_MODULES:
            return
        with _lock:
            opening = self.session is None
            if opening:
                self.session = _Session(Path(dispatcher._cache._cache_path), self.say,
                                        self.every)
            session = self.session
            session.kernel, session.kernel_started = _name(dispatcher), time.perf_counter()
        if opening:
            self._open(session, dispatcher, tuple(ev.data["args"]))
            threading.Thread(target=self._watch, args=(session,), daemon=True).start()

    def _open(self, session, dispatcher, signature):
        """Say why `session` compiles, before it does (where the code goes first, where that is
        not the cache folder)."""
        say, stand_in = session.say, cache.not_kept(session.folder)
        if stand_in is not None and not self.warned:
            self.warned = True
            say(f"cannot write in the cache folder {stand_in[0]} ({stand_in[1]}): this process "
                "compiles what that lacks into a temporary folder, removed when it ends, and "
                "so will every later start; set HERRINGBONE_CACHE_DIR to a folder you can "
                "write in to keep the compiled code")
        reason = cache.why_not_cached(dispatcher, signature)
        say(f"compiling kernels of herringbone for this machine, {session.kernel} first "
            f"({reason}): seconds for most, minutes for the integrator's loop; "
            f"{_kept_where(session.folder, 'them')}")

    def on_end(self, ev):
        """numba is done with a kernel: record its time; the loop's end ends the session."""
        self.depth -= 1
        dispatcher = ev.data["dispatcher"]
        if self.depth > 0 or dispatcher.py_func.__module__ not in _KERNEL_MODULES:
            return
        kernel, now = _name(dispatcher), time.perf_counter()
        with _lock:
            session = self.session
            if session is None:
                return
            session.took[kernel] = now - session.kernel_started
            session.kernel, session.last_end = None, now
        if tuple(ev.data["args"]) in dispatcher.overloads:  # compiled, not failed
            record_seconds(kernel, session.took[kernel])
        if kernel == LOOP:
            self._close(session)

    def _close(self, session, quiet=False):
        """Say the end of `session`, once (from the compiling thread or, `quiet`, from its own
        where no compile has begun since it looked)."""
        with _lock:
            if self.session is not session or (quiet and session.kernel is not None):
                return
            self.session, say = None, session.say
            session.ended.set()
        seconds = session.last_end - session.started
        if len(session.took) == 1:
            [kernel] = session.took
            say(f"compiled {kernel} in {seconds:.1f} s; {_kept_where(session.folder, 'it')}")
            return
        longest = max(session.took, key=session.took.__getitem__)
        say(f"compiled {len(session.took)} kernels in {seconds:.1f} s ({longest} "
            f"{session.took[longest]:.1f} s); {_kept_where(session.folder, 'them')}")

    def at_exit(self):
        """Say the end of a session whose compiles are done, the process ending before its
        watch did."""
        session = self.session
        if session is not None:
            self._close(session, quiet=True)

    def _watch(self, session):
        """While `session` lasts: a line every `every` seconds, and its end after
        QUIET_SECONDS without a compile."""
        said = 0
        while not session.ended.wait(min(0.25, session.every or 0.25)):
            with _lock:
                now, kernel, every = time.perf_counter(), session.kernel, session.every
                quiet = kernel is None and now - session.last_end >= QUIET_SECONDS
                due = kernel is not None and every and now - session.started >= (said + 1) * every
            if quiet:
                self._close(session, quiet=True)
            elif due:
                said = int((now - session.started) // every)
                session.say(_progress(now - session.started, kernel,
                                      now - session.kernel_started))


def _progress(seconds: float, kernel: str, on_kernel: float) -> str:
    """The line said `seconds` into a session, `on_kernel` into compiling `kernel`."""
    last = last_compile(kernel)
    if last is None:
        return f"  ... {seconds:.0f} s: compiling {kernel}"
    return (f"  ... {seconds:.0f} s: compiling {kernel}, {on_kernel:.0f} s of about "
            f"{last[0]:.0f} s (its last compile{last[1]})")


def _kept_where(folder, code: str) -> str:
    """Where later starts find the code compiled into `folder`, as said in a line."""
    if cache.not_kept(folder) is not None:
        return f"not kept: this process holds {code} in {folder} until it ends"
    return f"later starts load {code} from {folder}"


_lock = threading.RLock()
_announcer = _Announcer()
_registered = False
