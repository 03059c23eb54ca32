"""What each compiled method keeps over a long run: the angular momentum, and the switches.

    python benchmarks/long_run_drift.py                       # the reference scene, 0.5 s and 5 s
    python benchmarks/long_run_drift.py --methods radau --tolerances 1e-7 1e-9

With balanced torques (M_load = u·M_motor, as the reference scene has them) nothing outside the
train changes its angular momentum referred to the pinion, I_m·ω_m + I_p·ω_p + (I_w·ω_w +
I_l·ω_l)/u: for each method and tolerance, its spread over --momentum-time seconds relative to
its start. Over --long-time seconds, what a method's step errors add up to as the contact
switches move: the largest |F_mesh − F_mesh(DOP853 at 1e-11)| in each second, over the force
scale. docs/integrator.md (Methods) quotes these figures.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy as np  # noqa: E402
from helpers import momentum_terms  # noqa: E402

import herringbone  # noqa: E402
from herringbone.model.assembly import GearTrainModel  # noqa: E402


def per_second_error(run, truth, scale, seconds):
    """The largest |F_mesh − truth's| over the force scale in each whole second of `run`."""
    time_s, error = run["time"], np.abs(run["F_mesh"] - truth["F_mesh"]) / scale
    return [float(error[(time_s > k) & (time_s <= k + 1)].max()) for k in range(seconds)]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default="reference")
    parser.add_argument("--methods", nargs="+", default=["dop853", "radau", "exponential"])
    parser.add_argument("--tolerances", nargs="+", type=float, default=[1e-7, 1e-9])
    parser.add_argument("--momentum-time", type=float, default=0.5)
    parser.add_argument("--long-time", type=int, default=5, help="whole seconds")
    args = parser.parse_args(argv)
    scene = herringbone.load_scene(args.scene)
    model = GearTrainModel(scene)
    truth = herringbone.simulate(scene, stop_time=args.long_time, output_interval=1e-3,
                                 method="dop853", tolerance=1e-11)
    print(f"{scene.name}: momentum spread over {args.momentum_time:g} s; F_mesh off DOP853 at "
          f"1e-11 in each of {args.long_time} s, over the force scale")
    for method in args.methods:
        for tolerance in args.tolerances:
            started = time.process_time()
            short = herringbone.simulate(scene, stop_time=args.momentum_time,
                                         output_interval=1e-3, method=method,
                                         tolerance=tolerance)
            cpu = time.process_time() - started
            kept = np.sum(momentum_terms(scene, short), axis=0)
            long = herringbone.simulate(scene, stop_time=args.long_time, output_interval=1e-3,
                                        method=method, tolerance=tolerance)
            errors = per_second_error(long, truth, model.force_scale(), args.long_time)
            print(f"  {method:11s} {tolerance:7.0e}: momentum {np.ptp(kept) / abs(kept[0]):.1e} "
                  f"({cpu:.2f} s CPU); F_mesh " + " ".join(f"{e:.1e}" for e in errors),
                  flush=True)


if __name__ == "__main__":
    main()
