"""Where numba caches the compiled kernels of this package.

numba's own locators put the cache beside the source (`__pycache__`) or in a folder named after
the source's path. An FMU is unpacked to a fresh temporary folder for every instance, so either
way each start would compile again (a minute). This locator keys the cache on the source text
of every file that holds kernels or says how they are compiled (sources.py: numba alone
would miss a change to a kernel that another file's kernel compiled in), in a per-user
folder: $HERRINGBONE_CACHE_DIR, else $XDG_CACHE_HOME/herringbone/numba, else
~/.cache/herringbone/numba (cache_root). numba itself keeps apart the Python and numba versions
and the CPU. Each version of the package adds a folder there (a few MB); deleting the folder is
always safe.

Where that folder cannot be written, a temporary folder of the process stands in for it
(kernels_folder): declined, numba's own locators would write the kernels beside the installed
package, where `pip uninstall` leaves them. An index or code file there that numba cannot read
(truncated, overwritten) reads as absent, so the kernel is compiled again and the file written
over (_SparingIndexFile): numba's own reader raises, and every later start failed on it.
"""
from __future__ import annotations

import atexit
import functools
import hashlib
import io
import os
import pickle
import secrets
import shutil
import sys
import tempfile
from pathlib import Path

from numba.core import caching, serialize, types

from . import sources

# The data files of seeded entries are numbered from here (_merge_index), far above numba's
SEEDED_NUMBERS = 1 << 64


@functools.cache
def package_digest() -> str:
    """The hash of every kernel source file (sources.kernel_files), by its path in the
    package, and of the package's module name: numba's index pickles objects by their
    modules' names, so a copy of the same files under another name (the package moved)
    cannot read it and needs its own."""
    digest = hashlib.sha256(sources.package_name().encode() + b"\0")
    for source in sources.kernel_files():
        digest.update(source.relative_to(sources.ROOT).as_posix().encode() + b"\0"
                      + source.read_bytes())
    return digest.hexdigest()[:20]


def cache_root() -> Path:
    """The per-user folder that holds a kernels-<digest> folder per version of the package:
    $HERRINGBONE_CACHE_DIR (`~` expanded: an env file or a systemd unit does not), else
    $XDG_CACHE_HOME/herringbone/numba where that is an absolute path (the XDG spec says to
    ignore a relative one: each working folder would get its own cache), else
    .cache/herringbone/numba in the user's home (_home)."""
    if os.environ.get("HERRINGBONE_CACHE_DIR"):
        return Path(os.environ["HERRINGBONE_CACHE_DIR"]).expanduser().absolute()
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    base = Path(xdg) if os.path.isabs(xdg) else _home() / ".cache"
    return base / "herringbone" / "numba"


def _home() -> Path:
    """$HOME where it is an absolute path, else the account's home (an empty HOME put the
    cache in /.cache)."""
    home = os.environ.get("HOME", "")
    if os.path.isabs(home):
        return Path(home)
    try:
        import pwd

        return Path(pwd.getpwuid(os.getuid()).pw_dir)
    except (ImportError, KeyError):  # not a POSIX system, or an account without an entry
        return Path.home()


class SourceTextCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """Caches the kernels of this package by the hash of their source text."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = str(kernels_folder())

    def get_cache_path(self):
        """The folder of the package's compiled kernels."""
        return self._cache_path

    def get_source_stamp(self):
        """The hash of every kernel file, not of the one file: see below."""
        # numba checks only the function's own file; a kernel compiled into another (walk.py
        # holds dop853.step and the equations) must be compiled anew when any of them changes
        return package_digest()

    @classmethod
    def from_function(cls, py_func, py_file):
        """The locator for a kernel of this package; None for anyone else's."""
        if Path(py_file).resolve() not in _claimed_files():
            return None  # not ours: numba's own locators decide
        # None only where not even a temporary folder can be written (kernels_folder)
        return super().from_function(py_func, py_file)


@functools.cache
def _claimed_files() -> frozenset[Path]:
    """sources.kernel_files, read once a process: numba asks the locator about each of the
    package's 180 kernels as their modules load, and a glob of the folders each time cost a
    start 18 ms."""
    return frozenset(sources.kernel_files())


