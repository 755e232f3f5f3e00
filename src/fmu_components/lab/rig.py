"""The virtual test rig's engine: the sine and step-and-hold tests of an elastomer test
machine, run on a component model or its FMU, and the rig table they give.

Each point (preload P, amplitude A, frequency f; SI) drives the deflection
x(t) = P + A sin(2 pi f t) from rest at the preload, with the component relaxed there, and
runs whole cycles until it is periodic: until the first-harmonic result of a cycle changes
from the last one's, and by the trend of those changes will change in all, by less than
--steady (relative), within --max-cycles. The last cycle gives (fmu_components.lab.harmonics)
the dynamic stiffness |K*|, the loss angle, the energy per cycle and the secant stiffness:
one row of DIR/rig.csv (``write_rows``). For the damper (RotaryDamper, arm angle in) DIR/equivalent.csv adds
the equivalent stiffness K' = |K*| cos(delta) and damping c_eq = |K*| sin(delta) / omega.

The drive follows the FMUs' co-simulation semantics (spec section 4; runtime/cosim.py):
every sample sets the exact sine deflection and a rate, the force is read for that
deflection, and the step holds the rate. The rate is by default the secant to the next
sample, so that the held-rate path runs through every sample of the sine (what the README
advises for a prescribed motion); --rate exact holds the sine's own rate at each sample
instead, which a rigid hold turns into a path that misses the next sample by O(h^2) and a
first harmonic that is off by O(h) (measured in docs/rig.md: 5 % in loss angle for the bush
radial at 0.02 mm, 20 Hz, against 1e-5 with the secant). A cycle is at least
--samples-per-cycle steps, and steps of at most --max-step seconds (the damper's gas spring
and dashpot exchange in about 20 ms); a multiple of 4, so that the loop's tips are samples. The step-and-hold test ramps from the preload
by --relaxation STEP (default: the largest amplitude) in --rise seconds, then holds for
--hold seconds, sampled evenly in log time.

Engines: ``model`` (the Python model of catalog.component_definition, stepped through
runtime.cosim.CoSimulation, as the Python flavour's adapter does) or ``fmu`` (a built FMU
of either flavour, FMI 2.0 or 3.0, through coupling/instance.py).
Points run in parallel over --processes.
The plots and the structure study are ``rig_plots``; the command is ``commands/rig.py``.
"""

import csv
import math
import os
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing import get_context

import numpy as np

from .files import written_whole
from .harmonics import first_harmonic
from .signals import check_deflection
from ..export.identity import NotOurFmu, read_identity
from ..export.parameters import ParameterError, parameter_set
from ..runtime.catalog import COMPONENTS, component_definition, structures_of
from ..runtime.cosim import CoSimulation
from ..runtime.units import column_name

CSV_COLUMNS = ("preload", "amplitude", "frequency", "dynamic_stiffness", "loss_angle_deg",
               "energy_per_cycle", "secant_stiffness")
EQUIVALENT_COLUMNS = ("preload", "amplitude", "frequency", "equivalent_stiffness",
                      "equivalent_damping")
SAMPLES_PER_CYCLE = 200
MAX_STEP = 5e-3  # s
RATES = ("secant", "exact")  # the rate held over each step (module docstring)
STEADY = 1e-5  # relative change of the harmonic result still to come, at periodic steady state
MAX_CYCLES = 300
MIN_CYCLES = 3
# The integrator's relative tolerance: tighter than the FMUs' default (1e-4), because a rig
# reads small differences. The damper's secant stiffness, from the torque at the loop's tips
# where the rate is zero, is 4 % of its |K*| at test A and is off by 0.14 % at 1e-4, by
# 3e-6 at 1e-6 (against the reference solver); a point costs about twice as much.
RIG_RTOL = 1e-6
RISE_TIME = 0.1  # s, the step-and-hold ramp (a rig cannot step instantly; section 5.6)
HOLD_TIME = 200.0  # s, as Measurement IV (section 5.6)
LONGEST_STEP = 1.0  # s, the longest communication step the hold takes


class RigError(Exception):
    """A rig run that cannot be done as asked: said in one line."""


