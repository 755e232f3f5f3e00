"""The tracked vehicle's accuracy and cost study (examples/tracked_vehicle.py,
docs/vehicle.md): a benchmark, not a test (minutes to hours of CPU).

    python benchmarks/vehicle_study.py --end-time 0.05            # coupling's own error
    python benchmarks/vehicle_study.py --steps 4 2 1 0.5 --end-time 0.2
    python benchmarks/vehicle_study.py --path python    # the coupling's Python path

For each host step: the run with the default coupling and with `converged` at the same
step (the coupling's own error: the largest difference in hull vertical acceleration, in
% of the converged run's range), the error against the finest step's converged run (the
step study), CPU seconds per simulated second, exudyn's Newton iterations per solve and
solves per host step. All runs start from the same stored static point (one settling
first, excluded from the costs). CPU figures are this machine's, in one run, under
whatever load it carries: compare them within a table only.
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from fmu_components.coupling import DEFAULT_SCHEME  # noqa: E402

import bank_path  # noqa: E402
from tracked_vehicle import simulate  # noqa: E402
from vehicle.model import static_points  # noqa: E402

KEY = "hull_vertical_acceleration"


def run(args, step, scheme, statics):
    cpu = time.process_time()
    vehicle, result, _, run_cpu = simulate(args.course, args.speed, args.end_time, step,
                                           scheme, None, statics, args.settle_time,
                                           path=args.path)
    solver = vehicle.solver_statistics()
    print(f"  {scheme} at {step * 1e3:g} ms: {run_cpu:.1f} s CPU "
          f"({time.process_time() - cpu:.1f} with the set-up)", flush=True)
    return {"time": result["time"], "value": result[KEY],
            "cpu": run_cpu / (result["time"][-1] - result["time"][0]), **solver}


def difference(run, reference):
    """Largest |difference| on the reference's times (the run interpolated), in % of the
    reference's range."""
    value = np.interp(reference["time"], run["time"], run["value"])
    span = np.ptp(reference["value"]) or 1.0
    return 100 * np.max(np.abs(value - reference["value"])) / span


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[1.0], help="ms")
    parser.add_argument("--end-time", type=float, default=0.05)
    parser.add_argument("--speed", type=float, default=5.0)
    parser.add_argument("--course", default="bump")
    parser.add_argument("--scheme", default=DEFAULT_SCHEME)
    parser.add_argument("--settle-time", type=float, default=3.0)
    bank_path.add_argument(parser)
    args = parser.parse_args(argv)
    statics = static_points()
    runs = {}
    for step in sorted(args.steps, reverse=True):
        h = step * 1e-3
        runs[step] = (run(args, h, args.scheme, statics), run(args, h, "converged", statics))
    finest = runs[min(runs)][1]
    print(f"\n{args.course} at {args.speed:g} m/s, {args.end_time:g} s, the coupling's "
          f"{args.path} path; errors in hull vertical acceleration, % of range\n")
    print(f"| step (ms) | {args.scheme} against converged | against converged at "
          f"{min(runs):g} ms | CPU s / s | Newton per solve | solves per step |")
    print("|---|---|---|---|---|---|")
    for step, (default, converged) in sorted(runs.items(), reverse=True):
        print(f"| {step:g} | {difference(default, converged):.3g} | "
              f"{difference(default, finest):.3g} | {default['cpu']:.0f} | "
              f"{default['newton_per_pass']:.1f} | {default['passes_per_step']:.2f} |")


if __name__ == "__main__":
    main()
