"""The reduced tracked vehicle: the hull and its six road-wheel stations (the full
vehicle's values, examples/vehicle/layout.py) with the track laid on the ground under the
wheels instead of wrapped round them, in exudyn with the coupling library; beside it the
same vehicle with linear Kelvin elements, and (--reference) its independent monolithic
reference (docs/vehicle.md, "The reduced vehicle and its reference").

    python examples/ground_vehicle.py                          # bump at 5 m/s, 1.5 s
    python examples/ground_vehicle.py --course sine --step 5e-4 --csv
    python examples/ground_vehicle.py --end-time 0.4 --reference   # with the reference

Prints the FMU instances, the CPU and wall seconds per simulated second, and, FMUs
against linear: peak hull and seat acceleration, the seat's ISO 2631-1 Wk-weighted RMS,
the work done on the dampers, the peak tyre force. Plots (and --csv) go to --out.
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from fmu_components.coupling import DEFAULT_SCHEME

import bank_path
from coupling_study import history_error, write_csv
from example_fmus import add_fmu_arguments, fmu_dir_of
from vehicle import layout as lay
from vehicle.course import COURSES
from vehicle.flags import add_run_arguments
from vehicle.ground_exudyn import GroundVehicle, linearisation
from vehicle.model import VehicleError
from vehicle.ride import ride_figures

DEFAULT_STEP = 1e-3
# The track's front under the front wheel's leading edge (layout.Layout's station 1).
FRONT = 0.5 * (lay.STATIONS - 1) * lay.STATION_SPACING + lay.WHEEL_RADIUS
COMPARED = ("hull_vertical_acceleration", "hull_pitch_acceleration", "tyre_force",
            "damper_torque")
CSV_UNITS = {"time": "s", "hull_vertical_acceleration": "m/s2",
             "hull_pitch_acceleration": "rad/s2", "seat_acceleration": "m/s2",
             "tyre_force": "N", "damper_torque": "N.m", "damper_rotation": "rad",
             "tyre_compression": "m"}


def make_course(name, start=None):
    """The course `name` (course.py) in front of the reduced vehicle; `start`, the flat
    run before it (m; the course's own by default)."""
    course = COURSES[name](FRONT)
    if start is not None:
        course.start = start
    return course


def simulate(course, speed, end_time, step, coupling=DEFAULT_SCHEME,
             path=bank_path.DEFAULT_PATH, linear=None, fmu_dir=None):
    """One drive: (vehicle, histories, CPU seconds of the run). The set-up's (the
    static point, the FMUs' instantiation) is in the histories' "setup_cpu"."""
    cpu = time.process_time()
    vehicle = GroundVehicle(course, speed, fmu_dir, linear, coupling, path)
    setup = time.process_time() - cpu
    result = vehicle.run(end_time, step)
    result["costs"] = vehicle.coupling.costs()
    result["setup_cpu"] = setup
    return vehicle, result, time.process_time() - cpu - setup


def csv_columns(result):
    columns = {}
    for name in CSV_UNITS:
        values = result[name]
        if np.ndim(values) == 2:
            stations = ([f"{i}" for i in lay.DAMPED_STATIONS] if values.shape[1] < lay.STATIONS
                        else [f"{i + 1}" for i in range(lay.STATIONS)])
            columns[name] = [(f"{name}_{s}", values[:, k]) for k, s in enumerate(stations)]
        else:
            columns[name] = values
    return columns


def plot(path, course, runs):
    from plotting import plt, save_figure

    panels = (("seat_acceleration", "seat vertical\nacceleration (m/s2)", None),
              ("hull_vertical_acceleration", "hull vertical\nacceleration (m/s2)", None),
              ("hull_pitch_acceleration", "hull pitch\nacceleration (rad/s2)", None),
              ("tyre_force", "tyre force,\nstation 1 (kN)", 0),
              ("damper_torque", "damper torque,\nstation 1 (kN.m)", 0))
    figure, axes = plt.subplots(len(panels), 1, figsize=(9, 11), sharex=True)
    for axis, (key, label, column) in zip(axes, panels):
        scale = 1e-3 if column is not None else 1.0
        for name, result in runs.items():
            values = result[key] if column is None else result[key][:, column]
            axis.plot(result["time"], values * scale, lw=1.0, label=name,
                      ls="--" if name == "linear" else "-")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"Reduced vehicle (track laid on the ground): {course.describe()}",
                      fontsize=9)
    axes[-1].set_xlabel("time (s)")
    save_figure(figure, path)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_run_arguments(parser, end_time=1.5, step=DEFAULT_STEP)
    parser.add_argument("--reference", action="store_true",
                        help="also solve the monolithic reference (Radau with the Model "
                             "Exchange FMUs: minutes per simulated tenth of a second)")
    parser.add_argument("--csv", action="store_true", help="write the histories (SI) as CSV")
    parser.add_argument("--out", type=Path, default=Path("reports") / "ground_vehicle")
    add_fmu_arguments(parser)
    args = parser.parse_args(argv)
    if args.speed <= 0 or args.end_time <= 0 or args.step <= 0:
        parser.error(f"--speed {args.speed:g}, --end-time {args.end_time:g} and --step "
                     f"{args.step:g} must be positive")
    fmu_dir = fmu_dir_of(args)
    args.out.mkdir(parents=True, exist_ok=True)
    course = make_course(args.course)
    wall = time.perf_counter()
    try:
        vehicle, result, cpu = simulate(course, args.speed, args.end_time, args.step,
                                        args.coupling, args.path, fmu_dir=fmu_dir)
    except VehicleError as error:
        sys.exit(f"ground_vehicle: {error}")
    print(f"{vehicle.instances} FMU instances ({'compiled' if vehicle.compiled else 'Python'}"
          f" path, {args.coupling}, host step {args.step * 1e3:g} ms); {course.describe()} at "
          f"{args.speed:g} m/s: {cpu / args.end_time:.2f} s CPU per simulated second "
          f"(the set-up {result['setup_cpu']:.1f} s more); "
          f"{(time.perf_counter() - wall) / args.end_time:.2f} s wall per simulated second, "
          f"set-up included")
    linear = linearisation(fmu_dir)
    _, linear_result, _ = simulate(make_course(args.course), args.speed, args.end_time,
                                   args.step, args.coupling, linear=linear, fmu_dir=fmu_dir)
    runs = {"FMUs": result, "linear": linear_result}
    print(f"linear Kelvin elements: {linear.describe()}")
    print(f"{'':28s} {'FMUs':>10s} {'linear':>10s}")
    figures = [ride_figures(r) for r in (result, linear_result)]
    for key, label, unit in (("peak_hull_acceleration", "peak |hull acceleration|", "m/s2"),
                             ("peak_seat_acceleration", "peak |seat acceleration|", "m/s2"),
                             ("seat_wk_rms", "seat Wk-weighted RMS", "m/s2"),
                             ("total_damper_work", "work on the dampers", "J"),
                             ("peak_tyre_force", "peak tyre force (wheel)", "N")):
        print(f"{label + ' (' + unit + ')':28s} {figures[0][key]:10.4g} {figures[1][key]:10.4g}")
    if args.reference:
        from vehicle.ground_reference import solve_reference
        reference = solve_reference(make_course(args.course), args.speed, args.end_time,
                                    np.arange(0.0, args.end_time + 1e-12, 5e-4), fmu_dir)
        runs["reference"] = reference
        print("co-simulation against the reference (max on a 4 ms grid, % of range): "
              + ", ".join(f"{k.replace('_', ' ')} {history_error(result, reference, k):.3g} %"
                          for k in COMPARED))
    plot(args.out / f"ground_{args.course}.png", course, runs)
    if args.csv:
        for name, run in (("", result), ("_linear", linear_result)):
            write_csv(args.out / f"ground_{args.course}{name}.csv", csv_columns(run), CSV_UNITS)
    print(f"wrote {args.out}/ (plots{' and CSV' if args.csv else ''})")


if __name__ == "__main__":
    main()
