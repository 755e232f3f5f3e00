"""The thesis test programme (spec section 5) as cases, and their reference data.

Every case is one input history on a uniform communication grid (secant rates, see
``signals``) for one FMU. Its files in ``reference_data/<FMU>/`` follow the FMI cross-check
convention:

* ``<case>_in.csv``: time and the FMU's two inputs, quoted headers;
* ``<case>_ref.csv``: time and every output the independent solve provides (all outputs
  except ``stiffness``), under the co-simulation input convention
  (``reference.solve_held_rate``);
* ``<case>_ref.opt``: StartTime, StopTime, StepSize and RelTol (the tolerance the FMU is
  run with).

Numbers are written with ``repr``, which round-trips, so a regeneration is compared with the
committed files column by column: every value within ``REPRODUCE_TOLERANCE`` of the
column's peak-to-peak range (on the same machine the files come out byte-identical).

    python -m fmu_components.commands.cases --list
    python -m fmu_components.commands.cases --regenerate [--fmu NAME] [--case GLOB]
    python -m fmu_components.commands.cases --check [--fmu NAME] [--case GLOB]

The reference comes from ``reference`` (scipy Radau on plain right-hand sides); the only
thing taken from the FMU side is the variable names in the catalog.
"""

import contextlib
import fnmatch
import io
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from fmpy import simulate_fmu
from fmpy.util import read_csv

from . import reference
from ..runtime.catalog import COMPONENTS
from ..runtime.units import MM, RAD_PER_DEG
from ..lab.signals import (DUAL_SINE, DUAL_SINE_SHOWN, DUAL_SINE_STEP, DUAL_SINE_STOP, dual_sine,
                           input_table, piecewise_linear_rate, ramp_and_hold, sine, time_grid,
                           write_csv)

REFERENCE_DATA = Path(__file__).resolve().parents[3] / "reference_data"
REPRODUCE_TOLERANCE = 1e-9  # of each column's peak-to-peak range


@dataclass(frozen=True)
class Case:
    fmu: str
    name: str            # file stem in reference_data/<fmu>/
    test: str            # key of TESTS: the row of spec section 5
    label: str           # legend entry in the test's figure
    step: float          # communication step (s)
    stop_time: float     # s; the case starts at 0
    path: Callable       # times (s) -> deflection input (SI)
    shown_from: float    # plots show t >= shown_from: the recorded, settled part
    plateaus: tuple = ()  # constant-velocity sweep: (rate, start time, end time) of each
    rtol: float = None    # the FMU's tolerance if not the catalog's default

    @property
    def key(self):
        return f"{self.fmu}/{self.name}"

    @property
    def figure(self):
        return TESTS[self.test].figures[self.fmu]

    def times(self):
        return time_grid(self.stop_time, self.step)

    def inputs(self):
        t = self.times()
        return input_table(self.fmu, t, self.path(t))

    def options(self):
        return {"StartTime": 0.0, "StopTime": float(self.times()[-1]), "StepSize": self.step,
                "RelTol": self.rtol or COMPONENTS[self.fmu].default_experiment["tolerance"]}


@dataclass(frozen=True)
class Test:
    title: str
    figures: dict  # FMU -> the thesis figures this test corresponds to


