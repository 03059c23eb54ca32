"""`herringbone benchmark [error-vs-runtime | extreme-scenes] [OPTIONS]`: run a benchmark
script of the source checkout (benchmarks/), which declares and checks its own options."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from ..suggest import did_you_mean

NAME = "benchmark"
# The benchmarks are repository tools (they build FMUs with build_fmu.py), not part of the package.
BENCHMARKS = Path(__file__).resolve().parents[3] / "benchmarks"
SCRIPTS = {"error-vs-runtime": "error_vs_runtime", "extreme-scenes": "extreme_scenes"}
DEFAULT = "error-vs-runtime"  # what `herringbone benchmark` runs without a name
HELP = (f"[{' | '.join(SCRIPTS)}] [OPTIONS]: run benchmarks/error_vs_runtime.py (the default) "
        "or benchmarks/extreme_scenes.py of the source checkout; `herringbone benchmark "
        "--help` lists the options")
PROG = f"herringbone {NAME}"


def declare(parser) -> None:
    """Nothing: the script parses its options (main hands them over unparsed)."""


def execute(args, parser) -> int:
    """Not reached: `herringbone benchmark …` goes to execute_raw before any parsing."""
    return execute_raw([])


def execute_raw(arguments: list[str]) -> int:
    """Run the chosen script's main with the rest of the command line, its usage and messages
    naming the command as typed (`herringbone benchmark NAME`); its exit code."""
    if arguments[:1] and not arguments[0].startswith("-") and arguments[0] not in SCRIPTS:
        print(f"{PROG}: unknown benchmark {arguments[0]!r}"
              f"{did_you_mean(arguments[0], SCRIPTS)}; allowed: {', '.join(SCRIPTS)} "
              f"(`{PROG} --help` lists the options)", file=sys.stderr)
        return 2
    name = arguments.pop(0) if arguments[:1] and arguments[0] in SCRIPTS else DEFAULT
    script = BENCHMARKS / f"{SCRIPTS[name]}.py"
    if not script.is_file():
        print(f"{PROG}: the benchmarks need the source checkout: {script} is not there (this "
              "herringbone was installed without its repository); clone the repository, "
              "`pip install -e .` it and run `herringbone benchmark` from there", file=sys.stderr)
        return 2
    spec = importlib.util.spec_from_file_location(f"benchmarks_{script.stem}", script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main(arguments, prog=f"{PROG} {name}")