def install() -> None:
    """Put the locator first, and _SparingIndexFile where numba's Cache takes its index and
    code files from (once per process); numba falls back to its own if the locator declines."""
    implementation = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # type: ignore[attr-defined]  # numba < 0.62
    locators = implementation._locator_classes
    if SourceTextCacheLocator not in locators:
        locators.insert(0, SourceTextCacheLocator)
    # numba's Cache makes its file object itself, from this module attribute: no other hook
    caching.IndexDataCacheFile = _SparingIndexFile  # type: ignore[misc]


def kernels_folder() -> Path:
    """Where this process keeps the kernels of this version of the package (index .nbi, code
    .nbc): kernels-<digest> in cache_root(), or where that cannot be written, a folder of that
    name in a temporary one of the process's own (not_kept says which and why)."""
    return _kept(cache_root() / f"kernels-{package_digest()}")


def not_kept(folder) -> tuple[Path, str] | None:
    """The cache folder that `folder` (kernels_folder's, or a kernel's) stands in for, and why
    that cannot be written; None where `folder` is not a stand-in."""
    return _STAND_INS.get(Path(folder))


# stand-in folder -> (the cache folder it stands in for, why that cannot be written)
_STAND_INS: dict[Path, tuple[Path, str]] = {}


@functools.cache
def _kept(wanted: Path) -> Path:
    """`wanted`, made if absent, where this process can write there; else a stand-in of that
    name in a new temporary folder, removed when the process ends, holding a copy of what
    `wanted` holds (a read-only cache that holds the code still serves); `wanted` itself
    where not even that can be made (the locator then declines)."""
    refusal = _refusal(wanted)
    if refusal is None:
        return wanted
    try:
        stand_in = Path(tempfile.mkdtemp(prefix="herringbone-kernels-")) / wanted.name
    except OSError:
        return wanted
    atexit.register(_remove, stand_in.parent, os.getpid())
    try:
        shutil.copytree(wanted, stand_in)
    except OSError:  # shutil.Error among them: what could not be read is compiled
        pass
    stand_in.mkdir(exist_ok=True)
    _STAND_INS[stand_in] = (wanted, refusal)
    return stand_in


def _refusal(folder: Path) -> str | None:
    """Why this process cannot write in `folder` (made if absent), as numba would try it
    (caching._CacheLocator.ensure_cache_path); None where it can."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError as error:
        return error.strerror or str(error)  # not the name of numba's probe file
    return None


def _remove(folder: Path, owner: int) -> None:
    """Remove a stand-in's temporary folder, in the process that made it only (a forked child
    runs its parent's exit handlers too)."""
    if os.getpid() == owner:
        shutil.rmtree(folder, ignore_errors=True)


def seed_from(carried: Path) -> list[str]:
    """Copy compiled kernels into the cache folder: from `carried` (a folder that holds a
    kernels-<digest> folder, as build_fmu puts into an FMU), into each kernel's index there
    the carried entries it lacks, with their code (_merge_index; an FMU carries its own
    scene's code only, and another FMU may have seeded that kernel with another method's).
    Returns the index files written; nothing if `carried` has none for this version. Raises
    OSError where kernels_folder cannot be written (not even a stand-in could be made: the
    caller says so; numba then compiles into its own cache)."""
    source, target = Path(carried) / kernels_folder().name, kernels_folder()
    written = []
    for index in sorted(source.glob("*.nbi")) if source.is_dir() else []:
        target.mkdir(parents=True, exist_ok=True)
        if _merge_index(source, target, index.name):
            written.append(index.name)
    return written


def _merge_index(source: Path, target: Path, name: str) -> bool:
    """Add to the index `name` in `target` (none: an empty one) the entries of the one in
    `source` that it lacks, their code copied first under data names of their own (random
    numbers from SEEDED_NUMBERS on; numba numbers its own 1, 2, ...), the index rewritten
    last; whether there were any. Two processes that seed or compile the same kernel at once
    each read the index before the other writes it: numbered by numba's rule (the first
    number the index does not use) both would write the same data file, and the index that
    lands last would name the other's code, which numba loads without checking its key and
    calls with arguments of other types. An entry one of them adds may still be lost (the
    other's index lands last, as between numba's own processes): that kernel is compiled at
    a later start. An index of another numba or version of the package reads as empty
    (numba's own reading): the carried entries then replace it."""
    carried, index = _index_file(source, name)._load_index(), _index_file(target, name)
    entries = index._load_index()
    lacking = {key: data for key, data in carried.items() if key not in entries}
    for key, data in lacking.items():
        entries[key] = index._data_name(SEEDED_NUMBERS | secrets.randbits(64))
        _copy_into(source / data, target, entries[key])
    if lacking:
        index._save_index(entries)
    return bool(lacking)


