"""The virtual test rig: its cost and its accuracy against the reference solver.

    python benchmarks/rig.py [--fmu fmus/TrackBushRadial.fmu] [--check-points N]

* Cost: the TrackBushRadial sweep of docs/rig.md (preload 0.3 mm; 0.02, 0.05, 0.1, 0.2,
  0.3 mm; 0.1, 0.5, 1, 2, 5, 10, 20 Hz: 35 points) through the Python model, on one
  process and on every core, and through the FMU if one is given. Wall times, and their
  ratio, within this run.
* Accuracy: for the thesis sine of each component (signals.THESIS_SINES) and for the
  sweep's corner points, the rig's periodic steady state against the reference solve
  (reference.py, scipy Radau at rtol 1e-10) two cycles longer, of the same held-rate input
  (the rig's integration) and of the continuous sine (the rig's input convention as well):
  the relative deviation of |K*|, loss angle, energy per cycle and secant stiffness. The
  issue's target is 0.1 %.

Figures are measurements, not pass/fail.
"""

import argparse
import math
import time


from fmu_components.verification import reference


from fmu_components.lab import rig
from fmu_components.lab.harmonics import first_harmonic
from fmu_components.lab.signals import THESIS_SINES

MM = 1e-3
SWEEP = dict(preloads=[0.3 * MM], amplitudes=[0.02 * MM, 0.05 * MM, 0.1 * MM, 0.2 * MM, 0.3 * MM],
             frequencies=[0.1, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0])
QUANTITIES = ("dynamic_stiffness", "loss_angle_deg", "energy_per_cycle", "secant_stiffness")
CHECK_SAMPLES = 100  # per cycle: the reference takes one Radau solve per step


def timed(label, **options):
    started = time.perf_counter()
    rows = rig.run_rig("TrackBushRadial", SWEEP["preloads"], SWEEP["amplitudes"],
                       SWEEP["frequencies"], **options)
    wall = time.perf_counter() - started
    setup = rig.make_setup("TrackBushRadial")
    steps = sum(r.cycles * rig.cycle_samples(setup, r.frequency) for r in rows)
    print(f"{label:34s} {wall:7.2f} s  {len(rows)} points, {steps} steps, "
          f"{wall / steps * 1e6:6.1f} us per step")
    return wall, rows


def deviation(name, preload, amplitude, frequency):
    """The largest relative deviation of the rig's harmonic result from the reference's."""
    setup = rig.make_setup(name)
    row = rig.run_point(setup, preload, amplitude, frequency, samples_per_cycle=CHECK_SAMPLES)
    times, deflection, rates = rig.sine_input(setup, preload, amplitude, frequency,
                                              row.cycles + 2, samples_per_cycle=CHECK_SAMPLES)
    omega = 2 * math.pi * frequency
    load = reference.LOAD_NAMES.get(name, "torque")
    held = reference.solve_held_rate(name, times, deflection, rates, read_after_set=True)[load]
    smooth = reference.solve_smooth(name, times,
                                    lambda t: preload + amplitude * math.sin(omega * t),
                                    lambda t: amplitude * omega * math.cos(omega * t))[load]
    deviations = []
    for solved in (held, smooth):
        expected = first_harmonic(times, deflection, solved, frequency, cycles=1)
        deviations.append({q: abs(getattr(row, q) / getattr(expected, q) - 1) for q in QUANTITIES})
    return deviations, row


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu", help="a built TrackBushRadial FMU to time as well")
    parser.add_argument("--no-check", action="store_true", help="time only")
    args = parser.parse_args(argv)

    print("cost of the 35-point TrackBushRadial sweep (rtol "
          f"{rig.RIG_RTOL:g}, {rig.SAMPLES_PER_CYCLE} samples per cycle)")
    one, rows = timed("Python model, 1 process", processes=1)
    cores = rig._cores()
    every, _ = timed(f"Python model, {cores} processes", processes=cores)
    print(f"{'speed-up on ' + str(cores) + ' processes':34s} {one / every:7.2f}")
    if args.fmu:
        fmu, fmu_rows = timed(f"FMU {args.fmu}, {cores} processes", processes=cores,
                              engine="fmu", fmu=args.fmu)
        same = all(getattr(a, q) == getattr(b, q) for a, b in zip(rows, fmu_rows) for q in QUANTITIES)
        print(f"{'FMU / model wall time':34s} {fmu / every:7.2f}   rows identical: {same}")
    if args.no_check:
        return 0
    print("\ndeviation from the reference solver at periodic steady state (relative), "
          "held-rate input / continuous sine")
    print(f"{'component':18s} {'preload':>9s} {'amplitude':>9s} {'f Hz':>6s} "
          + " ".join(f"{q[:17]:>17s}" for q in QUANTITIES) + f" {'cycles':>6s}")
    points = [(name, *THESIS_SINES[name]) for name in sorted(THESIS_SINES)]
    points += [("TrackBushRadial", 0.3 * MM, a * MM, f) for a in (0.02, 0.3) for f in (0.1, 20.0)]
    worst = [{}, {}]
    for point in points:
        deviations, row = deviation(*point)
        for largest, errors in zip(worst, deviations):
            for q, e in errors.items():
                largest[(point[0], q)] = max(largest.get((point[0], q), 0.0), e)
        print(f"{point[0]:18s} {point[1]:9.4g} {point[2]:9.4g} {point[3]:6.3g} "
              + " ".join(f"{deviations[0][q]:8.1e}/{deviations[1][q]:8.1e}" for q in QUANTITIES)
              + f" {row.cycles:6d}")
    for label, largest in zip(("held-rate input", "continuous sine"), worst):
        (name, quantity), value = max(largest.items(), key=lambda item: item[1])
        print(f"largest deviation from the {label}: {value:.2e} ({name} {quantity})")
        rubber = max(v for (n, _), v in largest.items() if n != "RotaryDamper")
        print(f"  rubber components only: {rubber:.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
