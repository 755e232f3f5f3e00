"""One FMU (either flavour) on an input CSV through fmpy: the input read and checked, the
run, the result CSV and the plot of its loop.

The result CSV has the time, both inputs (deflection and rate) and every output, so that
the force-deflection loop can be plotted from it alone; `--plot` draws that loop. The
input is checked first, because fmpy would run on a wrong one without a word: a missing
rate column (fmpy would feed rate 0 and the viscoelastic force would vanish), misspelt
columns, values in mm or deg where the FMU takes m or rad, a stop time past the input's
end (fmpy would hold the last sample). docs/simulate.md describes the command
(``commands/simulate.py``).
"""

import contextlib
import csv
import io
import math
import os
import sys

import numpy as np

from ..errors import UsageError
from ..export.identity import NotOurFmu, read_identity
from ..export.parameters import parameter_set, read_parameters, settings
from .display import DISPLAY
from .files import save_figure, written_whole
from .signals import check_deflection, describe

# The most communication steps a run may take: fmpy keeps every step's outputs as a row of
# Python floats, and the input is held as read. Measured: the tyre over 2e5 steps of a
# 2e5-row input peaks at 129 MB resident, against 40 MB for 2e3 steps, about 450 bytes a
# step: MAX_STEPS take about 1 GB.
MAX_STEPS = 2_000_000


class Component:
    """What simulate needs to know of an FMU this project built (either flavour, any name):
    its component, inputs and outputs, read from the FMU (export/identity.py)."""

    def __init__(self, path):
        from fmpy import read_model_description

        try:
            self.identity = read_identity(path)
        except NotOurFmu as error:
            raise UsageError(str(error)) from None
        self.path = path
        self.description = read_model_description(path)
        self.name = self.identity.name
        self.definition = self.identity.definition
        self.flavour = self.identity.flavour
        self.inputs = [v.name for v in self.definition.inputs]
        self.outputs = [v.name for v in self.definition.outputs]

    def parameters(self, params_file=None, settings_=None):
        """{name: value} of the parameters to set: those of the file, then the NAME=VALUE
        settings, checked against the FMU's own values; unit slips are warned about."""
        given = (dict(read_parameters(params_file, self.identity.definition)) if params_file
                 else {})
        given.update(settings(settings_))
        if not given:
            return {}
        identity = self.identity
        values = parameter_set(identity.component, identity.structure, given,
                               base=identity.values,
                               warn=lambda message: print(f"warning: {message}",
                                                          file=sys.stderr))
        self.definition = identity.thesis.with_values(self.name, values)
        return {name: values[name] for name in given}


def read_input(path):
    """(column names, values as an array of rows) of an input CSV, quoted headers or not.
    A cell that is not a finite number is refused by its row (the file's line) and time."""
    try:
        with open(path, newline="") as file:
            rows = [(line, row) for line, row in enumerate(csv.reader(file), start=1) if row]
    except OSError as exc:
        raise UsageError(f"{path}: cannot read the input CSV ({exc.strerror})") from None
    if rows and len(rows[0][1]) == 1 and ";" in rows[0][1][0]:
        raise UsageError(f"{path} looks separated by ';' (its header is {rows[0][1][0]!r}): "
                         f"an input CSV is separated by commas, with '.' as the decimal point; "
                         f"save it so, e.g. with `fmu-components signal`")
    if len(rows) < 3:
        raise UsageError(f"{path}: an input CSV needs a header line and at least two rows of "
                         f"samples; write one with `fmu-components signal`")
    names = [name.strip() for name in rows[0][1]]
    values = np.empty((len(rows) - 1, len(names)))
    for i, (line, row) in enumerate(rows[1:]):
        if len(row) != len(names):
            raise UsageError(f"{path}: row {line} has {len(row)} values; every row must have "
                             f"{len(names)}, as the header ({', '.join(names)})")
        for j, cell in enumerate(row):
            try:
                values[i, j] = float(cell)
            except ValueError:
                values[i, j] = math.nan
            if not math.isfinite(values[i, j]):
                when = f"time {row[0].strip()} s" if j else "its time"
                raise UsageError(f"{path}: row {line} ({when}): {names[j]} is {cell.strip()!r}, "
                                 f"not a finite number; every value after the header must be "
                                 f"one (SI units)")
    return names, values


