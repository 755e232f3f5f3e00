"""The reduced vehicle (examples/ground_vehicle.py) against its independent monolithic
reference (examples/vehicle/ground_reference.py: its own equations of motion with the
Model Exchange FMUs, Radau): a benchmark, not a test (the reference takes tens of
minutes of CPU per simulated second).

    python benchmarks/vehicle_reference.py --course bump --end-time 1.0
    python benchmarks/vehicle_reference.py --course sine --end-time 1.0 --rtol-check

Per course: the reference (and with --rtol-check the same at ten times its tolerance:
how far the reference itself is from converged); at each host step the co-simulation with
the default coupling and with `converged` (compiled path), their errors against the
reference in hull vertical and pitch acceleration, tyre force (the worst wheel) and damper
torque (the worst damper), max on a 4 ms grid in % of the reference's range, the
coupling's own error (default against `converged` at the same step) and the CPU seconds
per simulated second (the run's, without the set-up); the Python path's cost at 1 ms; the equations of motion checked
with the Kelvin elements (exudyn against the reference's ODE, no FMU in either); and the
ride figures, FMUs against Kelvin elements. CPU figures are this machine's under its load
at the time: compare them within one run only.
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from fmu_components.coupling import DEFAULT_SCHEME  # noqa: E402

from coupling_study import history_error  # noqa: E402
from ground_vehicle import COMPARED, make_course, simulate  # noqa: E402
from vehicle.ground_exudyn import linearisation  # noqa: E402
from vehicle.ground_reference import solve_reference  # noqa: E402
from vehicle.ride import ride_figures  # noqa: E402

OUTPUT = 5e-4  # s, where the reference is sampled
LABELS = {"hull_vertical_acceleration": "hull vertical", "hull_pitch_acceleration": "pitch",
          "tyre_force": "tyre force", "damper_torque": "damper torque"}


def reference(args, course_name, rtol, linear=None):
    cpu = time.process_time()
    found = solve_reference(make_course(course_name, args.start), args.speed, args.end_time,
                            np.arange(0.0, args.end_time + 1e-12, OUTPUT), linear=linear,
                            rtol=rtol)
    found["cpu"] = time.process_time() - cpu
    return found


def errors(result, against):
    return {key: history_error(result, against, key) for key in COMPARED}


def study_course(args, name, linear):
    print(f"\n## {make_course(name, args.start).describe()}, {args.speed:g} m/s, "
          f"{args.end_time:g} s\n", flush=True)
    ref = reference(args, name, args.rtol)
    print(f"reference: Radau at rtol {args.rtol:g}, {ref['evaluations']} evaluations, "
          f"{ref['events']} contact events, {ref['cpu']:.0f} s CPU; ranges: "
          + ", ".join(f"{LABELS[k]} {np.ptp(ref[k]):.4g}" for k in COMPARED), flush=True)
    if args.rtol_check:
        loose = reference(args, name, 10 * args.rtol)
        print(f"reference at rtol {10 * args.rtol:g} against it: "
              + ", ".join(f"{LABELS[k]} {v:.2g} %" for k, v in errors(loose, ref).items()),
              flush=True)
    head = ["host step", "scheme"] + [f"{LABELS[k]} (total)" for k in COMPARED] + [
        "own: hull vertical", "own: tyre force", "CPU s per s"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for step in args.steps:
        runs = {}
        for scheme in ("converged", DEFAULT_SCHEME):
            _, runs[scheme], cpu = simulate(make_course(name, args.start), args.speed,
                                            args.end_time, step, scheme)
            runs[scheme]["cpu"] = cpu
        for scheme, run in runs.items():
            total = errors(run, ref)
            own = errors(run, runs["converged"])
            lines.append(f"| {step * 1e3:g} ms | {scheme} | "
                         + " | ".join(f"{total[k]:.3g} %" for k in COMPARED)
                         + f" | {own['hull_vertical_acceleration']:.2g} % | "
                         f"{own['tyre_force']:.2g} % | {run['cpu'] / args.end_time:.2f} |")
        print(lines[-2] + "\n" + lines[-1], flush=True)
    print("\n" + "\n".join(lines), flush=True)
    _, compiled, compiled_cpu = simulate(make_course(name, args.start), args.speed,
                                         args.end_time, 1e-3)
    _, python, python_cpu = simulate(make_course(name, args.start), args.speed,
                                     args.end_time, 1e-3, path="python")
    print(f"\nat 1 ms ({DEFAULT_SCHEME}): compiled path {compiled_cpu / args.end_time:.2f}, "
          f"Python path {python_cpu / args.end_time:.2f} CPU s per simulated s (the runs, "
          f"without their set-up); they differ by {history_error(python, compiled, COMPARED[0]):.2g} % "
          f"in hull vertical acceleration", flush=True)

    kelvin_ref = reference(args, name, args.rtol, linear)
    for step in (1e-3, 5e-4):
        _, kelvin, _ = simulate(make_course(name, args.start), args.speed, args.end_time,
                                step, linear=linear)
        print(f"equations of motion, Kelvin elements, exudyn at {step * 1e3:g} ms against "
              f"the ODE: " + ", ".join(f"{LABELS[k]} {v:.2g} %"
                                       for k, v in errors(kelvin, kelvin_ref).items()),
              flush=True)
    nonlinear, linear_run = ride_figures(ref), ride_figures(kelvin_ref)
    print("\n| figure | FMUs (reference) | Kelvin (its reference) |\n|---|---|---|")
    for key, label in (("peak_hull_acceleration", "peak hull vertical acceleration, m/s2"),
                       ("peak_seat_acceleration", "peak seat vertical acceleration, m/s2"),
                       ("seat_wk_rms", "seat Wk-weighted RMS, m/s2"),
                       ("peak_pitch_acceleration", "peak pitch acceleration, rad/s2"),
                       ("total_damper_work", "work on the dampers, J"),
                       ("peak_tyre_force", "peak tyre force (wheel), N")):
        print(f"| {label} | {nonlinear[key]:.4g} | {linear_run[key]:.4g} |")
    print("| work on each damper (stations 1, 2, 6), J | "
          + ", ".join(f"{w:.4g}" for w in nonlinear["damper_work"]) + " | "
          + ", ".join(f"{w:.4g}" for w in linear_run["damper_work"]) + " |", flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--course", nargs="+", default=["bump", "sine"],
                        choices=["bump", "sine"])
    parser.add_argument("--speed", type=float, default=5.0)
    parser.add_argument("--end-time", type=float, default=1.0)
    parser.add_argument("--start", type=float, default=0.0,
                        help="m of flat run before the course (its obstacle reaches the "
                             "front wheel at once by default)")
    parser.add_argument("--steps", type=float, nargs="+", default=[4e-3, 2e-3, 1e-3, 5e-4])
    parser.add_argument("--rtol", type=float, default=1e-9)
    parser.add_argument("--rtol-check", action="store_true")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    linear = linearisation()
    print(f"Kelvin elements: {linear.describe()}")
    for name in args.course:
        study_course(args, name, linear)
    print(f"\nwall {time.perf_counter() - started:.0f} s, CPU {time.process_time():.0f} s")


if __name__ == "__main__":
    main()