def carry_loaded(folder: Path) -> list[str]:
    """Copy into `folder`/kernels-<digest> (as seed_from reads it) the compiled code of this
    package that this process has loaded or compiled: for each kernel called from Python, the
    code for each set of argument types it ran with, and its index holding those entries
    alone. What those kernels call is compiled into their own code (the loop holds the
    events, the steps and the equations), so nothing else is needed to run them. Returns the
    index files written. Raises RuntimeError where an entry is not on disk
    (require_on_disk)."""
    target = Path(folder) / kernels_folder().name
    written = []
    for dispatcher in (kernel for kernel in kernels() if kernel.overloads):
        require_on_disk(dispatcher)
        cache, source = dispatcher._cache, Path(dispatcher._cache._cache_path)
        name, overloads = cache._cache_file._index_name, cache._cache_file._load_index()
        keys = [cache._index_key(signature, dispatcher.targetctx.codegen())
                for signature in dispatcher.overloads]
        target.mkdir(parents=True, exist_ok=True)
        for key in keys:
            _copy_into(source / overloads[key], target)
        _index_file(target, name, CarriedIndexFile)._save_index(
            {key: overloads[key] for key in keys})
        written.append(name)
    return written


def require_on_disk(dispatcher) -> None:
    """Raise RuntimeError, saying what to do, where the cache folder lacks code `dispatcher`
    (one of this package's kernels) holds in this process: numba could not write it there,
    or it went to a temporary folder that stands in for it (kernels_folder), which another
    process does not see."""
    stand_in = not_kept(dispatcher._cache._cache_path)
    if stand_in is not None:
        raise RuntimeError(f"the compiled integrator cannot be kept in {stand_in[0]} "
                           f"({stand_in[1]}): set HERRINGBONE_CACHE_DIR to a writable folder")
    missing = [reason for reason in map(functools.partial(why_not_cached, dispatcher),
                                        dispatcher.overloads) if reason]
    if missing:
        raise RuntimeError(f"the compiled integrator is not in {kernels_folder()} "
                           f"({missing[0]}): set HERRINGBONE_CACHE_DIR to a writable folder")


def _index_file(folder: Path, name: str, kind=None):
    """numba's reader and writer of the index `name` (a kernel's .nbi) in `folder`, as this
    version of the package stamps it (`kind`: _SparingIndexFile, or CarriedIndexFile)."""
    return (kind or _SparingIndexFile)(str(folder), name[:-len(".nbi")], package_digest())


# code files of this package's cache numba could not read and has not written since: path ->
# why (an index that cannot be read, why_not_cached reads itself)
_UNREADABLE: dict[str, str] = {}


class _SparingIndexFile(caching.IndexDataCacheFile):
    """numba's index and code files of a kernel, except that one of this package's (stamped
    with package_digest) that cannot be read reads as absent, as numba reads an index of
    another numba: numba then compiles the kernel and writes over the file. numba's own
    catches a missing file only, and a truncated index stopped every later start with an
    UnpicklingError. A code file it could not read is kept in _UNREADABLE, for
    why_not_cached."""

    def _load_index(self):
        try:
            return super()._load_index()
        except Exception:
            if self._source_stamp != package_digest():
                raise
            return {}

    def _load_data(self, name):
        try:
            return super()._load_data(name)
        except OSError:
            raise  # numba's load takes it for a missing file
        except Exception as error:
            if self._source_stamp != package_digest():
                raise
            _UNREADABLE[self._data_path(name)] = f"{type(error).__name__}: {error}"
            raise OSError(f"cannot read {self._data_path(name)}") from error

    def _save_data(self, name, data):
        super()._save_data(name, data)
        _UNREADABLE.pop(self._data_path(name), None)