@dataclass(frozen=True)
class RigRow:
    preload: float
    amplitude: float
    frequency: float
    dynamic_stiffness: float
    loss_angle_deg: float
    energy_per_cycle: float
    secant_stiffness: float
    equivalent_stiffness: float
    equivalent_damping: float
    cycles: int  # cycles run
    steady: bool  # reached periodic steady state within the cycle cap
    change: float  # the last cycle-to-cycle change of the harmonic result


@dataclass(frozen=True)
class Setup:
    """What a worker needs to drive one instance: picklable."""
    component: str
    structure: str
    parameters: dict  # the full parameter set, name -> SI value
    engine: str  # "model" or "fmu"
    fmu: str = None  # the extracted FMU's folder (engine "fmu")
    rtol: float = RIG_RTOL
    rate: str = "secant"  # the rate held over each sine step: one of RATES
    max_step: float = MAX_STEP  # s, the longest sine step


# --- drivers: one instance of the component, stepped with the co-simulation semantics -----

class ModelDriver:
    """The Python model through the co-simulation class the Python flavour wraps."""

    def __init__(self, setup, deflection, rate):
        definition = component_definition(setup.component, setup.structure)
        model = definition.build_model(setup.parameters)
        self.cosimulation = CoSimulation(model, setup.rtol, 0.0, deflection, rate)

    def force(self, deflection, rate):
        """Set the inputs at the current time; the force for them."""
        problem = self.cosimulation.set_inputs(deflection, rate)
        if problem:
            raise RigError(problem)
        return self.cosimulation.outputs()[0]

    def step(self, current_time, step_size):
        problem = self.cosimulation.do_step(current_time, step_size)
        if problem:
            raise RigError(problem[1])

    def close(self):
        pass


class FmuDriver:
    """A built FMU (either flavour, FMI 2.0 or 3.0) through the coupling library's FMU
    instance (coupling/instance.py); its messages are printed as fmpy prints them."""

    def __init__(self, setup, deflection, rate):
        from ..coupling.instance import FmuInstance

        definition = component_definition(setup.component, setup.structure)
        self.fmu = FmuInstance(setup.fmu, "rig", on_message=_print_message)
        self.inputs = self.fmu.reals([v.name for v in definition.inputs])
        self.load = self.fmu.reals([definition.outputs[0].name])
        with _refusals("its initialization"):
            self.fmu.setup(setup.parameters, setup.rtol, start_time=0.0)
            self.fmu.set(self.inputs, [deflection, rate])
            self.fmu.exit_initialization()

    def force(self, deflection, rate):
        with _refusals(f"setting deflection {deflection!r}, rate {rate!r}"):
            self.fmu.set(self.inputs, [deflection, rate])
            return self.fmu.get(self.load)[0]

    def step(self, current_time, step_size):
        with _refusals(f"the step from t = {current_time:.9g} s"):
            self.fmu.do_step(current_time, step_size)

    def close(self):
        self.fmu.close()


def _print_message(status, text):
    from ..coupling.instance import STATUS_NAMES

    print(f"[{STATUS_NAMES[status].upper()}] {text}")


@contextmanager
def _refusals(what):
    """An FMU call that fails becomes a RigError, with what the FMU said."""
    from ..coupling import CouplingError, StepDiscarded

    try:
        yield
    except (CouplingError, StepDiscarded) as error:
        raise RigError(f"the FMU refused {what} ({error})") from None


DRIVERS = {"model": ModelDriver, "fmu": FmuDriver}


def _driver(setup, deflection, rate):
    return DRIVERS[setup.engine](setup, deflection, rate)


def drive(setup, times, deflection, rates):
    """The load at every sample of any input history, from the relaxed state at its start:
    at each sample the deflection and rate are set and the load read, then the step to the
    next sample holds the rate (spec section 4)."""
    driver = _driver(setup, deflection[0], rates[0])
    force = np.empty(len(times))
    try:
        for k in range(len(times)):
            force[k] = driver.force(deflection[k], rates[k])
            if k + 1 < len(times):
                driver.step(times[k], times[k + 1] - times[k])
    finally:
        driver.close()
    return force


