"""Validate the model against the thesis's own measurements.

``reference_data/thesis/measurements.csv`` holds every number the thesis states from its rig
tests (its README describes the columns): loads at given deflections and the elastic and
geometric fits through them (section 5.3), the damper's torques, slopes and energy in tests
A-D (chapter 12) and its steady torque curve (Table A6-1), and the thesis's statements
without a number (frequency effects, relaxation, the dual sine), each with its source and
what the thesis says of its own model there.

Each row that names a metric is run through a built FMU of either flavour under the test's
conditions: the project's case of that test (``cases``, the same input histories the
verification uses) is simulated with fmpy, and the model's value is taken from the record
the way the thesis took the measured one (the centre of a small loop, a least-squares slope,
a steady torque). Each comparison holds the measured value, the model's, the difference
(absolute and in %), and the row's source and what the thesis says of its own model there.

A row is judged (``Comparison.inside``) when it has a measured value whose basis is a
measurement (rig, fit, supplier): the model within +-``BAND`` % of the measured value (of
the row's ``scale`` where it gives one), or on the right side of a bound. The band is a
convention for flagging, not a measurement uncertainty: the thesis gives none and fitted
its models by eye. The command is ``fmu-components validate`` (``commands/validate.py``).

This is a validation of the model; ``verify`` checks that the FMUs solve its equations.
"""

import csv
import fnmatch
import math
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from ..lab.harmonics import first_harmonic, secondary_loop_areas
from ..lab.simulate import main_frequency
from ..runtime.catalog import COMPONENTS
from ..runtime.units import UNITS
from . import cases as programme
from .junit import Check
from .outcome import aligned
from .reference import THESIS_DATA

MEASUREMENTS = THESIS_DATA / "measurements.csv"
BAND = 10.0  # % of the measured value (or of the row's scale): --strict
RELATIONS = {"=": "", "~": "~", "<": "< ", "<=": "<= ", ">": "> ", "": ""}
BOUNDS = ("<", "<=", ">")
# The bases that are measurements of the part; the others are shown, never judged.
MEASURED_BASES = ("rig", "fit", "supplier")
BASES = MEASURED_BASES + ("extrapolated", "assumed", "design", "statement", "none")

# Cases the measurements need beyond the verification's: the damper at the laminar-turbulent
# transition of section 12.2, 0.25 rad/s (Table A6-1 has no such rate).
EXTRA_CASES = (programme.constant_velocity_case("constant_velocity_0.25", "+-0.25 rad/s",
                                                [0.25]),)
CASES = tuple(programme.CASES) + EXTRA_CASES


# --- the data ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Measurement:
    """One row of measurements.csv; numbers as floats (None where empty)."""
    id: str
    component: str
    quantity: str
    test: str
    conditions: str
    measured: float
    relation: str
    unit: str
    basis: str
    obtained: str
    source: str
    quote: str
    thesis_model: float
    thesis_agreement: str
    thesis_says: str
    case: str
    metric: str
    at: float
    scale: float

    @property
    def judged(self):
        """Whether --strict holds the model to this row: a measurement (not a statement,
        extrapolation, assumption or design value) that is run, and a value that a
        difference can be expressed in (a bound, or a nonzero value or scale)."""
        return (bool(self.metric) and self.measured is not None
                and self.basis in MEASURED_BASES
                and (self.relation in BOUNDS or bool(self.scale or self.measured)))

    @property
    def case_patterns(self):
        """The keys or globs of the cases the metric runs (none for a parameter)."""
        return [] if self.metric == "parameter" else self.case.split()

    @property
    def measured_text(self):
        if self.measured is None:
            return "-"
        return RELATIONS[self.relation] + with_unit(self.measured, self.unit, ".6g")


NUMBERS = ("measured", "thesis_model", "at", "scale")
COLUMNS = tuple(f.name for f in fields(Measurement))


