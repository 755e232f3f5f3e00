"""Input histories for the FMUs: deflection samples on the communication grid with the
rate each step should hold.

The FMUs hold the rate over a step and move the deflection with it (spec section 4). A
host that knows the deflection at the end of the step should feed the secant rate
(x[k+1] - x[k]) / h: the deflection then follows the straight path through the samples
and the only error left is that of the path itself, O(h^2). Feeding the rate at the start
of the step instead lags by half a step: at 1 ms that costs about 2.5 % of the peak-to-peak
force at 20 Hz (see README). Every history here uses secant rates. The command that writes
one is ``fmu-components signal`` (``commands/signal.py``).
"""

import csv
import math
import sys

import numpy as np

from ..errors import UsageError
from ..runtime.catalog import COMPONENTS
from ..runtime.units import RAD_PER_DEG, UNITS

# The standard test input of each component, a sine inside the range the thesis measured:
# (mean, amplitude, frequency in Hz), SI units; the damper's is test A (Table 11.2-1).
THESIS_SINES = {
    "RoadWheelTyre": (3.5e-3, 1e-3, 1.0),
    "TrackBushRadial": (0.3e-3, 0.1e-3, 1.0),
    "TrackBushTorsion": (math.radians(10.0), math.radians(5.0), 1.0),
    "RotaryDamper": (0.0, 0.21, 0.75),
}


def time_grid(stop_time, step):
    n = int(round(stop_time / step))
    return np.arange(n + 1) * step


def secant_rates(times, deflection):
    """Rate held over each step; the last sample repeats the last step's rate."""
    rates = np.diff(deflection) / np.diff(times)
    return np.append(rates, rates[-1] if len(rates) else 0.0)


def sine(times, mean, amplitude, frequency, phase=0.0, sin=None):
    """mean + amplitude sin(2 pi frequency t + phase) at `times`; with `sin` a function that
    makes an expression tree's sine and symbols for the rest, the tree that the SSP rig
    driver's C is printed from (lab/rig_package.py): one definition for both."""
    if sin is None:
        sin, times = np.sin, np.asarray(times)
    return mean + amplitude * sin(2 * math.pi * frequency * times + phase)


def thesis_sine(name, stop_time, step, phase=0.0):
    """The THESIS_SINES input of a component: times, deflection and secant rates."""
    mean, amplitude, frequency = THESIS_SINES[name]
    t = time_grid(stop_time, step)
    x = sine(t, mean, amplitude, frequency, phase)
    return t, x, secant_rates(t, x)


def dual_sine(times, mean, components):
    """mean + sum of amplitude*sin(2*pi*f*t) over components [(amplitude, f)]."""
    t = np.asarray(times)
    return mean + sum(a * np.sin(2 * math.pi * f * t) for a, f in components)


# The torsion bush's dual sine of section 5.8 (Fig. 5.8-1): (mean, [(amplitude, frequency)])
# in rad and Hz, 10 deg + 7.5 deg at 0.1 Hz + 0.75 deg at 1.5 Hz, sampled every 5 ms for
# 20 s; the second half, settled, is the part shown and analysed.
DUAL_SINE = (10.0 * RAD_PER_DEG, [(7.5 * RAD_PER_DEG, 0.1), (0.75 * RAD_PER_DEG, 1.5)])
DUAL_SINE_STEP, DUAL_SINE_STOP, DUAL_SINE_SHOWN = 5e-3, 20.0, 10.0  # s


def ramp_and_hold(times, start, end, ramp_time):
    """A straight ramp from start at time 0 to end over ramp_time, then hold."""
    fraction = np.clip(np.asarray(times) / ramp_time, 0.0, 1.0)
    return start + (end - start) * fraction


def piecewise_linear_rate(times, knot_times, knot_rates, start=0.0):
    """The deflection whose rate runs straight between the knots [(t, rate)]: plateaus
    joined by constant-acceleration ramps, integrated exactly (a quadratic between knots)."""
    knot_times = np.asarray(knot_times, dtype=float)
    knot_rates = np.asarray(knot_rates, dtype=float)
    spans = np.diff(knot_times)
    mean_rates = (knot_rates[:-1] + knot_rates[1:]) / 2
    at_knots = start + np.concatenate([[0.0], np.cumsum(spans * mean_rates)])
    t = np.asarray(times, dtype=float)
    i = np.clip(np.searchsorted(knot_times, t, side="right") - 1, 0, len(spans) - 1)
    s = t - knot_times[i]
    acceleration = np.diff(knot_rates)[i] / spans[i]
    return at_knots[i] + knot_rates[i] * s + 0.5 * acceleration * s ** 2


def input_table(fmu_name, times, deflection, rate=None):
    """Structured array (time, deflection input, rate input) named as the FMU's inputs."""
    deflection_name, rate_name = (v.name for v in COMPONENTS[fmu_name].inputs)
    times = np.asarray(times, dtype=float)
    deflection = np.asarray(deflection, dtype=float)
    rate = secant_rates(times, deflection) if rate is None else np.asarray(rate, dtype=float)
    table = np.zeros(len(times), dtype=[("time", float), (deflection_name, float), (rate_name, float)])
    table["time"], table[deflection_name], table[rate_name] = times, deflection, rate
    return table


