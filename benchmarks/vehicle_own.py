"""CPU seconds per simulated second of the tracked vehicle on its own solver against exudyn
(examples/tracked_vehicle.py --solver own/exudyn; docs/vehicle.md "The vehicle on its own
solver"): the same run on the bump (--course: another) from the stored static point at
each speed, the two solvers alternated in rounds, with Newton iterations per solve, solves
per step and steps; for the own solver where its time goes (its solve's CPU: the system's
evaluation, its Jacobian, the rest the solver core's LU and updates; the bank's calls; the
deflections; the records; the step check; the rest Python per step).

    python benchmarks/vehicle_own.py [--speeds 3 5] [--end-time 0.2] [--rounds 2]
                                     [--course bump [sine random]]
    python benchmarks/vehicle_own.py --agreement 0.1 0.001 [--speeds 3] [--end-time 0.02]
    python benchmarks/vehicle_own.py --newton full reuse [--no-exudyn] ...
    python benchmarks/vehicle_own.py --couplings corrected iterated ...

Prints each run and the load (os.getloadavg) before and after, and then, for each course,
speed and solver, the median of its rounds' CPU s per simulated s with their range (real
time: 1 or less) and the system's evaluation's median time per call, the machine's pace
(one run's CPU moves with it: compare runs of one round). Each round runs every course,
speed and solver once, so that a change of the machine's pace falls on all of them.
--agreement: instead, at
each Newton absolute tolerance given, the two runs' largest difference of the histories
(outputs.largest_difference at the times both runs have, in % of range; the hull's
vertical acceleration's too) and their Newton iterations per solve, and each run against
the first's at the smallest tolerance. --newton: the own solver's Newton policies
(vehicle/own_host.py NEWTON; POLICY@RATIO: that policy at another contractivity), each
run in every round (with the Newton matrices per step and the solves' CPU); with two or
more, --agreement compares each with the first instead of exudyn with own. --couplings:
each solver's run with each of these coupling schemes in every round (default the
vehicle's, model.COUPLING).
"""

import argparse
import itertools
import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from tracked_vehicle import DEFAULT_STEP, simulate  # noqa: E402
from vehicle.course import COURSES  # noqa: E402
from vehicle.model import COUPLING, static_points  # noqa: E402
from vehicle.outputs import largest_difference  # noqa: E402
from vehicle.own_host import DEFAULT_NEWTON, NEWTON  # noqa: E402

KEYS = ("hull_vertical_acceleration", "hull_pitch_acceleration",
        "seat_vertical_acceleration", "hull_y", "tyre_force", "damper_torque",
        "bush_radial_force", "bush_torque")


def policy(name):
    """A key of own_host.NEWTON, or POLICY@RATIO (registered there); the key."""
    base, _, ratio = name.partition("@")
    if base not in NEWTON:
        raise SystemExit(f"--newton {name}: one of {', '.join(NEWTON)} (@RATIO after one)")
    if ratio:
        NEWTON[name] = {**NEWTON[base], "reuse_contractivity": float(ratio)}
    return name


def run(course, speed, end_time, statics, solver, **given):
    """simulate's run of `solver` on `course`: "exudyn", or an own solver's Newton policy."""
    own = None if solver == "exudyn" else solver
    return simulate(course, speed, end_time, DEFAULT_STEP, statics=statics,
                    solver="own" if own else "exudyn", own_newton=own, **given)


def common_times(a, b):
    """Two runs' histories of KEYS at the times both have (a step one run halved and the
    other did not adds times to one)."""
    ta, tb = (np.round(np.asarray(r["time"]) * 1e9).astype(np.int64) for r in (a, b))
    keep_a, keep_b = np.isin(ta, tb), np.isin(tb, ta)
    return ({key: np.asarray(a[key])[keep_a] for key in ("time",) + KEYS},
            {key: np.asarray(b[key])[keep_b] for key in ("time",) + KEYS})


def agreement(course, speeds, end_time, tolerances, statics, solvers):
    """Each pair at each tolerance, and each run against the first solver's at the smallest
    tolerance (what stopping at the tolerance moves), at the times both have."""
    def compare(what, a, b):
        ha, hb = common_times(runs[a][1], runs[b][1])
        difference, key = largest_difference(ha, hb, KEYS)
        hull, _ = largest_difference(ha, hb, KEYS[:1])
        iterations = [runs[r][0].solver_statistics()["newton_per_pass"] for r in (a, b)]
        print(f"{speed:g} m/s, {what}: largest difference {difference:.3g} % of range "
              f"({key}), the hull's vertical acceleration's {hull:.3g} %; Newton "
              f"iterations per solve {iterations[0]:.3f}, {iterations[1]:.3f}", flush=True)

    for speed in speeds:
        runs = {(solver, tolerance): run(course, speed, end_time, statics, solver,
                                         newton_tolerance=tolerance)
                for tolerance in tolerances for solver in solvers}
        first, tightest = solvers[0], min(tolerances)
        for tolerance in tolerances:
            for other in solvers[1:]:
                compare(f"tolerance {tolerance:g}, {first} against {other}",
                        (first, tolerance), (other, tolerance))
            for solver in solvers if tolerance != tightest else ():
                compare(f"{solver} at {tolerance:g} against {first} at {tightest:g}",
                        (first, tightest), (solver, tolerance))