def check_columns(component, names, derive_rate, path):
    """The input columns to feed the FMU; a UsageError naming the FMU's inputs against the
    CSV's columns when they do not fit."""
    deflection, rate = component.inputs
    have = ", ".join(names)
    if names[0] != "time":
        raise UsageError(f"{path}: the first column must be 'time' (s); its columns are: {have}")
    unknown = [n for n in names[1:] if n not in component.inputs]
    if unknown or deflection not in names:
        raise UsageError(f"{path}: columns {', '.join(names[1:])} do not match the inputs of "
                         f"{component.name} ({deflection}, {rate}); rename them to those")
    if rate not in names and not derive_rate:
        raise UsageError(f"{path} has no {rate} column: {component.name}'s inputs are "
                         f"{deflection}, {rate}; the CSV's columns are {have}. Add the rate, or "
                         f"pass --derive-rate to have the FMU derive it from {deflection}")
    return [deflection] if derive_rate else [deflection, rate]


def check_units(component, names, values, path):
    """A UsageError when the deflection looks like mm (deg) where m (rad) is expected; a
    warning on stderr where an angle may be in deg."""
    check_deflection(component.definition, values[:, names.index(component.inputs[0])],
                     f"{path}: ")


def check_times(times, stop_time, step, path):
    """(stop time, step): the defaults from the CSV; a UsageError for a stop time that is
    not after the input's start or is past its end, or a step that is not positive or makes
    more than MAX_STEPS steps; a warning on stderr for a step coarser than the samples."""
    intervals = np.diff(times)
    if not np.all(intervals > 0.0):
        raise UsageError(f"{path}: the times must increase from row to row")
    start, end = float(times[0]), float(times[-1])
    if stop_time is None:
        stop_time = end
    elif not (math.isfinite(stop_time) and stop_time > start):
        raise UsageError(f"--stop-time {stop_time:g} must be a time after the input's start at "
                         f"{start:g} s, e.g. its end: --stop-time {end:g}")
    elif stop_time > end * (1 + 1e-12):
        raise UsageError(f"--stop-time {stop_time:g} s is past the input's end at {end:g} s, "
                         f"where fmpy would hold the last sample; give --stop-time {end:g} or "
                         f"less, or extend the input")
    spacing = float(np.min(intervals))
    if step is None:
        step = spacing
    if not (step > 0.0 and math.isfinite(step)):
        raise UsageError(f"--step {step!r} must be a positive number of seconds")
    steps = (stop_time - start) / step
    if steps > MAX_STEPS:
        raise UsageError(f"--step {step:g} s makes {steps:.3g} communication steps from "
                         f"{start:g} to {stop_time:g} s; simulate keeps every step's outputs in "
                         f"memory and takes at most {MAX_STEPS:.0e}: give --step "
                         f"{(stop_time - start) / MAX_STEPS:.2g} or longer, or a shorter "
                         f"--stop-time")
    if step > spacing * (1 + 1e-9):
        print(f"warning: --step {step:g} s is coarser than the input's sampling ({spacing:g} s): "
              f"the FMU takes the inputs at each step only and holds that sample's rate over "
              f"the whole step, so the samples between are skipped and the load does not follow "
              f"the input; give --step {spacing:g} or less (the default)", file=sys.stderr)
    return stop_time, step


def check_tolerance(tolerance):
    """A UsageError for a relative tolerance that is not between 0 and 1 (None: the FMU's
    own)."""
    if tolerance is not None and not 0.0 < tolerance < 1.0:
        raise UsageError(f"--tolerance {tolerance:g} must be a relative tolerance between 0 and "
                         f"1, e.g. 1e-4 (the FMUs' default) or 1e-6")