TESTS = {
    "I": Test("Measurement I: small amplitude at several preloads, 1 Hz (section 5.3)",
              {"RoadWheelTyre": "Figs. 5.3.1-3, 7.2-4", "TrackBushRadial": "Fig. 5.3.1-2",
               "TrackBushTorsion": "Fig. 5.3.1-1"}),
    "II": Test("Measurement II: constant preload, several amplitudes, 1 Hz (section 5.4)",
               {"RoadWheelTyre": "Figs. 5.4-3, 7.2-3", "TrackBushRadial": "Figs. 5.4-2, 7.2-1",
                "TrackBushTorsion": "Figs. 5.4-1, 7.2-2"}),
    "III": Test("Measurement III: constant amplitude and preload, several frequencies "
                "(section 5.5)",
                {"RoadWheelTyre": "Figs. 5.5-1, 7.2-5", "TrackBushRadial": "Fig. 5.5-2",
                 "TrackBushTorsion": "section 5.5"}),
    "IV": Test("Measurement IV: step and hold, stress relaxation (section 5.6)",
               {"RoadWheelTyre": "Figs. 5.6-2, 7.2-6", "TrackBushRadial": "section 5.6",
                "TrackBushTorsion": "Figs. 5.6-1, 7.2-7"}),
    "dual sine": Test("Dual sine, 10 deg + 7.5 deg sin(2 pi 0.1 t) + 0.75 deg sin(2 pi 1.5 t) "
                      "(section 5.8)", {"TrackBushTorsion": "Figs. 5.8-1, 7.2-8"}),
    "A-D": Test("Tests A-D: +-0.21 rad at 0.75, 0.5, 0.25 and 0.1 Hz (Table 11.2-1)",
                {"RotaryDamper": "Figs. 13.1-1, 13.1-2"}),
    "high frequency": Test("High-frequency response: +-0.21 rad at 3 and 8 Hz (section 13.2)",
                           {"RotaryDamper": "Figs. 13.2-1, 13.2-2"}),
    "sweep": Test("Constant-velocity sweep, |omega| 0.1 to 14 rad/s (Appendix 6)",
                  {"RotaryDamper": "Table A6-1, Fig. A6-1"}),
}


# --- input paths ---------------------------------------------------------------------------

def preloaded_sine(start, preload, frequency, envelope, ramp_time):
    """A straight ramp from start to the preload over ramp_time, then preload + A sin(2 pi f s)
    with s the time since the ramp ended and the amplitude A piecewise linear through the
    envelope knots [(s, A)]."""
    knot_times, knot_amplitudes = (np.array(v, dtype=float) for v in zip(*envelope))

    def path(t):
        since = np.maximum(t - ramp_time, 0.0)
        level = ramp_and_hold(t, start, preload, ramp_time) if ramp_time > 0 else preload
        return level + sine(since, 0.0, np.interp(since, knot_times, knot_amplitudes), frequency)
    return path


def velocity_plateaus(rates, step, longest, travel, acceleration):
    """The constant-velocity sweep behind Table A6-1: for each rate w, +w, then -w, then +w
    again, so that every plateau of either sign settles to its steady torque while the angle
    returns to where it began and stays within +-travel. The rate changes at a constant
    acceleration, as a rig would drive it; each plateau lasts min(longest, what the travel
    allows). Knots fall on the grid.

    Returns (path, plateaus, stop time), plateaus = ((rate, start time, end time), ...)."""
    knots, plateaus = [(0, 0.0)], []  # (time in steps, rate)

    def to(steps, rate):
        knots.append((knots[-1][0] + steps, rate))

    for rate in rates:
        half_reversal = max(1, math.ceil(rate / acceleration / step))  # steps from +-w to 0
        hold = math.floor(min(longest, travel / rate - half_reversal * step) / step + 1e-9)
        # 0 -> w, hold, w -> -w, hold (twice as long, plus what the ramps to and from zero
        # added), -w -> w, hold, w -> 0: the angle ends where it began.
        for steps, signed, length in ((half_reversal, rate, hold),
                                      (2 * half_reversal, -rate, 2 * hold + half_reversal),
                                      (2 * half_reversal, rate, hold)):
            to(steps, signed)
            to(length, signed)
            plateaus.append((signed, knots[-2][0] * step, knots[-1][0] * step))
        to(half_reversal, 0.0)
    knot_times = np.array([k for k, _ in knots]) * step
    knot_rates = [r for _, r in knots]
    return ((lambda t: piecewise_linear_rate(t, knot_times, knot_rates)), tuple(plateaus),
            knot_times[-1])


# --- the programme -------------------------------------------------------------------------

RAMP = 1.0  # s, from the unloaded start to the preload
CYCLES = 3  # cycles of Measurements II and III; the plots show the last