def split(statistics, cpu):
    """The own run's CPU by part, s: the core's own share is its solve less the system's
    evaluations and Jacobians; Python the run's CPU less every part. Where a pass's end is
    one C call (own_pass.c), the step check holds the contacts' adoption and the
    deflections (deflections 0); the bank holds its accept in C, the records the record."""
    s = statistics
    parts = {"system f, g, G": s["evaluate_s"], "system K, D": s["jacobian_s"],
             "solver core (LU, updates)": s["solve"] - s["evaluate_s"] - s["jacobian_s"],
             "bank": s["bank"], "deflections": s["deflections"],
             "records": s["record"], "step check": s["check"]}
    parts["Python per step, the rest"] = cpu - s["solve"] - sum(
        s[k] for k in ("bank", "deflections", "record", "check"))
    return parts


def medians(figures, rounds):
    """The table of each run's median over the rounds: {(course, speed, solver, coupling):
    [(CPU s per simulated s, the system's us per evaluation or None)]}."""
    lines = [f"medians of {rounds} round(s), CPU s per simulated s (real time: 1 or less):",
             "| course | speed | solver | coupling | median | range | us per evaluation |",
             "|---|---|---|---|---|---|---|"]
    for (course, speed, solver, coupling), runs in figures.items():
        cpu = [run[0] for run in runs]
        paces = [run[1] for run in runs if run[1] is not None]
        pace = f"{np.median(paces):.1f}" if paces else "-"
        lines.append(f"| {course} | {speed:g} m/s | {solver} | {coupling} | "
                     f"{np.median(cpu):.2f} | {min(cpu):.2f}-{max(cpu):.2f} | {pace} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", type=float, nargs="+", default=[3.0, 5.0])
    parser.add_argument("--end-time", type=float, default=0.2)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--agreement", type=float, nargs="+", metavar="TOLERANCE")
    parser.add_argument("--newton", type=policy, nargs="+", default=[DEFAULT_NEWTON],
                        metavar="POLICY")
    parser.add_argument("--no-exudyn", action="store_true",
                        help="the own solver's policies alone")
    parser.add_argument("--couplings", nargs="+", default=[COUPLING], metavar="SCHEME",
                        help=f"coupling schemes (default {COUPLING})")
    parser.add_argument("--course", choices=sorted(COURSES), nargs="+",
                        default=["bump"],
                        help="one or more, each in every round (--agreement: the first)")
    args = parser.parse_args(argv)
    print(f"load before: {os.getloadavg()}")
    statics = static_points()
    solvers = ([] if args.no_exudyn else ["exudyn"]) + args.newton
    if args.agreement:
        agreement(args.course[0], args.speeds, args.end_time, args.agreement, statics,
                  args.newton if len(args.newton) > 1 else ["exudyn"] + args.newton)
        print(f"load after: {os.getloadavg()}")
        return
    figures = {}  # (course, speed, solver, coupling): [(CPU per simulated s, us an evaluation)]
    for round_, course, speed, (solver, coupling) in itertools.product(
            range(args.rounds), args.course, args.speeds,
            itertools.product(solvers, args.couplings)):
        vehicle, result, wall, cpu = run(course, speed, args.end_time, statics, solver,
                                         coupling=coupling)
        simulated = result["time"][-1] - result["time"][0]
        s = vehicle.solver_statistics()
        print(f"{course}, {speed:g} m/s round {round_ + 1} {solver} {coupling}: "
              f"{cpu / simulated:.2f} s CPU "
              f"per simulated s ({wall / simulated:.2f} wall); "
              f"{s['newton_per_pass']:.2f} Newton iterations per solve, "
              f"{s['passes_per_step']:.2f} solves per step, {s['steps']} steps for "
              f"{s['host_steps']}, {s['refused']} refused", flush=True)
        evaluation = None
        if solver != "exudyn":
            evaluation = 1e6 * s["evaluate_s"] / s["evaluations"]
            print(f"    {s['jacobians'] / s['steps']:.2f} Newton matrices (Jacobian "
                  f"and factorization) per step; the solves "
                  f"{s['solve'] / simulated:.2f} s CPU per simulated s; the system's "
                  f"f, g, G {evaluation:.1f} us per evaluation ({s['evaluations']})",
                  flush=True)
            parts = split(s, cpu)
            print("    " + ", ".join(f"{name} {seconds / simulated:.3f}"
                                     for name, seconds in parts.items())
                  + " (s per simulated s)", flush=True)
        figures.setdefault((course, speed, solver, coupling), []).append(
            (cpu / simulated, evaluation))
    print(medians(figures, args.rounds))
    print(f"load after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
