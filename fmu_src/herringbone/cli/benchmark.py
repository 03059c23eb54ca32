"""`herringbone benchmark [error-vs-runtime | extreme-scenes] [OPTIONS]`: run a benchmark
script of the source checkout (benchmarks/), which declares and checks its own options."""
from __future__ import annotations

import importlib.util
import sys
import textwrap
from pathlib import Path

from ..suggest import did_you_mean

NAME = "benchmark"
SCRIPTS = {"error-vs-runtime": "error_vs_runtime", "extreme-scenes": "extreme_scenes"}
DEFAULT = "error-vs-runtime"  # what `herringbone benchmark` runs without a name
HELP = (f"measure the integrators: error against run time (the default) or the extreme scenes, "
        f"[{' | '.join(SCRIPTS)}] [OPTIONS], by benchmarks/error_vs_runtime.py or "
        "benchmarks/extreme_scenes.py of the source checkout; `herringbone benchmark --help` "
        "lists the options")
PROG = f"herringbone {NAME}"
NOT_INSTALLED = ("the benchmarks are not part of the installed package: they are scripts in the "
                 "benchmarks/ folder of the herringbone repository; clone the repository, "
                 "`pip install -e .` in the clone and run `herringbone benchmark` there")


def benchmarks_folder() -> Path | None:
    """The source checkout's benchmarks/ folder, None where this herringbone was installed
    without its repository (the folder above the package is then site-packages' parent)."""
    # The benchmarks are repository tools (they build FMUs with build_fmu.py), not in the package.
    folder = Path(__file__).resolve().parents[3] / "benchmarks"
    return folder if all((folder / f"{script}.py").is_file() for script in SCRIPTS.values()) \
        else None


def declare(parser) -> None:
    """Nothing: the script parses its options (main hands them over unparsed)."""


def execute(args, parser) -> int:
    """Not reached: `herringbone benchmark …` goes to execute_raw before any parsing."""
    return execute_raw([])


def print_help_without_checkout() -> None:
    """What `herringbone benchmark --help` says where the scripts, which list their own
    options, are not there: the benchmarks, and how to get them."""
    paragraphs = (f"Run benchmarks/error_vs_runtime.py ({DEFAULT}, the default) or "
                  "benchmarks/extreme_scenes.py (extreme-scenes) of the source checkout; each "
                  f"script declares its own options, which `{PROG} NAME --help` lists from a "
                  "checkout.", f"Not available here: {NOT_INSTALLED}.")
    print(f"usage: {PROG} [{' | '.join(SCRIPTS)}] [OPTIONS]\n")
    print("\n\n".join(textwrap.fill(paragraph, 79) for paragraph in paragraphs))


def execute_raw(arguments: list[str]) -> int:
    """Run the chosen script's main with the rest of the command line, its usage and messages
    naming the command as typed (`herringbone benchmark NAME`); its exit code."""
    if arguments[:1] and not arguments[0].startswith("-") and arguments[0] not in SCRIPTS:
        print(f"{PROG}: unknown benchmark {arguments[0]!r}"
              f"{did_you_mean(arguments[0], SCRIPTS)}; allowed: {', '.join(SCRIPTS)} "
              f"(`{PROG} --help` lists the options)", file=sys.stderr)
        return 2
    name = arguments.pop(0) if arguments[:1] and arguments[0] in SCRIPTS else DEFAULT
    folder = benchmarks_folder()
    if folder is None:
        if {"-h", "--help"} & set(arguments):  # the help is always there, checkout or not
            print_help_without_checkout()
            return 0
        print(f"{PROG}: {NOT_INSTALLED} (`{PROG} --help` says what they do)", file=sys.stderr)
        return 2
    script = folder / f"{SCRIPTS[name]}.py"
    spec = importlib.util.spec_from_file_location(f"benchmarks_{script.stem}", script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    try:  # the script's argparse ends --help and its errors with SystemExit, as main's does
        return module.main(arguments, prog=f"{PROG} {name}")
    except SystemExit as stop:
        return stop.code if isinstance(stop.code, int) else 2