def _rubber_cases(fmu, start, unit, scale, preloads_i, small, preload, amplitudes, mean_iii,
                  amplitude_iii, frequencies, relaxation_to):
    """Measurements I-IV of one rubber component (spec section 5). Values in the display
    unit (mm or deg), scaled to SI by `scale`."""
    def fmt(value):
        return f"{value:g}{unit}"

    def ramp_time(level):
        return RAMP if level != start else 0.0

    cases = []
    large = 4 * small
    # I: ramp, 2 large cycles, amplitude reduced steadily over 3 cycles, 1 settling cycle and
    # the 5 recorded cycles (section 5.3).
    for level in preloads_i:
        envelope = [(0, large * scale), (2, large * scale), (5, small * scale), (11, small * scale)]
        cases.append(Case(fmu, f"I_preload_{fmt(level)}", "I", f"preload {fmt(level)}", 5e-3,
                          ramp_time(level) + 11.0,
                          preloaded_sine(start * scale, level * scale, 1.0, envelope,
                                         ramp_time(level)),
                          ramp_time(level) + 6.0))
    for amplitude in amplitudes:
        t0 = ramp_time(preload)
        cases.append(Case(fmu, f"II_amplitude_{fmt(amplitude)}", "II", f"+-{fmt(amplitude)}",
                          5e-3, t0 + CYCLES,
                          preloaded_sine(start * scale, preload * scale, 1.0,
                                         [(0, amplitude * scale)], t0),
                          t0 + CYCLES - 1))
    for frequency in frequencies:
        # at least 50 samples per cycle, at most 1000 (0.1 Hz at 10 ms)
        step = {0.1: 1e-2, 1.0: 2e-3}.get(frequency, 1e-3)
        t0 = ramp_time(mean_iii)
        period = 1.0 / frequency
        cases.append(Case(fmu, f"III_frequency_{frequency:g}Hz", "III", f"{frequency:g} Hz", step,
                          t0 + CYCLES * period,
                          preloaded_sine(start * scale, mean_iii * scale, frequency,
                                         [(0, amplitude_iii * scale)], t0),
                          t0 + (CYCLES - 1) * period))
    # IV: a 0.1 s ramp (a rig cannot step instantly, nor can a held-rate input) and a 200 s
    # hold, the part shown against log time.
    cases.append(Case(fmu, f"IV_relaxation_{fmt(relaxation_to)}", "IV",
                      f"{fmt(start)} to {fmt(relaxation_to)}", 2e-2, 200.1,
                      lambda t: ramp_and_hold(t, start * scale, relaxation_to * scale, 0.1),
                      0.1))
    return cases


def _damper_cases():
    cases = []
    # Whole cycles (the first settles, the plots show the last) ending on the grid; at
    # least 125 samples per cycle, 250 where blow-off makes the torque rise steeply.
    for test, frequency, step, cycles in (("A", 0.75, 2e-3, 3), ("B", 0.5, 2e-3, 2),
                                          ("C", 0.25, 5e-3, 2), ("D", 0.1, 1e-2, 2),
                                          (None, 3.0, 1e-3, 3), (None, 8.0, 5e-4, 4)):
        name = f"{test}_{frequency:g}Hz" if test else f"high_frequency_{frequency:g}Hz"
        cases.append(Case("RotaryDamper", name, "A-D" if test else "high frequency",
                          f"{test + ': ' if test else ''}{frequency:g} Hz", step,
                          cycles / frequency,
                          # from rest at -0.21 rad, as a rig starts: no start-up transient
                          lambda t, f=frequency: sine(t, 0.0, 0.21, f, phase=-math.pi / 2),
                          (cycles - 1) / frequency))
    # Where Table A6-1 is flat (rebound beyond -11, compression 11-12 and 13-14 rad/s) the dashpot
    # has zero slope, so nothing damps the rotor on the stiff gas spring (~800 Hz at
    # -8050 N.m): the exact solution keeps ringing after each change of rate. At the default
    # tolerance 1e-4 the FMU's integrator damps that ringing numerically (1.3 % of the torque
    # range, 1.8 % of the rotor rate's); at 1e-5 it follows it (0.17 %, 0.22 %).
    cases.append(constant_velocity_case(
        "constant_velocity_sweep", "+-0.1 to +-14 rad/s",
        [float(r) for r in reference.damper_spec().rates if r > 0], rtol=1e-5))
    return cases


