"""What the scipy reference costs on the shipped scenes (issue 25's cost bar).

    PYTHONPATH=fmu_src python3 benchmarks/reference_cost.py --stop-time 0.02 [models/x.toml …]

Runs reference_simulate at its default tolerance over `--stop-time` seconds of every scene given
(default: models/*.toml other than undamped.toml), 20 samples each, and prints the CPU and wall
seconds of each and the total. To compare two versions side by side, run it from each version's
source tree in turn (PYTHONPATH=<other tree>/fmu_src) and compare scene by scene.
"""
from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import herringbone  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stop-time", type=float, default=0.02)
    parser.add_argument("scenes", nargs="*", type=Path)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", UserWarning)  # scipy's note when rtol reaches its floor
    paths = args.scenes or [p for p in sorted((ROOT / "models").glob("*.toml"))
                            if p.stem != "undamped"]
    # the first run of a process loads the compiled equations from numba's cache (about a
    # second): a short run of the first scene takes that out of the figures
    herringbone.reference_simulate(herringbone.load_scene(paths[0]), stop_time=1e-4)
    total = 0.0
    for path in paths:
        scene = herringbone.load_scene(path)
        cpu, wall = time.process_time(), time.perf_counter()
        herringbone.reference_simulate(scene, stop_time=args.stop_time,
                                       output_interval=args.stop_time / 20)
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        total += cpu
        print(f"{path.stem:22s} cpu {cpu:7.2f} s  wall {wall:7.2f} s", flush=True)
    print(f"total cpu {total:.2f} s")


if __name__ == "__main__":
    main()
