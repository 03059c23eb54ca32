"""The first start of a built FMU for a user who has never run anything (every cache empty).

    python benchmarks/first_start.py               # the reference scene's FMU, 5 processes
    python benchmarks/first_start.py --runs 10 --fmu dist/reference-fmi2.fmu

Each run is a fresh process with fresh cache folders that simulates 0.01 s through
`fmpy.simulate_fmu`: its wall time, process start included, is what a user waits for on the
first run of an FMU on a new machine (the FMU carries its compiled code, so nothing is
compiled). Prints each run, then min, median and max, and whether any run compiled.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIMULATE = """
import sys, fmpy
messages = []
fmpy.simulate_fmu(sys.argv[1], stop_time=0.01, output_interval=1e-4, debug_logging=True,
                  logger=lambda *a: messages.append(a[-1].decode()))
print("\\n".join(messages))
"""


def fresh_user(home: Path) -> dict:
    """The environment of a user whose cache folders under `home` are all empty."""
    return {**os.environ, "HOME": str(home), "XDG_CACHE_HOME": str(home / "xdg"),
            "HERRINGBONE_CACHE_DIR": str(home / "herringbone")}


def first_start(fmu: Path) -> tuple[float, bool]:
    """(wall seconds of one first start, whether it compiled anything)."""
    with tempfile.TemporaryDirectory() as home:
        started = time.perf_counter()
        run = subprocess.run([sys.executable, "-c", SIMULATE, str(fmu)], env=fresh_user(
            Path(home)), capture_output=True, text=True, timeout=600)
        wall = time.perf_counter() - started
    if run.returncode != 0:
        sys.exit(f"first_start: the FMU's run failed: {run.stderr[-500:]}")
    return wall, "compil" in run.stdout + run.stderr


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="fresh processes (5)")
    parser.add_argument("--fmu", type=Path, help="a built FMU (default: the reference scene's, "
                        "built into a temporary folder)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        fmu = args.fmu
        if fmu is None:
            fmu = Path(folder) / "reference-fmi2.fmu"
            subprocess.run([sys.executable, "-m", "herringbone.cli", "build-fmu",
                            str(ROOT / "models" / "reference.toml"), "-o", str(fmu)],
                           check=True, capture_output=True)
        walls = []
        for k in range(args.runs):
            wall, compiled = first_start(fmu)
            walls.append(wall)
            print(f"run {k + 1}: {wall:.2f} s{'  (compiled)' if compiled else ''}", flush=True)
    print(f"first start, wall s: min {min(walls):.2f}  median {statistics.median(walls):.2f}  "
          f"max {max(walls):.2f}  ({args.runs} processes, {os.cpu_count()} cores)")


if __name__ == "__main__":
    main()