def read_measurements(path=MEASUREMENTS):
    """The rows of a measurements file, checked: every column present, ids unique, a known
    component, relation, basis and metric, a source for every row, numbers where numbers
    belong. A ValueError names the row and what is wrong."""
    with open(path, newline="") as file:
        reader = csv.DictReader(file)
        missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(f"{path}: columns missing: {', '.join(missing)}")
        rows = list(reader)
    measurements, seen = [], set()
    for line, row in enumerate(rows, start=2):
        where = f"{path}, line {line} ({row['id'] or 'no id'})"
        values = {c: row[c].strip() for c in COLUMNS}
        problems = [f"{name} {values[name]!r} is not one of {', '.join(sorted(known))}"
                    for name, known in (("component", COMPONENTS), ("relation", RELATIONS),
                                        ("basis", BASES), ("metric", [""] + sorted(METRICS)))
                    if values[name] not in known]
        problems += [f"no {name}" for name in ("id", "quantity", "source", "quote", "obtained")
                     if not values[name]]
        if values["id"] in seen:
            problems.append("the id is used twice")
        if values["metric"] and not values["case"]:
            problems.append("a metric needs a case")
        if (values["measured"] == "") != (values["relation"] == ""):
            problems.append("a measured value needs a relation, and a relation a value")
        for name in NUMBERS:
            try:
                values[name] = float(values[name]) if values[name] else None
            except ValueError:
                problems.append(f"{name} {values[name]!r} is not a number")
        if problems:
            raise ValueError(f"{where}: {'; '.join(problems)}")
        seen.add(values["id"])
        measurements.append(Measurement(**values))
    return measurements


def with_unit(value, unit, style=".5g"):
    """A value and its unit for a table (no unit for a ratio)."""
    return f"{value:{style}}" + ("" if unit in ("", "1") else f" {unit}")


# --- runs ----------------------------------------------------------------------------------

@dataclass
class Record:
    """One case run through one FMU: the input table and fmpy's result, sample for sample."""
    case: programme.Case
    inputs: np.ndarray
    result: np.ndarray

    @property
    def names(self):
        definition = COMPONENTS[self.case.fmu]
        return [v.name for v in definition.inputs], [v.name for v in definition.outputs]

    @property
    def shown(self):
        """The recorded part: the samples from case.shown_from on (whole cycles, both ends)."""
        return self.inputs["time"] >= self.case.shown_from - self.case.step / 2

    def column(self, which, shown=True):
        """'time', 'deflection', 'rate', 'load' (the first output) or 'elastic' (the second)
        over the recorded part, or over the whole record."""
        (deflection, rate), outputs = self.names
        table, name = {"time": (self.inputs, "time"), "deflection": (self.inputs, deflection),
                       "rate": (self.inputs, rate), "load": (self.result, outputs[0]),
                       "elastic": (self.result, outputs[1])}[which]
        values = np.asarray(table[name], dtype=float)
        return values[self.shown] if shown else values

    @property
    def frequency(self):
        """The frequency (Hz) of a sine case's recorded part: whole cycles, so with one end
        dropped the spectrum has a bin at exactly it."""
        return main_frequency(self.column("time")[:-1], self.column("deflection")[:-1])


class Runs:
    """Runs each case once through the FMU of its component in a folder, and keeps it."""

    def __init__(self, fmus, cases=CASES, progress=None):
        self.fmus, self.cases, self.progress = Path(fmus), cases, progress
        self.records, self.failures = {}, {}

    def fmu(self, component):
        return self.fmus / f"{component}.fmu"

    def select(self, measurement):
        """The cases a row names (space-separated keys or globs), in the catalogue's order."""
        patterns = measurement.case_patterns
        chosen = [c for c in self.cases
                  if any(fnmatch.fnmatchcase(c.key, p) for p in patterns)]
        if patterns and not chosen:
            raise ValueError(f"{measurement.id}: no case matches {measurement.case!r}")
        return chosen

    def records_of(self, measurement):
        return [self.run(case) for case in self.select(measurement)]

    def run(self, case):
        if case.key not in self.records and case.key not in self.failures:
            if self.progress is not None:
                self.progress.set_postfix_str(case.key)
            try:
                result, _ = programme.simulate_case(self.fmu(case.fmu), case.inputs(),
                                                    case.options(), outputs_of(case),
                                                    label=case.key)
            except Exception as exc:  # an FMU that fails is reported, not a crash
                result = f"{type(exc).__name__}: {exc}"
            self.keep(case, result)
            if self.progress is not None:
                self.progress.update(1)
        if case.key in self.failures:
            raise RunFailure(self.failures[case.key])
        return self.records[case.key]

    def keep(self, case, result):
        """The case's result (fmpy's), or the message of its failure, run here or
        elsewhere (a campaign's worker)."""
        inputs = case.inputs()
        if isinstance(result, str):
            self.failures[case.key] = f"{case.key}: {result}"
        elif len(result) != len(inputs):
            self.failures[case.key] = (f"{case.key}: {len(result)} samples, the input has "
                                       f"{len(inputs)}")
        else:
            self.records[case.key] = Record(case, inputs, result)


