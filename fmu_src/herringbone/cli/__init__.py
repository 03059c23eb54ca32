"""The `herringbone` command: one module per command (run, info, scenes, stability, sweep,
campbell, build-fmu, benchmark), each declaring its options once; every option is checked
through herringbone.arguments before any work, and every error is one line,
`herringbone COMMAND: <what is wrong>; allowed: …`, with exit code 2.

The library never imports this package.
"""
from __future__ import annotations

import argparse
import os
import sys

# Before numpy loads its BLAS: the model's matrices are 8 to 19 rows, which a BLAS's threads
# only slow down, and on a busy machine they fight over the cores (`herringbone stability` of
# examples/parametric_resonance.toml on 100 speeds: 5.7 s of wall time against 2.6 s with one
# thread on the 2-core machine at a load of 2). A thread count the user set is kept.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

from . import benchmark, build_fmu, campbell, info, run, scenes, stability, sweep  # noqa: E402
from .common import CommandParser, execute  # noqa: E402

COMMANDS = {module.NAME: module for module in (run, info, scenes, stability, sweep, campbell,
                                                 build_fmu, benchmark)}
DESCRIPTION = ("Dynamics of a herringbone Novikov gear train: run a scene, read its modes and "
               "stability, sweep it over speeds or parameters, build its FMU. SCENE is a scene "
               "file or the name of a shipped scene (`herringbone scenes`).")


def parser() -> tuple[argparse.ArgumentParser, dict[str, CommandParser]]:
    """The `herringbone` parser and each command's parser, by name."""
    from .. import __version__

    top = CommandParser(prog="herringbone", description=DESCRIPTION)
    top.add_argument("--version", action="version", version=f"herringbone {__version__}")
    subparsers = top.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                    parser_class=CommandParser)
    commands = {}
    for name, module in COMMANDS.items():
        commands[name] = subparsers.add_parser(name, help=module.HELP, description=module.HELP)
        module.declare(commands[name])
    return top, commands


def main(argv=None) -> int:
    """Run `herringbone ARGV`; the exit code: 0 on success, 2 with one line on stderr for a bad
    argument, option or scene (checked before any work) or a run that cannot go on."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == [benchmark.NAME]:  # its options belong to the benchmark script
        return benchmark.execute_raw(argv[1:])
    top, commands = parser()
    try:  # argparse ends --help, --version and its one-line errors with SystemExit
        args, extras = top.parse_known_args(argv)
        command = commands[args.command]
        if extras:
            command.unknown(extras)
        return execute(COMMANDS[args.command], args, command)
    except SystemExit as stop:
        return stop.code if isinstance(stop.code, int) else 2


if __name__ == "__main__":
    sys.exit(main())
