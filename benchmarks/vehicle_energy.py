"""The tracked vehicle's energy audit (docs/vehicle.md, "Runs at speed"): a benchmark, not a
test (a minute or more of CPU per tenth of a second simulated).

    python benchmarks/vehicle_energy.py --speed 3 --end-time 0.4
    python benchmarks/vehicle_energy.py --speed 5 --course sine --end-time 2 --window 0.1

Runs the vehicle from its stored static point and prints, for each window of time, the
work each class of contact force did on the bodies (J: tyres, pins on the ground, sprocket
teeth, idler, roller; the speed hold's), the sprocket's split (the drive's work; the
engagement's own, what remains of the teeth's work after the drive, their springs' change
of stored energy and their dampers' loss: zero for a passive engagement), the work done
on the bushes and dampers (their losses), the largest swing of a wheel's tyre load and
the track tensions' range. A run that stops (a wheel leaving the track) prints where.
"""

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
from scipy.integrate import cumulative_trapezoid

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from fmu_components.coupling import DEFAULT_SCHEME  # noqa: E402

from vehicle.course import COURSES  # noqa: E402
from vehicle.energy import audited_run  # noqa: E402
from vehicle.model import Vehicle, static_points  # noqa: E402

CLASSES = ("tyres", "ground", "sprocket", "idler", "roller", "speed hold", "drive")


def _work(force, deflection):
    """Work done on the elements (J) from their accepted histories, summed."""
    return float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(deflection, axis=0)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speed", type=float, default=3.0)
    parser.add_argument("--course", choices=sorted(COURSES), default="bump")
    parser.add_argument("--end-time", type=float, default=0.4)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--coupling", default=DEFAULT_SCHEME)
    parser.add_argument("--window", type=float, default=0.05, help="s")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")  # the bushes' range warnings round the sprocket
    vehicle = Vehicle(None, args.speed, coupling=args.coupling, statics=static_points())
    vehicle.course = COURSES[args.course](vehicle.layout.sprocket[0] + 0.3)
    vehicle.settle(3.0)
    time, power, result, error = audited_run(vehicle, args.end_time, args.step)
    work = {key: cumulative_trapezoid(power[key], time, initial=0.0) for key in CLASSES}
    work["engagement"] = (work["sprocket"] - work["drive"] + power["sprocket_stored"]
                          - power["sprocket_stored"][0]
                          + cumulative_trapezoid(power["sprocket_damped"], time, initial=0.0))
    columns = [*CLASSES, "engagement"]
    print(f"{args.course}, {args.speed:g} m/s, step {args.step * 1e3:g} ms, {args.coupling}: "
          f"work on the bodies per window (J); bushes, dampers: work done on them (J); "
          f"largest wheel-load swing, tensions (kN)")
    print("window (s)     " + " ".join(f"{c[:10]:>10}" for c in columns)
          + "     bushes   dampers  swing  sprocket tension  idler tension")
    t = result["time"]
    for start in np.arange(0.0, time[-1] - 1e-9, args.window):
        inside = np.flatnonzero((time >= start - 1e-12) & (time <= start + args.window + 1e-12))
        a, b = inside[0], inside[-1]
        rows = (t >= start - 1e-12) & (t <= start + args.window + 1e-12)
        bushes = (_work(result["bush_radial_force"][rows], result["bush_radial_deflection"][rows])
                  + _work(result["bush_torque"][rows], result["bush_angle"][rows]))
        dampers = _work(result["damper_torque"][rows], result["damper_angle"][rows])
        load = result["tyre_force"][rows]
        swing = np.max(load.max(axis=0) - load.min(axis=0)) / 1e3
        sprocket, idler = (result[f"track_tension_{k}"][rows] / 1e3 for k in ("sprocket", "idler"))
        print(f"{start:5.3f}-{start + args.window:5.3f}  "
              + " ".join(f"{work[c][b] - work[c][a]:10.1f}" for c in columns)
              + f" {bushes:10.1f} {dampers:9.1f} {swing:6.2f} {sprocket.min():7.1f} to "
              f"{sprocket.max():5.1f} {idler.min():7.1f} to {idler.max():5.1f}")
    print(f"stopped: {error}" if error else f"ran to {time[-1]:.3f} s")


if __name__ == "__main__":
    main()
