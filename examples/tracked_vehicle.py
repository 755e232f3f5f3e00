"""One side of a Warrior-class tracked vehicle in the pitch plane, in the exudyn multibody
host, every running-gear part an FMU: 12 RoadWheelTyre (two per wheel), 3 RotaryDamper
(stations 1, 2 and 6, section 9.0), a TrackBushRadial and a TrackBushTorsion at each of
the 80 joints of the closed track loop, coupled by fmu_components.coupling: by default
its compiled path (one bank of all 175 instances, the load laws in exudyn's compiled
symbolic functions; vehicle/compiled.py), or its Python path (--path python, the readable
reference; the same numbers). By default the time integration is the vehicle's own
solver (exudyn's generalized-alpha in C, no exudyn in the time loop: vehicle/own_host.py);
--solver exudyn integrates in exudyn, and is needed where the own solver cannot run
(--path python, --joints connectors, a scheme the bank lacks; the --linear vehicle's run
is exudyn's, and says so). See docs/vehicle.md for the model, its values and its present
state.

    python examples/tracked_vehicle.py --course bump --speed 3 --end-time 2
    python examples/tracked_vehicle.py --course random --csv --animate
    python examples/tracked_vehicle.py --course sine --linear   # and the Kelvin vehicle
    python examples/tracked_vehicle.py --solver exudyn          # the time loop in exudyn
    python examples/tracked_vehicle.py --path python --solver exudyn   # the Python path

Plots, CSV and the animation go to reports/tracked_vehicle/ (or --out).
"""

import argparse
import sys
import time
import warnings
from pathlib import Path


import bank_path
from coupling_study import write_csv
from vehicle import outputs
from vehicle.course import COURSES
from vehicle.flags import add_run_arguments
from vehicle.model import (COUPLING, DEFAULT_JOINTS, JOINTS, NEWTON_TOLERANCE, SPECTRAL_RADIUS,
                           Linear, Vehicle, VehicleError, static_points)
from vehicle.own_host import DEFAULT_NEWTON, NEWTON

DEFAULT_STEP = 1e-3  # s
SOLVERS = ("own", "exudyn")
SOLVER_NAMES = {"own": "own (no exudyn in the time loop)", "exudyn": "exudyn's"}
DEFAULT_SOLVER = "own"  # the vehicle's own solver where it can run (own_refusal)


def own_refusal(path=bank_path.DEFAULT_PATH, coupling=COUPLING, joints=DEFAULT_JOINTS,
                linear=None):
    """Why the own solver cannot run a vehicle of these settings, naming the flag that
    made it so; None where it can. It runs the coupling's compiled path (the bank) with
    the track's joints as one object."""
    if linear is not None:
        return ("no bank for the linear vehicle's Kelvin elements (the own solver runs the "
                "FMUs' compiled path)")
    if joints != "kernel":
        return ("--joints connectors: the own solver takes the track's joints as one "
                "object (--joints kernel)")
    if not bank_path.compiled(path, coupling):
        taken = ("--path python" if path == "python" else
                 f"--coupling {coupling} (a scheme the bank does not have)"
                 if coupling not in bank_path.SCHEME_CODES else "no C compiler found")
        return f"{taken}: the own solver runs the coupling's compiled path"
    return None