def constant_velocity_case(name, label, rates, rtol=None):
    """The damper at constant angular velocities (+w, -w, +w for each rate w > 0, see
    velocity_plateaus): the test behind Table A6-1. 0.6 s settles the slowest plateau of the
    table (0.4 rad/s: dashpot slope over gas-spring stiffness, c/k ~ 2600/76000 s, 17 time
    constants); the angle stays inside the +-45 deg the damper turns (section 9.1); 500
    rad/s2 is about the peak acceleration of the 8 Hz test."""
    path, plateaus, stop = velocity_plateaus(rates, 2e-3, 0.6, 0.7, 500.0)
    return Case("RotaryDamper", name, "sweep", label, 2e-3, stop, path, 0.0, plateaus, rtol=rtol)


CASES = (
    _rubber_cases("RoadWheelTyre", 0.0, "mm", MM, [1, 2, 3, 4, 5], 0.2, 3.5, [0.5, 1, 1.5, 2],
                  3.5, 1.0, [0.1, 1.0, 10.0, 20.0], 4.0)
    + _rubber_cases("TrackBushRadial", 0.0, "mm", MM, [0.05, 0.15, 0.25, 0.35, 0.45], 0.02, 0.3,
                    [0.05, 0.1, 0.15, 0.2], 0.3, 0.1, [0.1, 1.0, 10.0, 20.0], 0.3)
    # Torsion starts relaxed at the 10 deg live angle, where the elastic torque is ~0.
    + _rubber_cases("TrackBushTorsion", 10.0, "deg", RAD_PER_DEG, [-10, 0, 10, 20, 30], 1.0, 10.0,
                    [2.5, 5, 10, 15, 20], 10.0, 5.0, [0.1, 1.0, 5.0], 25.0)
    + [Case("TrackBushTorsion", "dual_sine", "dual sine", "dual sine", DUAL_SINE_STEP,
            DUAL_SINE_STOP, lambda t: dual_sine(t, *DUAL_SINE), DUAL_SINE_SHOWN)]
    + _damper_cases()
)


# Cheap to regenerate (a few seconds each; the whole programme takes minutes): the tests
# check that these reproduce the committed files; `--check` without a selection does all.
QUICK_CHECK = ("RoadWheelTyre/IV_relaxation_4mm", "RoadWheelTyre/II_amplitude_1mm",
               "TrackBushRadial/IV_relaxation_0.3mm", "TrackBushRadial/III_frequency_20Hz",
               "TrackBushTorsion/IV_relaxation_25deg", "TrackBushTorsion/II_amplitude_5deg",
               "RotaryDamper/B_0.5Hz")


def select(fmus=None, patterns=None, cases=CASES):
    """Cases of the given FMUs whose name or FMU/name matches any glob pattern."""
    return [c for c in cases
            if (not fmus or c.fmu in fmus)
            and (not patterns or any(fnmatch.fnmatchcase(c.name, p) or fnmatch.fnmatchcase(c.key, p)
                                     for p in patterns))]


# --- files ---------------------------------------------------------------------------------

def case_paths(case, root=REFERENCE_DATA):
    folder = Path(root) / case.fmu
    return {kind: folder / f"{case.name}_{kind}" for kind in ("in.csv", "ref.csv", "ref.opt")}


def reference_table(case, inputs, spec=None):
    """The independent solve of the case's input: time and the FMU's outputs, in the
    catalog's order. spec: a part's own values (reference.spec_from_parameters)."""
    deflection_name, rate_name = inputs.dtype.names[1:]
    outputs = reference.solve_held_rate(case.fmu, inputs["time"], inputs[deflection_name],
                                        inputs[rate_name], spec=spec)
    names = [v.name for v in COMPONENTS[case.fmu].outputs if v.name in outputs]
    assert set(names) == set(outputs), (names, list(outputs))
    table = np.zeros(len(inputs), dtype=[("time", float)] + [(n, float) for n in names])
    table["time"] = inputs["time"]
    for name in names:
        table[name] = outputs[name]
    return table


def options_text(options):
    return "".join(f"{key}, {value!r}\n" for key, value in options.items())


def read_options(path):
    options = {}
    for line in Path(path).read_text().splitlines():
        if line.strip():
            key, value = line.split(",", 1)
            options[key.strip()] = float(value)
    return options


def generate(case, spec=None):
    """(input table, reference table, .opt text) of one case, computed afresh (for a part's
    own values: spec)."""
    inputs = case.inputs()
    return inputs, reference_table(case, inputs, spec), options_text(case.options())


