"""Model Exchange figures: accuracy against the continuous-input solve and cost against
co-simulation on the verification cases, and the directional derivatives against finite
differences. Prints Markdown tables.

    python benchmarks/model_exchange.py                  # every smooth case (minutes)
    python benchmarks/model_exchange.py --case "*8Hz"    # some

* ME: the native FMU on fmpy's CVode (rtol 1e-6, nominals used) with continuous inputs
  (tests/me_host.py), against ``reference.solve_smooth`` of the same x(t), v(t): the largest
  error of any output in % of its peak-to-peak range; wall time per simulated second.
* CS: the same FMU in fmpy at the case's step with secant rates (the verification's run):
  wall time per simulated second, for comparison.
* Directional derivatives: at random points (both flavours of every kink), in both
  interfaces, the largest relative difference to central finite differences where the
  function is smooth there.
"""

import argparse
import fnmatch
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "src")]

from fmpy import simulate_fmu  # noqa: E402

from fmu_components.verification import cases, reference  # noqa: E402
from fmu_components.runtime.catalog import COMPONENTS  # noqa: E402
from me_host import (ModelExchangeRun, compare_directional_derivatives,  # noqa: E402
                     continuous_input)


def accuracy(fmus, patterns):
    rows = []
    for case in cases.CASES:
        if case.test in ("IV", "sweep") and not patterns:
            continue
        if patterns and not any(fnmatch.fnmatch(case.key, p) for p in patterns):
            continue
        x_of, v_of = continuous_input(case)
        times = case.times()
        started = time.perf_counter()
        outputs = ModelExchangeRun(fmus[case.fmu], x_of, v_of).run(times)
        me_wall = time.perf_counter() - started
        inputs, _, options = cases.read(case)
        started = time.perf_counter()
        simulate_fmu(str(fmus[case.fmu]), stop_time=options["StopTime"],
                     output_interval=options["StepSize"], input=inputs)
        cs_wall = time.perf_counter() - started
        expected = reference.solve_smooth(case.fmu, times, x_of, v_of)
        names = [o.name for o in COMPONENTS[case.fmu].outputs]
        errors = {k: float(np.max(np.abs(outputs[:, names.index(k)] - v)) / (np.ptp(v) or 1.0) * 100)
                  for k, v in expected.items()}
        worst = max(errors, key=errors.get)
        rows.append((case.key, errors[worst], worst, me_wall / times[-1], cs_wall / times[-1]))
        print(f"| {case.key} | {errors[worst]:.4f} | {worst} | {me_wall / times[-1]:.4f} | "
              f"{cs_wall / times[-1]:.4f} |", flush=True)
    return rows


def directional(fmus, points):
    rows = []
    for name in sorted(COMPONENTS):
        for interface in ("ModelExchange", "CoSimulation"):
            compared, kinks, worst = compare_directional_derivatives(fmus[name], interface,
                                                                     points, seed=5)
            rows.append((name, interface, compared, kinks, worst))
            print(f"| {name} | {interface} | {compared} | {kinks} | {worst:.2e} |", flush=True)
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus")
    parser.add_argument("--case", nargs="*", default=[], help="glob(s) of case keys")
    parser.add_argument("--points", type=int, default=200, help="random points per FMU")
    args = parser.parse_args(argv)
    fmus = {name: args.fmus / f"{name}.fmu" for name in COMPONENTS}
    print("## Model Exchange against the continuous-input solve\n")
    print("| case | largest error (% of peak-to-peak) | output | ME wall / simulated s | "
          "CS wall / simulated s |\n|---|---|---|---|---|")
    accuracy(fmus, args.case)
    print("\n## Directional derivatives against central differences\n")
    print("| FMU | interface | entries compared | entries at a kink (not compared) | "
          "largest difference, relative to the largest entry |\n|---|---|---|---|---|")
    directional(fmus, args.points)


if __name__ == "__main__":
    main()
