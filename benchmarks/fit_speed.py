"""The cost of the fit's inner simulation: a deflection history through the compiled native
co-simulation in one call (``fmu_components.lab.history``), against the same FMU stepped
through fmpy and against the reference solver (scipy Radau).

    python benchmarks/fit_speed.py [--repeat 20]

Prints microseconds per sample and the ratios, measured in this run; nothing is asserted.
"""

import argparse
import sys
import tempfile
import time
from pathlib import Path


from fmu_components.verification import reference
from fmu_components.export.build import build
from fmu_components.lab.history import simulate
from fmu_components.lab.signals import THESIS_SINES, input_table, secant_rates, sine, time_grid

RUBBER = ("RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion")
STOP, STEP = 2.0, 1e-3


def best_of(repeat, function):
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return min(times)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args(argv)
    from fmpy import simulate_fmu

    print(f"thesis sine of each component, {STOP:g} s at {STEP * 1e3:g} ms "
          f"({int(STOP / STEP) + 1} samples), best of {args.repeat}")
    print(f"{'component':18s} {'history us/sample':>18s} {'fmpy us/sample':>15s} "
          f"{'Radau us/sample':>16s} {'fmpy/history':>13s} {'Radau/history':>14s}")
    with tempfile.TemporaryDirectory() as tmp:
        fmus = build(list(RUBBER), Path(tmp), flavours=("native",))["native"]
        for name in RUBBER:
            t = time_grid(STOP, STEP)
            x = sine(t, *THESIS_SINES[name])
            v = secant_rates(t, x)
            simulate(name, {}, t, x)  # compiled and loaded outside the timing
            ours = best_of(args.repeat, lambda: simulate(name, {}, t, x))
            table = input_table(name, t, x, v)
            fmpy = best_of(max(1, args.repeat // 10), lambda: simulate_fmu(
                str(fmus[name]), stop_time=STOP, output_interval=STEP, input=table))
            radau = best_of(1, lambda: reference.solve_held_rate(name, t, x, v))
            n = len(t)
            print(f"{name:18s} {ours / n * 1e6:18.3f} {fmpy / n * 1e6:15.2f} "
                  f"{radau / n * 1e6:16.0f} {fmpy / ours:13.0f} {radau / ours:14.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