# --- the sine test -------------------------------------------------------------------------

def cycle_samples(setup, frequency, minimum=SAMPLES_PER_CYCLE):
    """Steps per cycle: at least `minimum`, none longer than the setup's max_step, a
    multiple of 4."""
    n = max(minimum, math.ceil(1.0 / (frequency * setup.max_step) - 1e-9))
    return 4 * math.ceil(n / 4)


def cycle_input(setup, preload, amplitude, frequency, n):
    """(deflection, rate) at the n + 1 samples of one cycle from phase 0: the exact sine
    and the setup's rate (the secant to the next sample, or the sine's own)."""
    phase = 2.0 * math.pi * np.arange(n + 2) / n
    deflection = preload + amplitude * np.sin(phase)
    if setup.rate == "exact":
        rates = amplitude * 2.0 * math.pi * frequency * np.cos(phase[:-1])
    else:
        rates = np.diff(deflection) * (frequency * n)  # (x_k+1 - x_k) / h
    return deflection[:-1], rates


def sine_input(setup, preload, amplitude, frequency, cycles, samples_per_cycle=SAMPLES_PER_CYCLE):
    """(times, deflection, rates) of `cycles` whole cycles as the rig drives them."""
    n = cycle_samples(setup, frequency, samples_per_cycle)
    deflection, rates = cycle_input(setup, preload, amplitude, frequency, n)
    times = np.arange(cycles * n + 1) / (frequency * n)
    return (times, np.append(np.tile(deflection[:-1], cycles), deflection[-1]),
            np.append(np.tile(rates[:-1], cycles), rates[-1]))


def sine_record(setup, preload, amplitude, frequency, cycles, samples_per_cycle=SAMPLES_PER_CYCLE):
    """(times, deflection, force) of `cycles` whole cycles from the relaxed preload, every
    sample: the exact deflection and a rate set, the force read, a step with the rate held."""
    records = []
    for record in _sine_cycles(setup, preload, amplitude, frequency, samples_per_cycle):
        records.append(record)
        if len(records) == cycles:
            break
    # each cycle's last sample is the next one's first
    return tuple(np.concatenate([r[i][:-1] for r in records] + [records[-1][i][-1:]])
                 for i in range(3))


def _sine_cycles(setup, preload, amplitude, frequency, samples_per_cycle):
    """Yields each cycle as (times, deflection, force) with both ends: its N + 1 samples,
    the last of which is the next cycle's first."""
    n = cycle_samples(setup, frequency, samples_per_cycle)
    h = 1.0 / (frequency * n)
    deflection, rates = cycle_input(setup, preload, amplitude, frequency, n)
    driver = _driver(setup, deflection[0], rates[0])
    try:
        cycle = 0
        force_at_start = driver.force(deflection[0], rates[0])
        while True:
            times = (cycle * n + np.arange(n + 1)) * h
            force = np.empty(n + 1)
            force[0] = force_at_start
            for k in range(n):
                driver.step(times[k], h)
                force[k + 1] = driver.force(deflection[k + 1], rates[k + 1])
            force_at_start = force[n]
            yield times, deflection, force
            cycle += 1
    finally:
        driver.close()


def run_point(setup, preload, amplitude, frequency, samples_per_cycle=SAMPLES_PER_CYCLE,
              steady=STEADY, max_cycles=MAX_CYCLES):
    """One rig point run to periodic steady state: a RigRow."""
    if samples_per_cycle < 16:
        raise RigError(f"samples per cycle {samples_per_cycle}: give at least 16")
    results, changes = [], []
    for cycle, record in enumerate(_sine_cycles(setup, preload, amplitude, frequency,
                                                samples_per_cycle), start=1):
        results.append(first_harmonic(*record, frequency))
        if len(results) > 1:
            changes.append(results[-1].change_from(results[-2]))
        if cycle >= MIN_CYCLES and _settled(changes, steady):
            done = True
            break
        if cycle >= max_cycles:
            done = False
            break
    result = results[-1]
    return RigRow(preload, amplitude, frequency, result.dynamic_stiffness,
                  result.loss_angle_deg, result.energy_per_cycle, result.secant_stiffness,
                  result.equivalent_stiffness, result.equivalent_damping, cycle, done,
                  changes[-1] if changes else math.inf)