def write(case, generated, root=REFERENCE_DATA):
    paths = case_paths(case, root)
    paths["in.csv"].parent.mkdir(parents=True, exist_ok=True)
    inputs, outputs, options = generated
    for table, kind in ((inputs, "in.csv"), (outputs, "ref.csv")):
        with open(paths[kind], "w", newline="") as f:
            write_csv(table, f)
    paths["ref.opt"].write_text(options)


def read(case, root=REFERENCE_DATA):
    """(input table, reference table, options dict) from the committed files."""
    paths = case_paths(case, root)
    return read_csv(paths["in.csv"]), read_csv(paths["ref.csv"]), read_options(paths["ref.opt"])


def column_scale(values):
    """Peak-to-peak range, the scale every error here is measured in (max |value| for a
    constant column, 1 for a zero one)."""
    values = np.asarray(values)
    span = float(values.max() - values.min()) if len(values) else 0.0
    return span or float(np.max(np.abs(values), initial=0.0)) or 1.0


def differences(expected, actual, tolerance):
    """Problems found comparing two tables column by column, to tolerance x column scale."""
    if expected.dtype.names != actual.dtype.names:
        return [f"columns {actual.dtype.names} instead of {expected.dtype.names}"]
    if len(expected) != len(actual):
        return [f"{len(actual)} rows instead of {len(expected)}"]
    return [f"{name} differs by {error:.3g} of its range"
            for name, error in column_errors(expected, actual, expected.dtype.names).items()
            if not error <= tolerance]


def column_errors(expected, actual, names):
    """Max |actual - expected| of each named column, in its column_scale."""
    return {name: float(np.max(np.abs(actual[name] - expected[name])))
            / column_scale(expected[name]) for name in names}


def check(case, root=REFERENCE_DATA):
    """Regenerate a case and compare with its committed files; a list of problems."""
    paths = case_paths(case, root)
    missing = [str(p) for p in paths.values() if not p.exists()]
    if missing:
        return [f"missing {', '.join(missing)}"]
    inputs, outputs, options = generate(case)
    committed_in, committed_ref = read_csv(paths["in.csv"]), read_csv(paths["ref.csv"])
    problems = [f"{kind}: {p}" for kind, (expected, actual) in
                (("in.csv", (inputs, committed_in)), ("ref.csv", (outputs, committed_ref)))
                for p in differences(expected, actual, REPRODUCE_TOLERANCE)]
    if paths["ref.opt"].read_text() != options:
        problems.append("ref.opt differs")
    return problems


def simulate_case(fmu_path, inputs, options, outputs, label=None, start_values=None):
    """(fmpy's result, wall time in s) of one case's input table run through an FMU with the
    case's options (StartTime, StopTime, StepSize, RelTol): the output interval is the step.
    What the FMU logs (fmpy prints it) goes to stderr, each line headed by `label` (the
    case's key), so that a warning says which case it is about. start_values: {variable:
    value} set before the run."""
    started = time.perf_counter()
    said = io.StringIO()
    try:
        with contextlib.redirect_stdout(said):
            result = simulate_fmu(str(fmu_path), start_time=options["StartTime"],
                                  stop_time=options["StopTime"],
                                  output_interval=options["StepSize"],
                                  relative_tolerance=options["RelTol"], input=inputs,
                                  output=outputs, start_values=start_values or {})
    finally:
        for line in said.getvalue().splitlines():
            if line.strip():
                print(f"{label}: {line}" if label else line, file=sys.stderr)
    return result, time.perf_counter() - started


def steady_torques(case, times, torque):
    """(rate, steady torque) of each plateau of the constant-velocity sweep: the mean over
    the plateau's second half, as a rig would average it (the torque rings about its
    steady value where Table A6-1 is flat, see _damper_cases)."""
    times, torque = np.asarray(times), np.asarray(torque)
    rates = np.array([rate for rate, _, _ in case.plateaus])
    half = case.step / 2
    steady = [torque[(times >= (start + end) / 2 - half) & (times <= end + half)].mean()
              for _, start, end in case.plateaus]
    return rates, np.array(steady)
