"""The tracked vehicle's energy audit (docs/vehicle.md, "Runs at speed", "The radial bush
never pushes"): a benchmark, not a test (12 to 13 s of CPU for 0.4 s of the bump at 3 and
5 m/s, from the stored static point).

    python benchmarks/vehicle_energy.py --speed 3 --end-time 0.4
    python benchmarks/vehicle_energy.py --speed 5 --course sine --end-time 2 --window 0.1
    python benchmarks/vehicle_energy.py --speed 3 --end-time 0.2 --spectral-radius 1

Runs the vehicle from its stored static point and prints, for each window of time, the
work each class of contact force did on the bodies (J: tyres, pins on the ground, sprocket
teeth, idler, roller; the speed hold's), the sprocket's split (the drive's work; the
engagement's own, what remains of the teeth's work after the drive, their springs' change
of stored energy and their dampers' loss: zero for a passive engagement), the work done
on the bushes and dampers (their losses), the largest swing of a wheel's tyre load and
the track tensions' range. A run that stops (a wheel leaving the track) prints where.
The audit's run is exudyn's (model.Vehicle's solver, not tracked_vehicle.py's default,
the own solver), and says so: it reads the joints' forces as exudyn's last residual of
the accepted pass left them in the joints' kernel, which the own solver's Newton does not
evaluate (its equations are system.c's).
"""

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
from scipy.integrate import cumulative_trapezoid

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]


from vehicle.course import COURSES  # noqa: E402
from vehicle.energy import audited_run, radial_account, window_account  # noqa: E402
from vehicle.model import COUPLING, Vehicle, static_points  # noqa: E402

CLASSES = ("tyres", "ground", "sprocket", "idler", "roller", "speed hold", "drive")
ACCOUNT = ("applied", "fmu", "cut", "rest", "torsion", "dampers", "linear", "stored",
           "balance", "torsion_fmu", "balance_fmu")


def windows(time, window):
    """(start, first step, last step) of each window of the audited steps."""
    for start in np.arange(0.0, time[-1] - 1e-9, window):
        inside = np.flatnonzero((time >= start - 1e-12) & (time <= start + window + 1e-12))
        yield start, inside[0], inside[-1]


def nearest_part(vehicle, result, step, joint):
    """The running-gear part nearest joint `joint` at history row `step`, in the hull's
    frame (the layout's positions at the static point); by a road wheel, the run (top
    or bottom) the joint is on."""
    geo = vehicle.layout
    theta = result["hull_pitch"][step]
    rel = result["pins"][step][joint] - (result["hull_x"][step], result["hull_y"][step])
    c, s = np.cos(theta), np.sin(theta)
    at = np.array([c * rel[0] + s * rel[1], -s * rel[0] + c * rel[1]]) + geo.cg
    parts = {"sprocket": geo.sprocket, "idler": geo.idler, "roller": geo.roller}
    parts.update({f"road wheel {i + 1}": w for i, w in enumerate(geo.wheel_centres)})
    name = min(parts, key=lambda part: np.hypot(*(at - parts[part])))
    if name.startswith("road wheel"):
        return f"{'top' if at[1] > parts[name][1] else 'bottom'} run at {name}"
    return name