def _settled(changes, steady):
    """Periodic steady state: the last change is below `steady`, and so is all the change
    still to come if the last two shrink geometrically (d r / (1 - r), r = d_n / d_n-1)."""
    if len(changes) < 2 or not changes[-1] < steady:
        return False
    last, before = changes[-1], changes[-2]
    if last == 0.0:
        return True
    ratio = last / before if before > 0.0 else 1.0
    return ratio < 1.0 and last * ratio / (1.0 - ratio) < steady


# --- step and hold -------------------------------------------------------------------------

def relaxation_record(setup, preload, step, rise=RISE_TIME, hold=HOLD_TIME, per_decade=50):
    """(times, deflection, force) of a ramp from the relaxed preload by `step` in `rise`
    seconds, then a hold of `hold` seconds sampled evenly in log time from 1e-4 s on."""
    if not (rise > 0.0 and hold > 0.0):
        raise RigError(f"the ramp ({rise:g} s) and the hold ({hold:g} s) must be positive")
    ramp_steps = 100
    ramp_rate = step / rise
    ramp = np.arange(ramp_steps + 1) * (rise / ramp_steps)
    first = min(1e-4, rise / ramp_steps)
    decades = math.log10(hold / first)
    after = first * 10.0 ** (np.arange(int(math.ceil(decades * per_decade)) + 1) / per_decade)
    after = after[after < hold]
    # once the log spacing would exceed LONGEST_STEP the hold goes on in steps of it
    spaced = [after[0]]
    for t in after[1:]:
        if t - spaced[-1] > LONGEST_STEP:
            break
        spaced.append(t)
    spaced += list(np.arange(spaced[-1] + LONGEST_STEP, hold, LONGEST_STEP))
    times = np.concatenate([ramp, rise + np.array(spaced + [hold])])
    deflection = np.where(times < rise, preload + ramp_rate * times, preload + step)
    rates = np.where(times < rise, ramp_rate, 0.0)
    return times, deflection, drive(setup, times, deflection, rates)


# --- the rig -------------------------------------------------------------------------------

def make_setup(component, structure="final", params=None, engine="model", fmu=None,
               rtol=RIG_RTOL, rate="secant", max_step=MAX_STEP):
    """Check the request and gather what each worker needs. With the FMU engine the
    parameters start from the FMU's own values (an engineer's own part keeps its own)."""
    if component not in COMPONENTS:
        raise RigError(f"no component {component!r}; choose one of {', '.join(sorted(COMPONENTS))}")
    if structure not in structures_of(component):
        raise RigError(f"{component} comes in no {structure!r} structure; it has "
                       f"{', '.join(structures_of(component))}")
    folder = base = None
    if engine == "fmu":
        base = _fmu_identity(fmu, component, structure).values
    elif engine != "model":
        raise RigError(f"engine {engine!r}: choose model or fmu")
    try:
        values = parameter_set(component, structure, params, base=base,
                               warn=lambda message: print(f"warning: {message}",
                                                          file=sys.stderr))
    except ParameterError as error:
        raise RigError(str(error)) from None
    if rate not in RATES:
        raise RigError(f"rate {rate!r}: choose {' or '.join(RATES)}")
    if not max_step > 0.0:
        raise RigError(f"the longest step {max_step!r} s must be positive")
    if engine == "fmu":
        folder = _extract_fmu(fmu)
    return Setup(component, structure, values, engine, folder, rtol, rate, max_step)


def _fmu_identity(path, component, structure):
    """The FMU's identity (export/identity.py): it must be `component` in `structure`,
    whatever its name (an own part built with fmu-components build --params)."""
    if path is None:
        raise RigError("--engine fmu needs --fmu PATH, the built FMU to drive")
    try:
        identity = read_identity(path)
    except NotOurFmu as error:
        raise RigError(str(error)) from None
    if (identity.component, identity.structure) != (component, structure):
        raise RigError(f"{path} is {identity.name}: {identity.component} in the "
                       f"{identity.structure!r} structure, not {component} in the "
                       f"{structure!r} one; give --component {identity.component} --structure "
                       f"{identity.structure}")
    return identity