def prepare_output(*paths):
    """Make the folders the result files go to, before the run, so that a run is never
    lost for want of them; a UsageError where one cannot be made."""
    for path in paths:
        if path is None:
            continue
        folder = os.path.dirname(os.path.abspath(path))
        try:
            os.makedirs(folder, exist_ok=True)
        except OSError as exc:
            raise UsageError(f"{path}: cannot make its folder {folder} ({exc.strerror})") from None


def simulate(component, times, columns, stop_time, step, tolerance=None, derive_rate=False,
             warnings=None, errors=None, parameters=None):
    """fmpy's result (a structured array: time and the outputs); the FMU's warnings and
    errors are appended to those lists."""
    from fmpy import simulate_fmu

    from ..coupling.instance import WARNING, FmuInstance
    inputs = np.zeros(len(times), dtype=[("time", float)] + [(n, float) for n in columns])
    inputs["time"] = times
    for name, values in columns.items():
        inputs[name] = values
    warnings = [] if warnings is None else warnings
    errors = [] if errors is None else errors

    def log(status, text):
        (warnings if status == WARNING else errors if status > WARNING else []).append(text)

    # The instance is made here (FMI 2.0 or 3.0), with a logger of its own: fmpy's `logger=`
    # would install it as the logger of the whole process (its logger proxy), and leave that
    # pointing at a freed callback once this simulation is over. fmpy's loop drives it.
    instance = FmuInstance(component.path, component.name, on_message=log)
    try:
        said = io.StringIO()  # fmpy prints; a rate left out on purpose is no news
        with contextlib.redirect_stdout(said):
            result = simulate_fmu(
                instance.fmu.directory, start_time=float(times[0]), stop_time=stop_time,
                output_interval=step, relative_tolerance=tolerance, input=inputs,
                output=component.outputs, model_description=instance.fmu.description,
                fmu_instance=instance.fmpy,
                start_values={**(parameters or {}),
                              **({"rate_from_deflection": True} if derive_rate else {})})
    finally:
        instance.close()  # fmpy's loop has terminated it
    expected = f'missing input for variable "{component.inputs[1]}"'
    warnings += [line for line in said.getvalue().splitlines()
                 if line.strip() and not (derive_rate and expected in line)]
    return result


def derived_rates(times, deflection):
    """The rate the FMU uses with rate_from_deflection at each sample: the backward
    difference over the step before it, held; the first sample's is 0 (no rate input)."""
    rates = np.zeros(len(times))
    rates[1:] = np.diff(deflection) / np.diff(times)
    return rates


def at_times(t, times, values):
    """values at fmpy's output times t: the sample's own where t is a sample time (fmpy adds
    up its steps, so only nearly), else interpolated."""
    i = np.clip(np.searchsorted(times, t), 1, len(times) - 1)
    nearest = np.where(np.abs(times[i - 1] - t) <= np.abs(times[i] - t), i - 1, i)
    on_sample = np.abs(times[nearest] - t) <= 1e-9 * np.maximum(1.0, np.abs(t))
    return np.where(on_sample, values[nearest], np.interp(t, times, values))


def finer_grid(times, columns, stop_time, step, deflection, rate):
    """The input on the communication grid when the step is finer than the samples: the
    deflection straight between samples, as fmpy would interpolate it, and as the rate the
    slope of that line, which is the rate of the path the FMU is then fed (an interpolated
    rate column would not fit it, and the FMU's rate check would say so)."""
    if step >= np.min(np.diff(times)) * (1 - 1e-9):
        return times, columns
    grid = times[0] + np.arange(int(math.floor((stop_time - times[0]) / step * (1 + 1e-12))) + 1) * step
    if stop_time - grid[-1] > 1e-9 * step:
        # The step does not divide the span: fmpy ends with a shorter step to the stop time,
        # whose outputs belong to the stop time, so the grid ends there too.
        grid = np.append(grid, stop_time)
    segment = np.clip(np.searchsorted(times, grid, side="right") - 1, 0, len(times) - 2)
    x = columns[deflection]
    slopes = (np.diff(x) / np.diff(times))[segment]
    resampled = {deflection: x[segment] + slopes * (grid - times[segment])}
    if rate in columns:
        resampled[rate] = slopes
    return grid, resampled