def outputs_of(case):
    """The outputs a case records: all of its component's."""
    return [v.name for v in COMPONENTS[case.fmu].outputs]


class RunFailure(Exception):
    """A case the FMU could not run."""


# --- metrics: the model's value of each row, in SI, from its records -------------------------
# Each takes (measurement, runs) and returns the value in SI units (a fraction for %).

def _tips(record):
    """(loads at the upper tips, loads at the lower tips, elastic loads at each) of the
    recorded cycles: the samples where the deflection has a local maximum or minimum."""
    x = record.column("deflection")
    inner = np.arange(1, len(x) - 1)
    upper = inner[(x[inner] >= x[inner - 1]) & (x[inner] > x[inner + 1])]
    lower = inner[(x[inner] <= x[inner - 1]) & (x[inner] < x[inner + 1])]
    load, elastic = record.column("load"), record.column("elastic")
    return load[upper], load[lower], elastic[upper], elastic[lower]


def loop_centre(record):
    """The centre of the small loops (section 5.3): the mean of the loads at the two tips."""
    top, bottom, _, _ = _tips(record)
    return 0.5 * (float(np.mean(top)) + float(np.mean(bottom)))


def viscoelastic_half_height(record):
    """Half the difference of the viscoelastic load (the load less the elastic load) at
    the two tips of the small loops (section 5.3.2)."""
    top, bottom, elastic_top, elastic_bottom = _tips(record)
    return 0.5 * (float(np.mean(top - elastic_top)) - float(np.mean(bottom - elastic_bottom)))


def _preload(record):
    return float(np.mean(record.column("deflection")[:-1]))


def _line(xs, ys):
    """(intercept, slope) of the least-squares line."""
    slope, intercept = np.polyfit(np.asarray(xs, dtype=float), np.asarray(ys, dtype=float), 1)
    return float(intercept), float(slope)


def _centre_line(measurement, runs):
    records = runs.records_of(measurement)
    return _line([_preload(r) for r in records], [loop_centre(r) for r in records])


def metric_loop_centre(measurement, runs):
    (record,) = runs.records_of(measurement)
    return loop_centre(record)


def metric_elastic_slope(measurement, runs):
    """Slope of the least-squares line through the loop centres over the preloads
    (Eqs. 5.3.1-1, 5.3.1-2)."""
    return _centre_line(measurement, runs)[1]


def metric_elastic_offset(measurement, runs):
    """Its value at zero deflection."""
    return _centre_line(measurement, runs)[0]


def metric_geometric_slope(measurement, runs):
    """h of f = 1 + h |x - x_ref| (Eqs. 5.3.2-1, 5.3.2-2), x_ref = `at`: the least-squares
    line V = c + m |x - x_ref| through the viscoelastic half-heights V over the preloads x,
    h = m / c."""
    records = runs.records_of(measurement)
    intercept, slope = _line([abs(_preload(r) - measurement.at) for r in records],
                             [viscoelastic_half_height(r) for r in records])
    return slope / intercept


def _harmonics(record):
    """The first-harmonic result of the last recorded cycle."""
    return first_harmonic(record.column("time"), record.column("deflection"),
                          record.column("load"), record.frequency, cycles=1)


def _slowest_and_fastest(measurement, runs):
    records = sorted(runs.records_of(measurement), key=lambda r: r.frequency)
    return _harmonics(records[0]), _harmonics(records[-1])


def metric_stiffness_change(measurement, runs):
    """|K*| at the highest frequency over |K*| at the lowest, less one."""
    slow, fast = _slowest_and_fastest(measurement, runs)
    return fast.dynamic_stiffness / slow.dynamic_stiffness - 1.0


def metric_loss_angle_change(measurement, runs):
    """The loss angle at the highest frequency less that at the lowest (rad)."""
    slow, fast = _slowest_and_fastest(measurement, runs)
    return math.radians(fast.loss_angle_deg - slow.loss_angle_deg)


