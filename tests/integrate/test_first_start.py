"""The first start on a machine: an FMU carries its compiled integrator; a compile says so first."""
import itertools
import os
import pickle
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import MODELS
from numba.core import types

import herringbone
from herringbone.compiling import cache
from herringbone.integrate import first_start

# s of wall time, process start included: a compile's announcement comes within it of the start
ANNOUNCEMENT_BOUND = 5.0
SOURCE = Path(herringbone.__file__).resolve().parent.parent


def fresh_user(tmp_path):
    """The environment of a user who has never run anything: every cache folder new."""
    home = tmp_path / "home"
    home.mkdir()
    return {**os.environ, "HOME": str(home), "XDG_CACHE_HOME": str(home / "xdg"),
            "HERRINGBONE_CACHE_DIR": str(home / "herringbone")}


SIMULATE = """
import sys, time, fmpy
messages = []
logger = lambda *a: messages.append((time.time(), a[-1].decode()))
fmpy.simulate_fmu(sys.argv[1], stop_time=0.01, output_interval=1e-4, debug_logging=True,
                  logger=logger)
for at, text in messages:
    print(f"{at:.3f} {text}")
"""


def test_a_built_fmu_starts_on_an_empty_cache_without_compiling(scene_fmu, tmp_path):
    """The FMU carries its compiled code: a user with every cache empty compiles nothing (how
    long that start takes: benchmarks/first_start.py)."""
    environment, fmu = fresh_user(tmp_path), scene_fmu("reference")
    run = subprocess.run([sys.executable, "-c", SIMULATE, str(fmu)],
                         env=environment, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "compil" not in run.stdout + run.stderr  # nothing was compiled
    # the carried code now sits in the user's cache, for every later start
    kernels = list(Path(environment["HERRINGBONE_CACHE_DIR"]).glob("kernels-*/walk.advance-*.nbi"))
    assert len(kernels) == 1


def test_an_fmu_of_another_method_started_next_compiles_nothing_either(scene_fmu, tmp_path):
    """Each FMU carries its own scene's code: the second (staggered, DOP853's loop), started
    after the first (the reference scene, the exponential method's) seeded the user's cache,
    adds its loop's entry to the index there rather than compiling it."""
    environment = fresh_user(tmp_path)
    for scene in ("reference", "staggered"):
        run = subprocess.run([sys.executable, "-c", SIMULATE, str(scene_fmu(scene))],
                             env=environment, capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr[-2000:]
        assert "compil" not in run.stdout + run.stderr, scene
    index, = Path(environment["HERRINGBONE_CACHE_DIR"]).glob("kernels-*/walk.advance-*.nbi")
    with open(index, "rb") as f:
        pickle.load(f)  # numba's version
        stamp, overloads = pickle.loads(f.read())
    assert len(overloads) == 2 == len(set(overloads.values()))
    assert all((index.parent / data).is_file() for data in overloads.values())


def _write_index(folder, name, entries):
    """An index `name` in `folder` mapping each key to its data file, which holds `entries`'
    bytes for it (numba's own reader and writer of indexes; the keys stand for numba's)."""
    folder.mkdir(parents=True, exist_ok=True)
    index = cache._index_file(folder, name)
    index._save_index({key: index._data_name(number) for number, key in
                       enumerate(entries, start=1)})
    for key, data in index._load_index().items():
        (folder / data).write_bytes(entries[key])


def test_two_fmus_seeding_a_kernel_at_once_never_name_each_others_code(tmp_path, monkeypatch):
    """Two processes that seed the same kernel's index at once each read it before the other
    writes it. However their writes interleave, every entry of the index that lands last
    names its own code: numba loads an entry's code without checking its key, and would call
    code compiled for other argument types. (An entry may be lost, which costs a compile.)"""
    monkeypatch.setenv("HERRINGBONE_CACHE_DIR", str(tmp_path / "user"))
    name, target = "walk.advance-1.py311.nbi", cache.kernels_folder()
    _write_index(target, name, {("own",): b"the user's own"})
    codes = {("own",): b"the user's own"}
    snapshots = {}
    for fmu in ("exponential", "dop853"):
        carried = tmp_path / fmu / target.name
        _write_index(carried, name, {(fmu,): fmu.encode()})
        codes[(fmu,)] = fmu.encode()
        snapshots[fmu] = tmp_path / f"{fmu}-view"  # the cache folder as that process read it
        shutil.copytree(target, snapshots[fmu])
        assert cache._merge_index(carried, snapshots[fmu], name)
    for first, second in itertools.permutations(snapshots.values()):
        for last_index in (first, second):
            landed = tmp_path / f"landed-{first.name}-{second.name}-{last_index.name}"
            shutil.copytree(target, landed)
            for writer in (first, second):  # each data file renamed into place, then the index
                for data in writer.glob("*.nbc"):
                    shutil.copyfile(data, landed / data.name)
            shutil.copyfile(last_index / name, landed / name)
            entries = cache._index_file(landed, name)._load_index()
            assert ("own",) in entries and len(entries) == 2
            assert all((landed / data).read_bytes() == codes[key]
                       for key, data in entries.items())


# Loads or compiles the integrator for a scene (argv[1]) as its FMU would, in a fresh cache, and
# prints the kernels numba compiled there.
COMPILE_FOR_SCENE = """
import sys
from herringbone.integrate import first_start
from herringbone.compiling import cache
first_start.compile_for_scene(sys.argv[1], say=lambda message: None)
print(" ".join(sorted(index.name.split("-")[0] for index in cache.kernels_folder().glob("*.nbi"))))
"""


@pytest.mark.slow  # a cold compile: three minutes on two cores
def test_a_scene_compiles_the_code_of_its_own_method_only(tmp_path):
    """The reference scene runs the exponential method (as "auto" picks), whose loop holds
    DOP853 for the segments it cannot take exactly: Radau IIA's kernels are not compiled, which
    shortens a cold compile by a quarter (docs/integrator.md, First start)."""
    environment = {**fresh_user(tmp_path), "PYTHONPATH": str(SOURCE)}
    run = subprocess.run([sys.executable, "-c", COMPILE_FOR_SCENE,
                          str(MODELS / "reference.toml")],
                         env=environment, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    compiled = run.stdout.split()
    assert "walk.advance" in compiled and "dop853.step" in compiled
    # Radau IIA's step, LU factors and Jacobian (its step-size rule, a few scalar lines, is
    # compiled with the loop's controller either way)
    assert not {"radau.step", "radau.factorize", "radau.lu_factor", "radau.lu_solve",
                "radau.jacobian_of"} & set(compiled)


PROBE = """
import json, pickle, sys
from pathlib import Path
from numba import typeof
from herringbone.compiling import announce, cache
from herringbone.integrate.compiled import walk
from herringbone.integrate import first_start

said = []
first_start.announce_compiles(lambda m: said.append((m, len(walk.hermite_root.overloads))))
arguments = (1.0, -1.0, -2.0, -2.0)
signature = tuple(typeof(a) for a in arguments)
before = cache.why_not_cached(walk.hermite_root, signature)
walk.hermite_root(*arguments)
after = cache.why_not_cached(walk.hermite_root, signature)
index = next(cache.kernels_folder().glob("walk.hermite_root-*.nbi"))
with open(index, "rb") as f:
    version = pickle.load(f)
    stamp, overloads = pickle.loads(f.read())
(key, data), = overloads.items()
def write(version, stamp, overloads):
    with open(index, "wb") as f:
        pickle.dump(version, f)
        f.write(pickle.dumps((stamp, overloads)))
other_cpu = (key[0], (key[1][0], "pentium4", key[1][2]), key[2])
write(version, stamp, {other_cpu: data})
on_other_cpu = cache.why_not_cached(walk.hermite_root, signature)
write("0.1.0", stamp, overloads)
other_numba = cache.why_not_cached(walk.hermite_root, signature)
write(version, "0" * 20, overloads)
other_version = cache.why_not_cached(walk.hermite_root, signature)
print(json.dumps(dict(before=before, after=after, on_other_cpu=on_other_cpu, cpu=key[1][1],
                      other_numba=other_numba, other_version=other_version, said=said,
                      records=announce._records())))
"""


def test_numba_is_asked_why_it_must_compile_and_the_compile_is_announced_first(tmp_path):
    import json

    environment = {**fresh_user(tmp_path), "PYTHONPATH": str(SOURCE)}
    run = subprocess.run([sys.executable, "-c", PROBE], env=environment, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    found = json.loads(run.stdout.splitlines()[-1])
    assert found["before"].startswith("there is no compiled code for this version")
    assert found["after"] is None
    assert found["on_other_cpu"] == ("the code was compiled for a pentium4 CPU, and this is a "
                                     f"{found['cpu']}")
    assert found["other_numba"].startswith("the code was compiled by numba 0.1.0, and this is")
    assert found["other_version"] == "the cached code belongs to another version of the integrator"
    # one message before numba compiled (the end's comes QUIET_SECONDS after, from a thread)
    (message, overloads_then), = [said for said in found["said"] if "compiling" in said[0]]
    assert overloads_then == 0
    assert message.startswith("compiling kernels of herringbone for this machine, "
                              "walk.hermite_root first (there is no compiled code for this "
                              "version of the integrator in ")
    assert "later starts load them from " in message
    assert found["records"]["walk.hermite_root"]["seconds"] > 0.0


@pytest.mark.slow
def test_an_fmu_on_another_cpu_says_why_and_how_long_before_it_compiles(scene_fmu, tmp_path):
    """The carried code marked as compiled for another CPU: the FMU compiles, and the host's
    logger hears about it while fmi2Instantiate is still running, not after."""
    import shutil
    import zipfile

    fmu = tmp_path / "other_cpu.fmu"
    unzipped = tmp_path / "unzipped"
    with zipfile.ZipFile(scene_fmu("reference")) as archive:
        archive.extractall(unzipped)
    for index in (unzipped / "resources" / first_start.CARRIED_FOLDER).glob("*/*.nbi"):
        with open(index, "rb") as f:
            version = pickle.load(f)
            stamp, overloads = pickle.loads(f.read())
        moved = {(k[0], (k[1][0], "pentium4", k[1][2]), k[2]): v for k, v in overloads.items()}
        with open(index, "wb") as f:
            pickle.dump(version, f)
            f.write(pickle.dumps((stamp, moved)))
    shutil.make_archive(str(fmu.with_suffix("")), "zip", unzipped)
    fmu.with_suffix(".zip").rename(fmu)
    started = time.time()  # the process's start: the announcement must come within seconds
    run = subprocess.run([sys.executable, "-c", SIMULATE, str(fmu)], env=fresh_user(tmp_path),
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    lines = [line.split(" ", 1) for line in run.stdout.splitlines()]
    announced = [(float(at), text) for at, text in lines if "compiling kernels of" in text]
    done = [(float(at), text) for at, text in lines if "kernels in" in text]
    assert len(announced) == 1 and len(done) == 1, run.stdout
    assert "the code was compiled for a pentium4 CPU, and this is a" in announced[0][1]
    assert announced[0][0] - started < ANNOUNCEMENT_BOUND  # said at the start, not after
    assert done[0][0] - announced[0][0] > 5.0  # ... of a compile that took a while


# Pickles an index's entry as an FMU carries it (CarriedIndexFile) and as numba writes its own
# (numba.core.serialize.dumps), after making `sys.argv[1]` other numba types first
PICKLE_AN_ENTRY = """
import sys
from numba.core import serialize, types
from herringbone.compiling import cache
count = int(sys.argv[1])
made = [types.Array(types.float64, 1 + k % 3, "C", readonly=k % 2 == 1) for k in range(count)]
made += [types.UniTuple(types.int64, k + 2) for k in range(count)]
key = ((types.Array(types.float64, 1, "C"), types.UniTuple(types.int64, 3)), ("x86_64", "cpu", ""))
carried = cache.CarriedIndexFile.__new__(cache.CarriedIndexFile)._dump(("stamp", {key: "k.nbc"}))
sys.stdout.write(carried.hex() + " " + serialize.dumps(("stamp", {key: "k.nbc"})).hex())
"""


def test_the_index_an_fmu_carries_does_not_depend_on_the_types_its_builder_made_before():
    """An index entry pickled as an FMU carries it (cache.CarriedIndexFile) is the same bytes
    in a process that made forty other numba types first as in one that made none, and reads
    back to an equal key; numba's own pickle differs there (each type carries the number the
    process gave it), which once made two builds of one scene different FMUs."""
    def pickled(others):
        run = subprocess.run([sys.executable, "-c", PICKLE_AN_ENTRY, str(others)],
                             capture_output=True, text=True, check=True)
        return [bytes.fromhex(text) for text in run.stdout.split()]

    (carried, numbas), (carried_after, numbas_after) = pickled(0), pickled(20)
    assert carried == carried_after and numbas != numbas_after
    stamp, entries = pickle.loads(carried)
    [(signature, _)] = entries
    assert signature == (types.Array(types.float64, 1, "C"), types.UniTuple(types.int64, 3))


def test_the_cache_folder_is_where_the_environment_says_read_as_the_xdg_spec_asks(tmp_path,
                                                                                  monkeypatch):
    """$HERRINGBONE_CACHE_DIR with `~` expanded (an env file or a systemd unit leaves it) and
    pinned where it was read; a relative $XDG_CACHE_HOME ignored, as the XDG spec says (each
    working folder would get a cache of its own); an empty HOME taken as none (the cache went
    to /.cache)."""
    import pwd

    home = tmp_path / "home"
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("HERRINGBONE_CACHE_DIR", raising=False)
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("XDG_CACHE_HOME", "relative")
    assert cache.cache_root() == home / ".cache" / "herringbone" / "numba"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache.cache_root() == tmp_path / "xdg" / "herringbone" / "numba"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", "")
    account = Path(pwd.getpwuid(os.getuid()).pw_dir)
    assert cache.cache_root() == account / ".cache" / "herringbone" / "numba"
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("HERRINGBONE_CACHE_DIR", "~/hb")
    assert cache.cache_root() == home / "hb"
    monkeypatch.setenv("HERRINGBONE_CACHE_DIR", "hb")
    assert cache.cache_root() == tmp_path / "hb"


# Compiles one small kernel (the cache as the environment says) and prints where numba keeps
# it and where the package it imported lives
SMALL_COMPILE = """
import herringbone
from herringbone.integrate.compiled import walk
walk.hermite_root(1.0, -1.0, -2.0, -2.0)
print(walk.hermite_root._cache._cache_path)
print(herringbone.__file__)
"""


def test_an_unwritable_cache_folder_is_said_once_and_nothing_goes_beside_the_package(tmp_path):
    """Where the cache folder cannot be written, the code goes to a temporary folder of the
    process, removed when it ends, and one line says so and what to set; numba's own
    locators, left to decide, wrote it beside the package's source (site-packages, where `pip
    uninstall` leaves it), or in ~/.cache/numba. The package runs from a copy here, so that
    such files land there and are seen."""
    package = tmp_path / "installed" / "herringbone"
    shutil.copytree(SOURCE / "herringbone", package,
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    (tmp_path / "file").write_text("in the way")
    environment = {**fresh_user(tmp_path), "PYTHONPATH": str(package.parent),
                   "HERRINGBONE_CACHE_DIR": str(tmp_path / "file" / "cache")}
    run = subprocess.run([sys.executable, "-c", SMALL_COMPILE], env=environment,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    kept, imported = run.stdout.split()
    assert Path(imported).parent == package
    written = [*package.rglob("*.nbi"), *Path(environment["HOME"]).rglob("*.nbi")]
    assert not written
    assert not Path(kept).exists()  # removed as the process ended
    [line] = [line for line in run.stderr.splitlines() if "cannot write" in line]
    assert f"cannot write in the cache folder {tmp_path / 'file' / 'cache'}" in line
    assert "HERRINGBONE_CACHE_DIR" in line
    assert "later starts load" not in run.stderr and "not kept" in run.stderr
    assert "compiled walk.hermite_root in " in run.stderr  # said as the process ended


def test_a_read_only_cache_folder_still_serves_the_code_it_holds(tmp_path, monkeypatch):
    """The temporary folder that stands in for a cache folder this process cannot write in
    starts as a copy of it: a cache filled beforehand and mounted read-only is loaded, not
    compiled again."""
    wanted = tmp_path / "read-only" / "kernels-0123"
    wanted.mkdir(parents=True)
    (wanted / "walk.advance-1.py311.nbi").write_bytes(b"an index")
    monkeypatch.setattr(cache, "_refusal", lambda folder: "[Errno 30] Read-only file system")
    stand_in = cache._kept(wanted)
    assert stand_in != wanted and stand_in.name == wanted.name
    assert (stand_in / "walk.advance-1.py311.nbi").read_bytes() == b"an index"
    assert cache.not_kept(stand_in) == (wanted, "[Errno 30] Read-only file system")
    assert cache.not_kept(wanted) is None


def test_a_damaged_cache_file_is_compiled_again_and_written_anew(tmp_path):
    """A truncated index (or code file) of a kernel reads as absent: numba compiles the kernel
    again and writes over it, and the announcement names the file; numba's own reader raised
    UnpicklingError, at every later start."""
    environment = {**fresh_user(tmp_path), "PYTHONPATH": str(SOURCE)}

    def start():
        run = subprocess.run([sys.executable, "-c", SMALL_COMPILE], env=environment,
                             capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr[-3000:]
        return run.stderr

    start()
    index, = Path(environment["HERRINGBONE_CACHE_DIR"]).glob("*/walk.hermite_root-*.nbi")
    data, = index.parent.glob("walk.hermite_root-*.nbc")
    for damaged in (index, data):
        damaged.write_bytes(damaged.read_bytes()[:20])
        said = start()
        assert f"{damaged} cannot be read (" in said, said
        assert "compiled again" in said
        assert len(damaged.read_bytes()) > 20  # written anew
    with open(index, "rb") as f:
        pickle.load(f)
        stamp, overloads = pickle.loads(f.read())
    assert stamp == cache.package_digest() and len(overloads) == 1


def test_an_fmu_seeds_over_a_damaged_index(tmp_path, monkeypatch):
    """The user's index of a kernel, truncated: the entries the FMU carries replace it (it
    raised UnpicklingError, and the FMU did not instantiate)."""
    monkeypatch.setenv("HERRINGBONE_CACHE_DIR", str(tmp_path / "user"))
    name, target = "walk.advance-1.py311.nbi", cache.kernels_folder()
    carried = tmp_path / "fmu" / target.name
    _write_index(carried, name, {("carried",): b"the carried code"})
    target.mkdir(parents=True, exist_ok=True)
    (target / name).write_bytes((carried / name).read_bytes()[:20])
    assert cache._merge_index(carried, target, name)
    entries = cache._index_file(target, name)._load_index()
    assert list(entries) == [("carried",)]
    assert (target / entries[("carried",)]).read_bytes() == b"the carried code"


# Compiles one small kernel with nothing said to the announcer but how often to report
# progress (on stderr, by default), then waits for the announcement's end
ANNOUNCED = """
import time
from herringbone.compiling import announce
from herringbone.integrate.compiled import walk
announce.announce_compiles(every=0.05)
walk.hermite_root(1.0, -1.0, -2.0, -2.0)
time.sleep(announce.QUIET_SECONDS + 1.0)
"""


def test_every_compile_is_announced_on_stderr_with_its_progress_and_its_end(tmp_path):
    """No caller has a word to say (herringbone.simulate, a sweep, a script): the compile is
    announced on stderr as it starts, with what and why, then its progress, then its end and
    time; nothing was said outside `herringbone run` and build-fmu, and progress lines only by
    the builder."""
    environment = {**fresh_user(tmp_path), "PYTHONPATH": str(SOURCE)}
    run = subprocess.run([sys.executable, "-c", ANNOUNCED], env=environment,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stdout == ""
    lines = run.stderr.splitlines()
    assert lines[0].startswith("compiling kernels of herringbone for this machine, "
                               "walk.hermite_root first (there is no compiled code for this "
                               "version of the integrator in ")
    progress = [line for line in lines if line.startswith("  ... ")]
    assert progress and all(": compiling walk.hermite_root" in line for line in progress)
    assert lines[-1].startswith("compiled walk.hermite_root in ")
    assert lines[-1].endswith(f"later starts load it from {cache_folder(environment)}")
    assert len(lines) == 2 + len(progress)


def cache_folder(environment) -> Path:
    """The kernels folder of this version of the package under `environment`'s cache."""
    return Path(environment["HERRINGBONE_CACHE_DIR"]) / f"kernels-{cache.package_digest()}"