def write_result(path, component, result, times, columns, derive_rate):
    """time, deflection, rate, then every output, at fmpy's output times."""
    t = result["time"]
    if not np.all(np.diff(t) > 0.0):
        raise RuntimeError("fmpy's output times do not increase")  # never written as rows
    deflection, rate = component.inputs
    x = columns[deflection]
    v = derived_rates(times, x) if derive_rate else columns[rate]
    t, x, v = (at_times(t, times, column) for column in (times, x, v))
    columns = [("time", t), (deflection, x), (rate, v)]
    columns += [(name, result[name]) for name in component.outputs]
    with written_whole(path) as whole, open(whole, "w", newline="") as file:
        writer = csv.writer(file, lineterminator="\n")
        writer.writerow([name for name, _ in columns])
        for row in zip(*(c for _, c in columns)):
            writer.writerow([repr(float(v)) for v in row])
    return dict(columns)


def main_frequency(times, deflection):
    """The frequency (Hz) of the largest Fourier component of the deflection about its mean,
    or None for an input that does not oscillate."""
    if len(times) < 4:
        return None
    t = np.linspace(times[0], times[-1], len(times))
    x = np.interp(t, times, deflection)
    spectrum = np.abs(np.fft.rfft(x - np.mean(x)))
    frequencies = np.fft.rfftfreq(len(t), t[1] - t[0])
    if len(spectrum) < 2 or not spectrum[1:].max() > 0.0:
        return None
    return float(frequencies[1 + int(np.argmax(spectrum[1:]))])


def plot_loop(path, component, columns):
    """loop_figure, saved at 200 dpi."""
    import matplotlib.pyplot as plt

    figure = loop_figure(component, columns)
    save_figure(figure, path, dpi=200)
    plt.close(figure)


def loop_figure(component, columns):
    """The force-deflection loop beside the time histories of the inputs and every output
    (display units), titled with what the input is (signals.describe)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    definition = component.definition
    deflection, rate = definition.inputs
    load = definition.outputs[0]
    (x_factor, x_unit), (f_factor, f_unit), (v_factor, v_unit) = DISPLAY[definition.component]
    time, x = columns["time"], columns[deflection.name]
    figure = plt.figure(figsize=(12.8, 5.6))
    grid = figure.add_gridspec(3, 2, width_ratios=(1.0, 1.3))
    loop = figure.add_subplot(grid[:, 0])
    loop.plot(x * x_factor, columns[load.name] * f_factor, lw=1.2)
    loop.set_xlabel(f"{deflection.name} ({x_unit})")
    loop.set_ylabel(f"{load.name} ({f_unit})")
    loop.set_title("loop", fontsize=9)
    panels = [figure.add_subplot(grid[i, 1]) for i in range(3)]
    for panel in panels[1:]:
        panel.sharex(panels[0])
    for panel, variable, factor, unit in ((panels[0], deflection, x_factor, x_unit),
                                          (panels[1], rate, v_factor, v_unit)):
        panel.plot(time, columns[variable.name] * factor, lw=1.0, color="tab:gray")
        panel.set_ylabel(f"{variable.name}\n({unit})", fontsize=8)
    # The load wide and light, its parts (every other output in its unit) thin on top: a
    # part that equals the load (the damper's dashpot torque, most of the time) would
    # otherwise hide it.
    panels[2].plot(time, columns[load.name] * f_factor, lw=3.0, alpha=0.35, color="black",
                   label=load.name, zorder=1)
    for output in (v for v in definition.outputs if v.unit == load.unit and v is not load):
        panels[2].plot(time, columns[output.name] * f_factor, lw=1.0, label=output.name,
                       zorder=2)
    panels[2].set_ylabel(f"{load.name} ({f_unit})", fontsize=8)
    panels[2].set_xlabel("time (s)")
    panels[2].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    for panel in (loop, *panels):
        panel.grid(True, alpha=0.3)
    figure.suptitle(f"{os.path.basename(component.path)} ({component.flavour}), "
                    f"{describe(time, x, x_factor, x_unit)}", fontsize=10)
    figure.tight_layout()
    return figure