def metric_relaxed_share(measurement, runs):
    """The share of the whole hold's relaxation done `at` seconds after the ramp: (load at
    the ramp's end - load then) / (load at the ramp's end - load at the end)."""
    (record,) = runs.records_of(measurement)
    t, load = record.column("time"), record.column("load")
    peak, final = load[0], load[-1]
    return float((peak - np.interp(t[0] + measurement.at, t, load)) / (peak - final))


def metric_small_loop_energy(measurement, runs):
    """The mean energy per cycle of the dual sine's 1.5 Hz motion over the recorded primary
    cycle: the area of its small loops (J)."""
    (record,) = runs.records_of(measurement)
    return float(np.mean(secondary_loop_areas(record.column("time", shown=False),
                                              record.column("load", shown=False),
                                              start=record.case.shown_from)))


def metric_peak_torque(measurement, runs):
    """The largest load of the recorded cycles."""
    return max(float(np.max(r.column("load"))) for r in runs.records_of(measurement))


def metric_largest_torque(measurement, runs):
    """The largest |load| of the recorded cycles."""
    return max(float(np.max(np.abs(r.column("load")))) for r in runs.records_of(measurement))


def metric_torque_rate_slope(measurement, runs):
    """The least-squares line through the origin of torque against angular velocity, over
    the recorded cycles of every case named."""
    records = runs.records_of(measurement)
    rate = np.concatenate([r.column("rate") for r in records])
    torque = np.concatenate([r.column("load") for r in records])
    return float(np.dot(rate, torque) / np.dot(rate, rate))


def metric_energy_ratio(measurement, runs):
    """The smallest ratio of a case's energy per cycle to that of the next slower case."""
    records = sorted(runs.records_of(measurement), key=lambda r: r.frequency)
    energies = [_harmonics(r).energy_per_cycle for r in records]
    return min(faster / slower for slower, faster in zip(energies, energies[1:]))


def metric_steady_torque(measurement, runs):
    """The steady torque at the constant angular velocity `at`: the mean over the second
    half of each plateau at that rate (cases.steady_torques), averaged over the plateaus."""
    (record,) = runs.records_of(measurement)
    rates, steady = programme.steady_torques(record.case, record.column("time", shown=False),
                                             record.column("load", shown=False))
    at_rate = np.isclose(rates, measurement.at, rtol=1e-12, atol=0.0)
    if not at_rate.any():
        raise ValueError(f"{measurement.id}: {record.case.key} holds no plateau at "
                         f"{measurement.at:g} rad/s")
    return float(np.mean(steady[at_rate]))


def metric_parameter(measurement, runs):
    """The start value of the FMU's parameter named in `case`."""
    from fmpy import read_model_description

    description = read_model_description(str(runs.fmu(measurement.component)))
    (variable,) = [v for v in description.modelVariables if v.name == measurement.case]
    return float(variable.start)


METRICS = {name[len("metric_"):]: function for name, function in globals().items()
           if name.startswith("metric_")}


# --- units ---------------------------------------------------------------------------------

# Units of the rows that are not in the FMUs' unit table: name -> factor from SI.
ROW_UNITS = {"%": 100.0, "N.m.s/rad": 1.0, "J": 1.0}


def from_si(value, unit):
    """A metric's SI value in a row's unit (an SI unit of runtime.units, one of its display
    units, or one of ROW_UNITS)."""
    if unit in UNITS or unit in ROW_UNITS:
        return value * ROW_UNITS.get(unit, 1.0)
    for _, displays in UNITS.values():
        for name, factor in displays:
            if name == unit:
                return value * factor
    raise ValueError(f"unit {unit!r}: not an SI or display unit of runtime.units")


# --- the comparison ------------------------------------------------------------------------

