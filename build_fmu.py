"""Build this project's FMUs from a source checkout: a thin wrapper of herringbone.fmu.builder,
which `herringbone build-fmu` runs too (the same function, the same arguments).

    python build_fmu.py [SCENE] [-o OUT.fmu] [--simulate]   the gear FMU of a scene (a file or a
                                                            shipped scene's name; default
                                                            reference -> dist/HerringboneGear.fmu)
    python build_fmu.py --examples DIR                      the drive-train example FMUs
    python build_fmu.py [SCENE] --fmi 3                     the FMI 3.0 FMU instead (pythonfmu3)

Importable as before: `build_gear_fmu`, `build_example_fmus`, `build_slave_fmu`,
`fix_model_description`, `validate`, `carry_compiled_integrator`.
"""
from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT / "fmu_src"))  # this checkout's package, whatever is installed

from herringbone.fmu.builder import (  # noqa: E402, F401
    build_example_fmus,
    build_gear_fmu,
    build_slave_fmu,
    carry_compiled_integrator,
    fix_model_description,
    validate,
)
from herringbone.fmu.builder import main as _main  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    return _main(argv, prog="build_fmu", help_command="python build_fmu.py --help",
                 default_output=ROOT / "dist" / "HerringboneGear.fmu")


if __name__ == "__main__":
    sys.exit(main())
