"""Synthetic measurements for checking the fit: a rubber component with parameter values
other than the thesis's, driven through the thesis's test programme (``cases``), solved by
the independent reference solver (``reference.solve_smooth``: the continuous input, scipy
Radau at rtol 1e-10, no code shared with the FMUs) and sampled with Gaussian noise.
"""

from pathlib import Path

import numpy as np

from . import reference
from ..lab.fit import MAXWELL, maxwell_quantity
from ..lab.measured import History
from ..runtime.catalog import component_definition

SAMPLES_PER_CYCLE = 200
DIFFERENCE_STEP = 1e-7  # s, central difference of the programme's path for its rate


def scaled(component, factors, structure="final"):
    """The thesis values with each name's factor applied; a factor for 'k', 'c' or 'xi'
    scales that quantity in every Maxwell element."""
    values = dict(component_definition(component, structure).default_parameters())
    for name, factor in factors.items():
        targets = [n for n in values if maxwell_quantity(n) == name] if name in MAXWELL else [name]
        for target in targets:
            values[target] *= factor
    return values


def case_times(case):
    """The case's time grid, refined to SAMPLES_PER_CYCLE samples per cycle of a sine."""
    frequency = _frequency(case)
    step = case.step if frequency is None else min(case.step, 1.0 / frequency / SAMPLES_PER_CYCLE)
    n = int(round(case.stop_time / step))
    return np.arange(n + 1) * step


def _frequency(case):
    if case.test == "III":
        return float(case.name.split("_")[-1].rstrip("Hz"))
    if case.test in ("I", "II"):
        return 1.0
    return None


def measure(case, values, noise=0.005, seed=0, structure="final"):
    """A History of a programme case under these parameter values (see measure_path) and
    its noise-free force."""
    return measure_path(case.fmu, f"{case.name}.csv", case_times(case), case.path, values,
                        noise, seed, structure)


def measure_path(component, label, times, path, values, noise=0.005, seed=0,
                 structure="final"):
    """A History of the deflection path(t) sampled at `times`: the reference solution plus
    Gaussian noise of standard deviation `noise` times its peak-to-peak force; and the
    noise-free force."""
    def rate(t):
        return (path(t + DIFFERENCE_STEP) - path(t - DIFFERENCE_STEP)) / (2 * DIFFERENCE_STEP)

    solution = reference.solve_smooth(component, times, path, rate, structure,
                                      spec=reference.spec_from_parameters(component, values, structure))
    force = solution[reference.LOAD_NAMES[component]]
    generator = np.random.default_rng(seed)
    noisy = force + generator.normal(0.0, noise * np.ptp(force), len(force))
    return History(Path(label), times, path(times), noisy), force


def write_history(path, history):
    """A DATA.csv (time,deflection,force)."""
    np.savetxt(path, np.column_stack([history.times, history.deflection, history.force]),
               delimiter=",", header="time,deflection,force", comments="", fmt="%.17g")
    return path


def peak_to_peak_error(predicted, truth):
    """Max |predicted - truth| in % of the truth's peak-to-peak."""
    return float(np.max(np.abs(np.asarray(predicted) - truth)) / np.ptp(truth) * 100.0)