@dataclass
class Comparison:
    """A row and the model's value for it (in the row's unit), or why it has none."""
    measurement: Measurement
    model: float = None
    problem: str = ""  # the FMU failed to run this row's case

    @property
    def ran(self):
        return self.model is not None

    @property
    def difference(self):
        """model - measured, in the row's unit; None without both."""
        if self.model is None or self.measurement.measured is None:
            return None
        return self.model - self.measurement.measured

    @property
    def percent(self):
        """The difference in % of the row's scale, or of |measured|; None where that is 0."""
        m = self.measurement
        scale = m.scale if m.scale is not None else (abs(m.measured) if m.measured is not None
                                                     else 0.0)
        if self.difference is None or m.relation not in ("=", "~") or not scale:
            return None
        return 100.0 * self.difference / scale

    @property
    def inside(self):
        """Whether a judged row's model value is inside the band (an equality) or on the
        right side of its bound; None for a row that is not judged or did not run."""
        m = self.measurement
        if not (m.judged and self.ran):
            return None
        bounds = {"<": self.model < m.measured, "<=": self.model <= m.measured,
                  ">": self.model > m.measured}
        if m.relation in bounds:
            return bool(bounds[m.relation])
        return self.percent is not None and abs(self.percent) <= BAND

    @property
    def verdict(self):
        if self.problem:
            return "FMU FAILED"
        if self.inside is None:
            return "shown" if self.ran else "not run"
        if self.measurement.relation in BOUNDS:
            return "bound holds" if self.inside else "BOUND BROKEN"
        return f"inside +-{BAND:g} %" if self.inside else f"OUTSIDE +-{BAND:g} %"


def compare_all(measurements, runs):
    """A Comparison for every row: the metric's value where it has one."""
    comparisons = []
    for m in measurements:
        if not m.metric:
            comparisons.append(Comparison(m))
            continue
        try:
            comparisons.append(Comparison(m, from_si(METRICS[m.metric](m, runs), m.unit)))
        except RunFailure as failure:
            comparisons.append(Comparison(m, problem=str(failure)))
    return comparisons


def rows(comparisons):
    """The printed table: a header and one row of strings per comparison."""
    table = [("id", "measured", "model", "difference", "%", "basis", "thesis says model",
              "result")]
    for c in comparisons:
        m = c.measurement
        table.append((
            m.id, m.measured_text,
            with_unit(c.model, m.unit) if c.ran else "-",
            with_unit(c.difference, m.unit, "+.4g") if c.difference is not None else "-",
            f"{c.percent:+.1f}" if c.percent is not None else "-",
            m.basis, m.thesis_agreement or "-", c.verdict))
    return table


def table(comparisons):
    return aligned(rows(comparisons), right=(2, 3, 4))


def tally(comparisons):
    """One paragraph: how many rows compared, shown, not run, judged, outside, failed."""
    compared = [c for c in comparisons if c.difference is not None]
    shown = [c for c in comparisons if c.ran and c.difference is None]
    not_run = [c for c in comparisons if not c.ran and not c.problem]
    judged = [c for c in comparisons if c.inside is not None]
    outside = [c for c in judged if not c.inside]
    failed = [c for c in comparisons if c.problem]
    disagree = [c for c in outside if c.measurement.thesis_agreement == "disagrees"]
    return (f"{len(comparisons)} measured quantities: {len(compared)} compared with the "
            f"model, {len(shown)} statements shown with the model's value, {len(not_run)} not "
            f"run (no conditions in the thesis, or not in the model). {len(judged)} judged "
            f"(a measurement, not an extrapolation, assumption or design value): "
            f"{len(judged) - len(outside)} inside the +-{BAND:g} % band or their bound, "
            f"{len(outside)} outside"
            + (f" ({len(disagree)} where the thesis itself reports disagreement)"
               if outside else "")
            + (f". {len(failed)} could not run: the FMU failed" if failed else "") + ".")


def select(measurements, fmus=None, patterns=None):
    return [m for m in measurements
            if (not fmus or m.component in fmus)
            and (not patterns or any(fnmatch.fnmatchcase(m.id, p) for p in patterns))]


def junit_checks(comparisons, strict=False):
    """A junit.Check per row: failed where the FMU failed (and, with strict, where a judged
    row lies outside its band or bound, as ``validate --strict`` counts it), skipped where
    the row is not judged; its table row as the output."""
    lines = table(comparisons).splitlines()
    return [Check(c.measurement.component, c.measurement.id,
                  failure=c.problem or (c.verdict if strict and c.inside is False else ""),
                  skipped="" if c.inside is not None else c.verdict,
                  output=f"{lines[0]}\n{line}")
            for c, line in zip(comparisons, lines[1:])]