def account_table(vehicle, time, power, account, result, window):
    """The account's rows (J per window) and where the cut acted."""
    print("account (J): the work done on the radial bushes as applied, by their FMUs' "
          "loads, what the cut removed, the rest of their difference; on the torsion "
          "bushes (their laws' torque), the dampers (FMUs' torque), the linear dampers; "
          "the stored energy's change; the balance with the loads applied, the torsion "
          "bushes' work by their FMUs' torque, the balance with the FMUs' loads (the "
          "account before the cut); joint-steps cut (%), the lowest law load (kN)")
    print("window (s)       applied       fmu       cut  fmu-rest   torsion   dampers"
          "    linear   dstored   balance  tors fmu  bal(fmu)  cut %  lowest")
    for start, a, b in windows(time, window):
        row = window_account(time, power, account, a, b)
        row["rest"] = row["fmu"] - row["applied"] - row["cut"]
        print(f"{start:5.3f}-{start + window:5.3f} "
              + " ".join(f"{row[key]:9.2f}" for key in ACCOUNT)
              + f" {100 * row['share_cut']:6.2f} {row['lowest'][0] / 1e3:7.3f}")
    whole = radial_account(account)
    law = account["radial_law"]
    load, step, joint = whole["lowest"]
    t = result["time"]
    row = int(np.argmin(np.abs(t - time[step])))
    places = {}
    for s, j in zip(*np.nonzero(law < 0.0)):
        name = nearest_part(vehicle, result, int(np.argmin(np.abs(t - time[s]))), j)
        places[name] = places.get(name, 0) + 1
    total = max(sum(places.values()), 1)
    print(f"the cut: {100 * whole['share_cut']:.2f} % of {law.size} joint-steps "
          f"({np.mean(np.any(law < 0.0, axis=0)) * law.shape[1]:.0f} of {law.shape[1]} "
          f"joints at least once); it removed {whole['cut']:.2f} J of the radial bushes' "
          f"{whole['fmu']:.2f} J (FMUs' loads; applied {whole['applied']:.2f} J); lowest "
          f"law load {load / 1e3:.3f} kN at joint {joint}, t = {time[step]:.4f} s, nearest "
          f"{nearest_part(vehicle, result, row, joint)}")
    print("joint-steps cut, by the nearest part: " + ", ".join(
        f"{name} {100 * count / total:.0f} %" for name, count in
        sorted(places.items(), key=lambda item: -item[1])))
    if account["evaluated_at_record"]:
        print(f"({account['evaluated_at_record']} record(s) evaluated the joints at the "
              f"record, the laws then current)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speed", type=float, default=3.0)
    parser.add_argument("--course", choices=sorted(COURSES), default="bump")
    parser.add_argument("--end-time", type=float, default=0.4)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--coupling", default=COUPLING)
    parser.add_argument("--window", type=float, default=0.05, help="s")
    parser.add_argument("--spectral-radius", type=float, default=None,
                        help="generalized-alpha's at infinite frequency (default the "
                             "vehicle's, model.SPECTRAL_RADIUS; 1 has no numerical damping)")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")  # the bushes' range warnings round the sprocket
    vehicle = Vehicle(None, args.speed, coupling=args.coupling, statics=static_points())
    vehicle.course = COURSES[args.course](vehicle.layout.sprocket[0] + 0.3)
    vehicle.settle(3.0)
    if args.spectral_radius is not None:
        vehicle.spectral_radius = args.spectral_radius
    time, power, account, result, error = audited_run(vehicle, args.end_time, args.step)
    work = {key: cumulative_trapezoid(power[key], time, initial=0.0) for key in CLASSES}
    work["engagement"] = (work["sprocket"] - work["drive"] + power["sprocket_stored"]
                          - power["sprocket_stored"][0]
                          + cumulative_trapezoid(power["sprocket_damped"], time, initial=0.0))
    columns = [*CLASSES, "engagement"]
    print(f"{args.course}, {args.speed:g} m/s, step {args.step * 1e3:g} ms, {args.coupling}, "
          f"{vehicle.solver}'s solver (the audit reads the joints' forces of its residual): "
          f"work on the bodies per window (J); bushes (as applied), dampers: work done on "
          f"them (J); "
          f"largest wheel-load swing, tensions (kN)")
    print("window (s)     " + " ".join(f"{c[:10]:>10}" for c in columns)
          + "     bushes   dampers  swing  sprocket tension  idler tension")
    t = result["time"]
    for start, a, b in windows(time, args.window):
        rows = (t >= start - 1e-12) & (t <= start + args.window + 1e-12)
        row = window_account(time, power, account, a, b)
        bushes, dampers = row["applied"] + row["torsion"], row["dampers"]
        load = result["tyre_force"][rows]
        swing = np.max(load.max(axis=0) - load.min(axis=0)) / 1e3
        sprocket, idler = (result[f"track_tension_{k}"][rows] / 1e3 for k in ("sprocket", "idler"))
        print(f"{start:5.3f}-{start + args.window:5.3f}  "
              + " ".join(f"{work[c][b] - work[c][a]:10.1f}" for c in columns)
              + f" {bushes:10.1f} {dampers:9.1f} {swing:6.2f} {sprocket.min():7.1f} to "
              f"{sprocket.max():5.1f} {idler.min():7.1f} to {idler.max():5.1f}")
    account_table(vehicle, time, power, account, result, args.window)
    print(f"stopped: {error}" if error else f"ran to {time[-1]:.3f} s")


if __name__ == "__main__":
    main()
