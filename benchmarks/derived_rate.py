"""What deriving the rate in the FMU costs in accuracy (parameter rate_from_deflection,
docs/simulate.md). Prints a Markdown table.

    python benchmarks/derived_rate.py [--fmus DIR]     # DIR: built native FMUs (fmus/)

For each component's thesis sine (fmu_components.lab.signals.THESIS_SINES) at several
communication steps, the FMU is fed the deflection samples with (a) the secant rates the
project's input CSVs carry, (b) no rate, derived by the FMU, (c) rate 0, what a host that
leaves the rate unset gets. Each result is compared with
the independent solve of the continuous input (fmu_components.verification.reference.solve_smooth,
scipy Radau at rtol 1e-10): the largest difference in the first output over the run, in
per cent of that output's peak-to-peak range.
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from fmpy import simulate_fmu

from fmu_components.verification import reference
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import THESIS_SINES, input_table, time_grid

STEPS = (1e-3, 1e-2)
CYCLES = 2


def error_percent(path, name, step, rate):
    """rate: "secant", "derived" or "zero"."""
    mean, amplitude, frequency = THESIS_SINES[name]
    t = time_grid(CYCLES / frequency, step)
    omega = 2 * math.pi * frequency

    def x_of_t(time):
        return mean + amplitude * np.sin(omega * time)

    def v_of_t(time):
        return amplitude * omega * np.cos(omega * time)

    table = input_table(name, t, x_of_t(t))
    derive = rate == "derived"
    if rate == "zero":
        table[COMPONENTS[name].inputs[1].name] = 0.0
    if derive:
        table = table[["time", COMPONENTS[name].inputs[0].name]]
    load = COMPONENTS[name].outputs[0].name
    result = simulate_fmu(str(path), stop_time=t[-1], output_interval=step, input=table,
                          output=[load], start_values={"rate_from_deflection": derive},
                          logger=lambda *args: None)
    expected = reference.solve_smooth(name, t, x_of_t, v_of_t)[load]
    span = expected.max() - expected.min()
    return 100 * np.max(np.abs(result[load] - expected)) / span


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", default="fmus", help="folder of the built native FMUs")
    args = parser.parse_args(argv)
    print("| FMU | input | step | secant rates | derived rate | rate 0 |")
    print("|---|---|---|---|---|---|")
    for name in sorted(COMPONENTS):
        path = Path(args.fmus) / f"{name}.fmu"
        mean, amplitude, frequency = THESIS_SINES[name]
        for step in STEPS:
            errors = [error_percent(path, name, step, rate)
                      for rate in ("secant", "derived", "zero")]
            print(f"| {name} | sine {amplitude:.4g} at {frequency:g} Hz | {step * 1e3:g} ms | "
                  + " | ".join(f"{e:.2f} %" for e in errors) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
