"""Build this project's FMUs from a source checkout: `herringbone build-fmu` under another name,
its FMUs in the checkout's dist/ (`python build_fmu.py --help` lists the options)."""
from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT / "fmu_src"))  # this checkout's package, whatever is installed

from herringbone.cli.build_fmu import main as build_main  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    """`herringbone build-fmu ARGV` as build_fmu.py; the exit code."""
    return build_main(argv, prog="build_fmu", help_command="python build_fmu.py --help",
                      dist=ROOT / "dist")


if __name__ == "__main__":
    sys.exit(main())
