"""How well the scipy reference at its default tolerance agrees with itself 100× tighter, over the
random-scene distribution, undamped trains included (issue 25).

    PYTHONPATH=fmu_src python3 benchmarks/reference_accuracy.py --count 10 --seed 0 [--undamped]
    PYTHONPATH=fmu_src python3 benchmarks/reference_accuracy.py --seeds 1202 1028 [--undamped]

Scene k is the one tests/helpers/scene_distribution.py draws from seed S + k; with --undamped
each is run
a second time with every damping set to zero (mesh, shafts, bearings), the trains whose step
errors ring for the whole run. Each runs over its own experiment (5-20 ms) with
reference_simulate at 1e-10 and at 1e-12; the figure is max |F(1e-10) − F(1e-12)| over F_mesh and
the bearing forces, in units of GearTrainModel.force_scale(). Prints one line per run and a
summary: the largest figure, the median, how many are beyond 1e-8 (issue 25's bar), and the
seconds each run took. A run that lands is checked (herringbone/integrate/global_error.py): its
line adds, at each tolerance, the runs the check made, the step tolerance of the run delivered,
its estimate of that run's error and "warned" where it gave a ReferenceAccuracyWarning. Needs
numpy, scipy and a herringbone source tree on PYTHONPATH.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[1]
# helpers.scene_distribution: the one home of the distribution
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402
from helpers.scene_distribution import random_scene  # noqa: E402

from herringbone.integrate.global_error import ReferenceAccuracyWarning  # noqa: E402
from herringbone.integrate.reference import checked_reference_run  # noqa: E402
from herringbone.model.assembly import GearTrainModel  # noqa: E402

FORCES = ("F_mesh", "F_brg_pinion_left", "F_brg_pinion_right", "F_brg_wheel_left",
          "F_brg_wheel_right")
BAR = 1e-8


def undamped(scene):
    """The scene with every damping (mesh, shafts, bearings) set to zero."""
    zeros = {name: 0.0 for name in scene.parameters
             if name == "zeta_mesh" or name.startswith("h_")}
    return scene.with_parameters(**zeros)


def agreement(scene) -> tuple[float, list[float], list[str]]:
    """(max |ΔF| / force scale of 1e-10 against 1e-12, seconds at each, what the check of each
    did: "" for a run that was not checked)."""
    runs, seconds, checks = [], [], []
    for tolerance in (1e-10, 1e-12):
        started = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ReferenceAccuracyWarning)
            result, check = checked_reference_run(scene, tolerance=tolerance)
        seconds.append(time.perf_counter() - started)
        runs.append(result)
        warned = ", warned" if any(issubclass(w.category, ReferenceAccuracyWarning)
                                   for w in caught) else ""
        checks.append("" if check.estimate is None else
                      f"[{check.runs} runs to {check.step_tolerance:.1e}, "
                      f"est {check.estimate:.1e}{warned}]")
    scale = GearTrainModel(scene).force_scale()
    error = max(np.abs(runs[0][k] - runs[1][k]).max() for k in FORCES if k in runs[0]) / scale
    return float(error), seconds, checks


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--seeds", type=int, nargs="*",
                        help="these seeds instead of --count from --seed")
    parser.add_argument("--undamped", action="store_true",
                        help="also run each scene with every damping set to zero")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", UserWarning)  # scipy's note when rtol reaches its floor
    figures = []
    seeds = args.seeds or range(args.seed, args.seed + args.count)
    for seed in seeds:
        scene = random_scene(seed)
        variants = [("drawn", scene)] + ([("undamped", undamped(scene))] if args.undamped else [])
        for label, variant in variants:
            error, seconds, checks = agreement(variant)
            figures.append(error)
            loss = variant.parameters["contact_loss"]
            stop_ms = variant.experiment.stop_time * 1e3
            checked = f"  checked: {checks[0] or '-'} {checks[1] or '-'}" if any(checks) else ""
            print(f"seed {seed:5d} {label:8s} contact_loss={loss!s:5s} stop {stop_ms:5.1f} ms  "
                  f"1e-10 vs 1e-12: "
                  f"{error:.2e}  ({seconds[0]:.1f} s, {seconds[1]:.1f} s){checked}", flush=True)
    values = np.array(figures)
    print(f"{len(values)} runs: largest {values.max():.2e}, median {np.median(values):.2e}, "
          f"beyond {BAR:g}: {int((values > BAR).sum())}")


if __name__ == "__main__":
    main()