class CarriedIndexFile(caching.IndexDataCacheFile):
    """numba's index file, written without the number numba gives each type in the process
    that made it (`Type._code`, a counter): pickled with it, the index an FMU carries depended
    on how many types its builder had made before, which the other entries of the user's
    index (unpickled with it) changed, and two builds of one scene differed. Unpickling
    numbers a type anew where the process has none like it (numba's _type_reconstructor)."""

    def _dump(self, obj):
        with io.BytesIO() as buffer:
            _UnnumberedPickler(buffer, protocol=4).dump(obj)
            return buffer.getvalue()


class _UnnumberedPickler(serialize.NumbaPickler):
    """numba's pickler, numba types pickled without their `_code`."""

    def reducer_override(self, obj):
        """A numba type's reduction with its state less `_code`; numba's for the rest."""
        if isinstance(obj, types.Type):
            function, (reconstructor, arguments, state) = obj.__reduce__()
            if isinstance(state, dict):
                state = {key: value for key, value in state.items() if key != "_code"}
            return function, (reconstructor, arguments, state)
        return super().reducer_override(obj)


def kernels() -> list:
    """The package's kernels (numba dispatchers defined at the top of its kernel modules,
    sources.kernel_modules) among the modules this process has imported."""
    from numba.core.dispatcher import Dispatcher

    return [value for name in sources.kernel_modules() if name in sys.modules
            for value in vars(sys.modules[name]).values()
            if isinstance(value, Dispatcher) and value.py_func.__module__ == name]


def _copy_into(source: Path, folder: Path, name: str | None = None) -> None:
    """Copy `source` into `folder` (as `name`, else its own), renamed into place."""
    handle, staging = tempfile.mkstemp(dir=folder, prefix=f".{source.name}.")
    os.close(handle)
    try:
        shutil.copyfile(source, staging)
        os.replace(staging, folder / (name or source.name))
    except BaseException:
        Path(staging).unlink(missing_ok=True)
        raise


def why_not_cached(dispatcher, signature) -> str | None:
    """Why numba must compile `dispatcher` (one of this package's kernels) for `signature`
    (its argument types) on this machine; None if its on-disk cache holds that entry. numba
    keys an entry on the signature, the target (triple, CPU name, CPU features) and the
    function's bytecode, under an index stamped with numba's version and the source digest."""
    cache = dispatcher._cache
    codegen = dispatcher.targetctx.codegen()
    key = cache._index_key(signature, codegen)
    index_path = Path(cache._cache_path) / cache._cache_file._index_name
    try:
        with open(index_path, "rb") as index:
            version = pickle.load(index)
            stamp, overloads = pickle.loads(index.read()) if version == _numba_version() \
                else (None, {})
    except FileNotFoundError:
        folder = (not_kept(index_path.parent) or (index_path.parent,))[0]
        return f"there is no compiled code for this version of the integrator in {folder}"
    except Exception as error:  # truncated or overwritten: read as absent (_SparingIndexFile)
        return (f"its cache index {index_path} cannot be read ({type(error).__name__}: "
                f"{error}): it is compiled again, and the index written anew")
    if version != _numba_version():
        return f"the code was compiled by numba {version}, and this is numba {_numba_version()}"
    if stamp != package_digest():
        return "the cached code belongs to another version of the integrator"
    if key in overloads:
        return _why_not_loaded(index_path.parent / overloads[key])
    machine = key[1]
    targets = {k[1] for k in overloads if k[0] == key[0]}
    if targets and machine not in targets:
        cpus = ", ".join(sorted({target[1] for target in targets}))
        same_cpu = any(target[1] == machine[1] for target in targets)
        return (f"the code was compiled for a {cpus} CPU with other features" if same_cpu
                else f"the code was compiled for a {cpus} CPU, and this is a {machine[1]}")
    return "the cached code was compiled for other argument types"


def _why_not_loaded(data: Path) -> str | None:
    """Why numba cannot load the code file `data` an index names; None where it can."""
    if str(data) in _UNREADABLE:
        return (f"its compiled code {data} cannot be read ({_UNREADABLE[str(data)]}): it is "
                "compiled again, and the file written anew")
    return None if data.is_file() else f"its compiled code {data} is missing"


def _numba_version() -> str:
    import numba

    return numba.__version__