def write_csv(table, file):
    """CSV with quoted headers, as fmpy and the FMI cross-check files expect."""
    writer = csv.writer(file, quoting=csv.QUOTE_NONNUMERIC, lineterminator="\n")
    writer.writerow(table.dtype.names)
    for row in table:
        writer.writerow([float(value) for value in row])


def describe(times, deflection, display_factor=1.0, unit=""):
    """What a deflection history is, in a few words for a plot's title: constant, a step and
    hold, a ramp, a single bump, a sine (its frequency, mean and amplitude), or else its
    range and how often it turns. Values shown in the display unit (factor, unit)."""
    t, x = np.asarray(times, dtype=float), np.asarray(deflection, dtype=float)
    span = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    low, high = float(x.min()), float(x.max())
    size = high - low

    def v(value):
        value = 0.0 if abs(value) <= 1e-9 * size else value  # round-off of a zero mean
        return f"{value * display_factor:.4g} {unit}".strip()

    if len(x) < 3 or size <= 1e-12 * max(abs(high), abs(low), 1e-300):
        return f"constant at {v(x[0])}"
    moves = np.diff(x)
    still = np.abs(moves) <= 1e-9 * size
    steps = np.sign(moves[~still])
    turns = int(np.count_nonzero(np.diff(steps) != 0))
    moving_until = float(t[1:][~still][-1])  # the end of the last movement
    held = float(t[-1]) - moving_until
    if turns == 0 and held >= 0.5 * span:
        return (f"step and hold: {v(x[0])} to {v(x[-1])} in {moving_until - t[0]:.3g} s, "
                f"held {held:.3g} s")
    if turns == 0:
        return f"ramp: {v(x[0])} to {v(x[-1])} over {span:.3g} s"
    if turns == 1:
        peak = high if abs(high - x[0]) >= abs(low - x[0]) else low
        return f"single bump: {v(x[0])} to {v(peak)} and back to {v(x[-1])} over {span:.3g} s"
    # A sine: a least-squares fit at the main frequency that leaves little unexplained.
    uniform = np.linspace(t[0], t[-1], len(t))
    resampled = np.interp(uniform, t, x)
    spectrum = np.abs(np.fft.rfft(resampled[:-1] - resampled.mean()))
    cycles = 1 + int(np.argmax(spectrum[1:]))  # whole cycles over the record, roughly

    def fit(frequency):
        omega = 2 * math.pi * frequency
        basis = np.column_stack([np.ones_like(t), np.sin(omega * t), np.cos(omega * t)])
        coefficients, *_ = np.linalg.lstsq(basis, x, rcond=None)
        return np.max(np.abs(basis @ coefficients - x)), frequency, coefficients

    # between the spectrum's neighbouring bins (a record need not hold whole cycles), then
    # finer about the best
    low_c, high_c = max(cycles - 1.0, 0.5), cycles + 1.0
    for _ in range(3):
        worst, frequency, (mean, a, b) = min(
            (fit(c / span) for c in np.linspace(low_c, high_c, 41)), key=lambda f: f[0])
        width = (high_c - low_c) / 40
        low_c, high_c = frequency * span - width, frequency * span + width
    if worst <= 0.05 * size:
        return f"sine: {frequency:.3g} Hz, {v(mean)} +- {v(math.hypot(a, b))}"
    return f"{v(low)} to {v(high)} over {span:.3g} s, turning {turns} times"


# A deflection this many times the largest the thesis measured is a unit mistake, not a test.
UNIT_MISTAKE_FACTOR = 10.0


def deflection_slip(definition, deflection):
    """(kind, message) when a deflection history looks typed in the display unit (mm or deg)
    rather than SI: "error" beyond UNIT_MISTAKE_FACTOR times the largest the thesis measured,
    "warning" for an angle beyond that largest (an angle in deg is 57 times its value in
    rad, so a small one can pass the first test); else None."""
    variable = definition.inputs[0]
    span = definition.deflection_scale
    largest = float(np.max(np.abs(deflection))) if len(deflection) else 0.0
    display, factor = UNITS[variable.unit][1][0]
    convert = (f"Convert to SI ({variable.unit}, and its rate in {variable.unit}/s): divide "
               f"by {factor:.6g} ({largest:g} {display} = {largest / factor:.4g} "
               f"{variable.unit})")
    if largest > UNIT_MISTAKE_FACTOR * span:
        return "error", (f"{variable.name} reaches {largest:g} {variable.unit}, far beyond the "
                         f"{span:.3g} {variable.unit} the thesis measured: it looks like "
                         f"{display}. {convert}")
    if variable.unit == "rad" and largest > span:
        return "warning", (f"{variable.name} reaches {largest:g} rad ({largest * factor:.3g} "
                           f"deg), beyond the {span:.3g} rad ({span * factor:.3g} deg) the "
                           f"thesis measured; if the values are in deg, {convert[0].lower()}"
                           f"{convert[1:]}")
    return None


def check_deflection(definition, deflection, where=""):
    """The unit check every tool gives a deflection it is handed (signal, simulate, rig): a
    UsageError where it looks typed in mm or deg, a warning on stderr where an angle may
    be (deflection_slip). `where` prefixes the message (a file's name)."""
    slip = deflection_slip(definition, np.asarray(deflection, dtype=float))
    if slip and slip[0] == "error":
        raise UsageError(f"{where}{slip[1]}")
    if slip:
        print(f"warning: {where}{slip[1]}", file=sys.stderr)