def _extract_fmu(path):
    import atexit
    import shutil
    import tempfile

    from fmpy import extract

    folder = tempfile.mkdtemp(prefix="fmu_components_rig_")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return extract(str(path), folder)


def _cores():
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _point_task(arguments):
    setup, point, options = arguments
    return run_point(setup, *point, **options)


def run_rig(component, preloads, amplitudes, frequencies, params=None, structure="final",
            engine="model", fmu=None, rtol=RIG_RTOL, samples_per_cycle=SAMPLES_PER_CYCLE,
            steady=STEADY, max_cycles=MAX_CYCLES, processes=None, rate="secant",
            max_step=MAX_STEP, runner=None):
    """Every (preload, amplitude, frequency) point to periodic steady state: RigRows in
    that order (preload, then amplitude, then frequency). runner(tasks), if given, runs
    the (setup, point, options) tasks of ``run_point`` elsewhere (a campaign's engine)
    and returns their rows in order; else they run on `processes` local processes."""
    for label, values in (("amplitude", amplitudes), ("frequency", frequencies)):
        if not values or any(not (v > 0.0 and math.isfinite(v)) for v in values):
            raise RigError(f"each {label} must be a positive number (SI units)")
    if not preloads or any(not math.isfinite(p) for p in preloads):
        raise RigError("each preload must be a finite number (SI units)")
    if component in COMPONENTS:  # else make_setup says what to choose
        check_deflection(COMPONENTS[component], [p + s * a for p in preloads
                                                 for a in amplitudes for s in (-1, 1)])
    setup = make_setup(component, structure, params, engine, fmu, rtol, rate, max_step)
    points = [(p, a, f) for p in preloads for a in amplitudes for f in frequencies]
    options = dict(samples_per_cycle=samples_per_cycle, steady=steady, max_cycles=max_cycles)
    tasks = [(setup, point, options) for point in points]
    if runner is not None:
        return runner(tasks)
    processes = min(processes or _cores(), len(tasks))
    if processes <= 1:
        return [_point_task(task) for task in tasks]
    with get_context("fork").Pool(processes) as pool:
        return pool.map(_point_task, tasks, chunksize=1)


def write_rows(rows, out, component):
    """DIR/rig.csv, and for the damper DIR/equivalent.csv; each header names its column's
    unit in brackets ("preload [m]"; read_rows and the fit read them with or without)."""
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "rig.csv"]
    tables = [(paths[0], CSV_COLUMNS)]
    if component == "RotaryDamper":
        paths.append(out / "equivalent.csv")
        tables.append((paths[1], EQUIVALENT_COLUMNS))
    for path, columns in tables:
        with written_whole(path) as whole, open(whole, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(csv_header(columns, component))
            for row in rows:
                writer.writerow([repr(float(getattr(row, c))) for c in columns])
    return paths


def read_rows(path):
    """The rows of a rig.csv, as dicts of floats by the columns' bare names."""
    with open(path, newline="") as f:
        return [{column_name(k): float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def units(component):
    definition = COMPONENTS[component]
    length, load = definition.inputs[0].unit, definition.outputs[0].unit
    return length, load, f"{load}/{length}"


def csv_header(columns, component):
    """The rig table's header: each column's name and its unit in brackets (the loss angle's
    name says its unit)."""
    length, load, stiffness = units(component)
    unit = {"preload": length, "amplitude": length, "frequency": "Hz",
            "dynamic_stiffness": stiffness, "energy_per_cycle": "J",
            "secant_stiffness": stiffness, "equivalent_stiffness": stiffness,
            "equivalent_damping": f"{load}.s/{length}"}
    return [f"{c} [{unit[c]}]" if c in unit else c for c in columns]


def write_relaxation(record, path, component):
    times, deflection, force = record[:3]
    definition = COMPONENTS[component]
    with written_whole(path) as whole, open(whole, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["time", definition.inputs[0].name, definition.outputs[0].name])
        for row in zip(times, deflection, force):
            writer.writerow([repr(float(v)) for v in row])
    return path