def simulate(course_name, speed, end_time, step, coupling=COUPLING, linear=None,
             statics=None, settle_time=3.0, fmu_dir=None, path=bank_path.DEFAULT_PATH,
             contacts=None, joints=DEFAULT_JOINTS, spectral_radius=SPECTRAL_RADIUS,
             newton_tolerance=NEWTON_TOLERANCE, solver=DEFAULT_SOLVER, own_newton=None):
    """One run; returns (vehicle, histories, wall seconds, CPU seconds) of the run proper
    (the settling to the static point, stored after the first run, and the set-up,
    Vehicle.prepare, excluded). contacts: the contacts' kernel, "compiled" or "numpy"
    (default: compiled where it builds; vehicle/contacts_kernel.py). joints: the track's
    joints as one object with their Jacobian ("kernel", vehicle/joints.py) or as two
    exudyn connectors each ("connectors"). spectral_radius: generalized-alpha's, at
    infinite frequency (model.SPECTRAL_RADIUS). newton_tolerance: exudyn's Newton's
    absolute tolerance (model.NEWTON_TOLERANCE). solver: "own" (default: the compiled
    path on the vehicle's own solver, no exudyn in the time loop: vehicle/own_host.py; a
    VehicleError naming why where it cannot run: own_refusal), or "exudyn".
    own_newton: the own solver's Newton policy (own_host.NEWTON; None: its default)."""
    if solver not in SOLVERS:
        raise ValueError(f"solver {solver!r}: one of {', '.join(SOLVERS)}")
    refusal = own_refusal(path, coupling, joints, linear) if solver == "own" else None
    if refusal:
        raise VehicleError(f"{refusal}; solver='exudyn' (--solver exudyn) runs it in exudyn")
    statics = statics or static_points(fmu_dir)
    vehicle = Vehicle(None, speed, fmu_dir, linear, coupling, statics, path, joints)
    vehicle.spectral_radius = spectral_radius
    vehicle.newton_tolerance = newton_tolerance
    vehicle.solver = solver
    vehicle.own_newton = own_newton
    if contacts:
        vehicle.contacts.use(contacts)
    vehicle.course = COURSES[course_name](vehicle.layout.sprocket[0] + 0.3)
    if settle_time > 0:
        vehicle.settle(settle_time)
    vehicle.prepare()
    wall, cpu = time.perf_counter(), time.process_time()
    result = vehicle.run(end_time, step, settle=False)
    return vehicle, result, time.perf_counter() - wall, time.process_time() - cpu


def add_solver_arguments(parser):
    """The settings a run takes on either solver: generalized-alpha's spectral radius,
    Newton's absolute tolerance (check them with check_solver_arguments)."""
    parser.add_argument("--spectral-radius", type=float, default=SPECTRAL_RADIUS,
                        help="generalized-alpha's spectral radius at infinite frequency, "
                             f"0 to 1 (default {SPECTRAL_RADIUS:g}: damps the links' "
                             "in-phase turning the 1 ms step does not resolve; exudyn's own "
                             "default is 0.9)")
    parser.add_argument("--newton-tolerance", type=float, default=NEWTON_TOLERANCE,
                        help="Newton (either solver's) stops where its residual's norm is "
                             f"below this (default {NEWTON_TOLERANCE:g}; 1 takes about 10 %% "
                             "fewer iterations and moves the hull's accelerations by "
                             "0.004 %% of their range: docs/vehicle.md, What remains 2)")


