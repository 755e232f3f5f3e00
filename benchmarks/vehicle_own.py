"""CPU seconds per simulated second of the tracked vehicle on its own solver against exudyn
(examples/tracked_vehicle.py --solver own/exudyn; docs/vehicle.md "The vehicle on its own
solver"): the same run on the bump from the stored static point at each speed, the two
solvers alternated in rounds, with Newton iterations per solve, solves per step and steps;
for the own solver where its time goes (its solve's CPU: the system's evaluation, its
Jacobian, the rest the solver core's LU and updates; the bank's calls; the deflections;
the records; the step check; the rest Python per step).

    python benchmarks/vehicle_own.py [--speeds 3 5] [--end-time 0.2] [--rounds 2]
    python benchmarks/vehicle_own.py --agreement 0.1 0.001 [--speeds 3] [--end-time 0.02]

Prints each run and the load (os.getloadavg) before and after. --agreement: instead, at
each Newton absolute tolerance given, the two runs' largest difference of the histories
(outputs.largest_difference, in % of range) and their Newton iterations per solve.
"""

import argparse
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from tracked_vehicle import DEFAULT_STEP, simulate  # noqa: E402
from vehicle.model import static_points  # noqa: E402
from vehicle.outputs import largest_difference  # noqa: E402

KEYS = ("hull_vertical_acceleration", "hull_pitch_acceleration",
        "seat_vertical_acceleration", "hull_y", "tyre_force", "damper_torque",
        "bush_radial_force", "bush_torque")


def agreement(speeds, end_time, tolerances, statics):
    for speed in speeds:
        for tolerance in tolerances:
            runs = {solver: simulate("bump", speed, end_time, DEFAULT_STEP, statics=statics,
                                     newton_tolerance=tolerance, solver=solver)
                    for solver in ("exudyn", "own")}
            difference, key = largest_difference(runs["exudyn"][1], runs["own"][1], KEYS)
            iterations = [runs[s][0].solver_statistics()["newton_per_pass"] for s in runs]
            print(f"{speed:g} m/s, tolerance {tolerance:g}: largest difference "
                  f"{difference:.3g} % of range ({key}); Newton iterations per solve "
                  f"exudyn {iterations[0]:.3f}, own {iterations[1]:.3f}", flush=True)


def split(statistics, cpu):
    """The own run's CPU by part, s: the core's own share is its solve less the system's
    evaluations and Jacobians; Python the run's CPU less every part."""
    s = statistics
    parts = {"system f, g, G": s["evaluate_s"], "system K, D": s["jacobian_s"],
             "solver core (LU, updates)": s["solve"] - s["evaluate_s"] - s["jacobian_s"],
             "bank": s["bank"], "deflections": s["deflections"],
             "records": s["record"], "step check": s["check"]}
    parts["Python per step, the rest"] = cpu - s["solve"] - sum(
        s[k] for k in ("bank", "deflections", "record", "check"))
    return parts


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", type=float, nargs="+", default=[3.0, 5.0])
    parser.add_argument("--end-time", type=float, default=0.2)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--agreement", type=float, nargs="+", metavar="TOLERANCE")
    args = parser.parse_args(argv)
    print(f"load before: {os.getloadavg()}")
    statics = static_points()
    if args.agreement:
        agreement(args.speeds, args.end_time, args.agreement, statics)
        print(f"load after: {os.getloadavg()}")
        return
    for speed in args.speeds:
        for round_ in range(args.rounds):
            for solver in ("exudyn", "own"):
                vehicle, result, wall, cpu = simulate("bump", speed, args.end_time,
                                                      DEFAULT_STEP, statics=statics,
                                                      solver=solver)
                simulated = result["time"][-1] - result["time"][0]
                s = vehicle.solver_statistics()
                print(f"{speed:g} m/s round {round_ + 1} {solver}: {cpu / simulated:.2f} s CPU "
                      f"per simulated s ({wall / simulated:.2f} wall); "
                      f"{s['newton_per_pass']:.2f} Newton iterations per solve, "
                      f"{s['passes_per_step']:.2f} solves per step, {s['steps']} steps for "
                      f"{s['host_steps']}, {s['refused']} refused", flush=True)
                if solver == "own":
                    parts = split(s, cpu)
                    print("    " + ", ".join(f"{name} {seconds / simulated:.3f}"
                                             for name, seconds in parts.items())
                          + " (s per simulated s)", flush=True)
    print(f"load after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
