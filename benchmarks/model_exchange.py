"""Model Exchange figures: accuracy against the continuous-input solve and cost against
co-simulation on the validation cases, and the directional derivatives against finite
differences. Prints Markdown tables.

    python benchmarks/model_exchange.py                  # every smooth case (minutes)
    python benchmarks/model_exchange.py --case "*8Hz"    # some

* ME: the native FMU on fmpy's CVode (rtol 1e-6, nominals used) with continuous inputs
  (tests/me_host.py), against ``reference.solve_smooth`` of the same x(t), v(t): the largest
  error of any output in % of its peak-to-peak range; wall time per simulated second.
* CS: the same FMU in fmpy at the case's step with secant rates (the validation's run):
  wall time per simulated second, for comparison.
* Directional derivatives: at random points (both flavours of every kink), in both
  interfaces, the largest relative difference to central finite differences where the
  function is smooth there.
"""

import argparse
import fnmatch
import math
import random
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "src")]

from fmpy import simulate_fmu  # noqa: E402

from fmu_components import cases, reference  # noqa: E402
from fmu_components.runtime.catalog import COMPONENTS  # noqa: E402
from me_host import (Instance, ModelExchangeRun, central_differences,  # noqa: E402
                     continuous_input, evaluate, random_points)


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
    rng = random.Random(5)
    rows = []
    for name in sorted(COMPONENTS):
        for interface in ("ModelExchange", "CoSimulation"):
            instance = Instance(fmus[name], interface)
            fmu = instance.fmu
            knowns, unknowns = instance.knowns(), instance.unknowns()
            x, v, _ = next(random_points(name, 1, rng))
            if interface == "CoSimulation":
                instance.runner.initialize(x, v)
                for k in range(300):
                    instance.runner.step(x + 0.5 * v * 1e-3 * math.sin(k / 30),
                                         v * math.cos(k / 30), 1e-3)
            else:
                fmu.setupExperiment(startTime=0.0)
                fmu.enterInitializationMode()
                fmu.setReal(knowns[:2], [x, v])
                fmu.exitInitializationMode()
                fmu.newDiscreteStates()
                fmu.enterContinuousTimeMode()
            nominals = COMPONENTS[name].build_model(COMPONENTS[name].default_parameters()).nominals
            worst, compared, kinks = 0.0, 0, 0
            for x, v, states in random_points(name, points, rng):
                if interface == "CoSimulation" and name == "RotaryDamper":
                    x = fmu.getReal([knowns[0]])[0] + rng.uniform(-5e-3, 5e-3)
                point = {knowns[0]: x, knowns[1]: v}
                if interface == "ModelExchange":
                    point.update(zip(knowns[2:], states))
                scale = {knowns[0]: abs(x) + 1e-3, knowns[1]: abs(v)}
                scale.update({vr: abs(point[vr]) + n for vr, n in zip(knowns[2:], nominals)})
                instance.steps = {vr: 1e-6 * scale[vr] for vr in knowns}
                for known in knowns:
                    base = evaluate(instance, point, knowns, unknowns)
                    analytic = np.array(fmu.getDirectionalDerivative(unknowns, [known], [1.0]))
                    up, down = central_differences(instance, point, knowns, unknowns, {known: 1.0})
                    step = instance.steps[known]
                    numeric = (up - down) / (2 * step)
                    smooth = np.abs((up - base) - (base - down)) / step <= 1e-4 * np.abs(numeric) + 1e-9 * (
                        np.max(np.abs(numeric)) + 1e-300)
                    kinks += int(np.sum(~smooth))
                    big = np.max(np.abs(numeric)) + 1e-300
                    for i in np.flatnonzero(smooth):
                        worst = max(worst, abs(analytic[i] - numeric[i]) / max(abs(numeric[i]), 1e-6 * big))
                        compared += 1
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
          "largest relative difference |\n|---|---|---|---|---|")
    directional(fmus, args.points)


if __name__ == "__main__":
    main()