def check_solver_arguments(parser, args):
    """Refuse the settings add_solver_arguments parsed where they make no run."""
    if not 0.0 <= args.spectral_radius <= 1.0:
        parser.error(f"--spectral-radius {args.spectral_radius:g}: give a value from 0 "
                     "(most damping) to 1 (none)")
    if not args.newton_tolerance > 0.0:
        parser.error(f"--newton-tolerance {args.newton_tolerance:g}: give a value above 0 "
                     f"(default {NEWTON_TOLERANCE:g})")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    # 3 m/s: the default run finishes (at 5 m/s runs stop within 2 s; docs/vehicle.md)
    add_run_arguments(parser, end_time=1.0, step=DEFAULT_STEP, speed=3.0,
                      coupling=COUPLING)
    parser.add_argument("--settle-time", type=float, default=3.0,
                        help="longest damped settling to the static point, s (solved once, "
                             "then stored; 0: start from the laid-out geometry)")
    parser.add_argument("--linear", action="store_true",
                        help="also run the vehicle with linear Kelvin elements")
    parser.add_argument("--csv", action="store_true", help="write the histories (SI) as CSV")
    parser.add_argument("--animate", action="store_true", help="write an animated GIF")
    parser.add_argument("--fmu-dir", type=Path, help="default: fmus/")
    parser.add_argument("--contacts", choices=("compiled", "numpy"),
                        help="the contacts' kernel: C compiled on first use (the default "
                             "where gcc is found) or numpy (the readable reference)")
    parser.add_argument("--joints", choices=JOINTS, default=DEFAULT_JOINTS,
                        help="the track's joints: one object with their analytic Jacobian "
                             f"(kernel) or two exudyn connectors each (default "
                             f"{DEFAULT_JOINTS})")
    add_solver_arguments(parser)
    parser.add_argument("--solver", choices=SOLVERS, default=DEFAULT_SOLVER,
                        help="the time integration: the vehicle's own solver, exudyn's "
                             "generalized-alpha scheme in C with no exudyn in the time loop "
                             "(default; the compiled path with the joints' kernel only: "
                             "other settings are refused naming --solver exudyn), or "
                             "exudyn's (docs/vehicle.md, The vehicle on its own solver)")
    parser.add_argument("--own-newton", choices=tuple(NEWTON),
                        help=f"the own solver's Newton policy (default {DEFAULT_NEWTON}; "
                             "docs/vehicle.md, The vehicle on its own solver)")
    parser.add_argument("--out", type=Path, default=Path("reports") / "tracked_vehicle")
    args = parser.parse_args(argv)
    if args.speed < 0 or args.end_time <= 0 or args.step <= 0:
        parser.error("--speed must be >= 0, --end-time and --step > 0")
    check_solver_arguments(parser, args)
    refusal = (own_refusal(args.path, args.coupling, args.joints)
               if args.solver == "own" else None)
    if refusal:
        parser.error(f"{refusal}; add --solver exudyn to run it in exudyn")
    args.out.mkdir(parents=True, exist_ok=True)
    warnings.simplefilter("once")
    statics = static_points(args.fmu_dir)
    runs = {}
    try:
        vehicle, result, wall, cpu = simulate(args.course, args.speed, args.end_time,
                                              args.step, args.coupling, None, statics,
                                              args.settle_time, args.fmu_dir, args.path,
                                              args.contacts, args.joints,
                                              args.spectral_radius,
                                              args.newton_tolerance, args.solver,
                                              args.own_newton)
        runs["FMUs"] = result
        if args.linear:
            linear = Linear(statics, args.fmu_dir)
            print(f"Kelvin equivalents: {linear.describe()}")
            print(f"the linear vehicle on exudyn's solver: {own_refusal(linear=linear)}")
            runs["linear"] = simulate(args.course, args.speed, args.end_time, args.step,
                                      args.coupling, linear, statics, args.settle_time,
                                      args.fmu_dir, contacts=args.contacts,
                                      joints=args.joints,
                                      spectral_radius=args.spectral_radius,
                                      newton_tolerance=args.newton_tolerance,
                                      solver="exudyn")[1]
    except VehicleError as error:
        sys.exit(f"tracked_vehicle: {error}")
    simulated = result["time"][-1] - result["time"][0]
    name = f"{args.course}_{args.speed:g}mps"
    print(f"{vehicle.instances} FMU instances ({vehicle.links} links), course: "
          f"{vehicle.course.describe()}; {args.speed:g} m/s, host step {args.step * 1e3:g} ms, "
          f"coupling {args.coupling}, {'compiled' if vehicle.compiled else 'Python'} path, "
          f"{vehicle.contacts.kernel} contacts, joints by "
          f"{vehicle.joints.kernel + ' kernel' if vehicle.joints else 'connectors'}, "
          f"spectral radius {vehicle.spectral_radius:g}, Newton tolerance "
          f"{vehicle.newton_tolerance:g}, solver {SOLVER_NAMES[vehicle.solver]}")
    print(f"{simulated:.3f} s simulated in {wall:.1f} s wall, {cpu:.1f} s CPU: "
          f"{wall / simulated:.1f} s wall and {cpu / simulated:.1f} s CPU per simulated "
          f"second")
    solver = vehicle.solver_statistics()
    print(f"{vehicle.solver}: {solver['newton_per_pass']:.1f} Newton iterations per solve, "
          f"{solver['passes_per_step']:.2f} solves per host step, "
          f"{solver['steps']} steps for the {solver['host_steps']} asked (more where "
          f"shortened), {solver['refused']} solutions refused (they jumped)")
    for key, label, unit, scale in outputs.FIGURE_LABELS:
        values = "  ".join(f"{model}: {outputs.figures(r)[key] * scale:.3g} {unit}"
                           for model, r in runs.items())
        print(f"  {label}: {values}")
    for model, run in runs.items():
        if run["across_track"]:
            print(f"  {model}: {run['across_track']}")
    written = [args.out / f"{name}.png", args.out / f"{name}_shapes.png"]
    outputs.plot_histories(written[0], result, runs.get("linear"),
                           f"Tracked vehicle, {vehicle.course.describe()}, {args.speed:g} m/s")
    outputs.plot_shapes(written[1], result, vehicle.course)
    if args.csv:
        for model, run in runs.items():
            path = args.out / f"{name}{'' if model == 'FMUs' else '_linear'}.csv"
            write_csv(path, outputs.csv_columns(run), outputs.CSV_UNITS)
            written.append(path)
    if args.animate:
        written.append(args.out / f"{name}.gif")
        outputs.animate(written[-1], result, vehicle.course)
    print("wrote " + ", ".join(str(p) for p in written))


if __name__ == "__main__":
    main()
