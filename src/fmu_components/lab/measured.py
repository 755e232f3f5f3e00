"""A user's measured tests of a rubber part, read and checked: the data ``fmu-components
fit`` identifies a part from.

Each DATA.csv is one measured test, told apart by its header:

* a history, ``time,deflection,force`` (SI: s, m or rad, N or N.m), of any motion;
* a rig table, ``preload,amplitude,frequency,dynamic_stiffness,loss_angle_deg``: one steady
  sine per row.

A file that cannot be a test of the component (too few samples or cycles, time that does
not increase, values in mm, deg or kN where SI is expected) is refused with one line that
says what to do.
"""

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import UsageError
from ..runtime.units import column_name

HISTORY_COLUMNS = ("time", "deflection", "force")
TABLE_COLUMNS = ("preload", "amplitude", "frequency", "dynamic_stiffness", "loss_angle_deg")
MIN_SAMPLES = 50
UNIT_FACTOR = 30.0  # a magnitude this far from the component's scale is a unit mistake

@dataclass
class History:
    """A measured test under any deflection history."""
    path: Path
    times: np.ndarray
    deflection: np.ndarray
    force: np.ndarray
    columns: tuple = HISTORY_COLUMNS  # the file's columns they were read from

    @property
    def label(self):
        return self.path.name

    @property
    def scale(self):
        return float(np.ptp(self.force))


@dataclass
class RigTable:
    """Steady sines: per row preload, amplitude, frequency, |K*|, loss angle (deg)."""
    path: Path
    rows: np.ndarray  # (n, 5)

    @property
    def label(self):
        return self.path.name


def _numbers(path, rows, columns):
    values = np.empty((len(rows), len(columns)))
    for i, row in enumerate(rows):
        for j, name in enumerate(columns):
            text = row.get(name)
            try:
                values[i, j] = float(text)
            except (TypeError, ValueError):
                raise UsageError(f"{path}: line {i + 2}, column {name}: {text!r} is not a "
                                 f"number; give every value in SI") from None
            if not math.isfinite(values[i, j]):
                raise UsageError(f"{path}: line {i + 2}, column {name} is {text}; remove or "
                                 f"fill the samples that are not finite numbers")
    return values


def read_data(path, definition):
    """One DATA.csv as a History or a RigTable, checked against the component."""
    path = Path(path)
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            # a rig table's header may give units ("preload [m]", fmu-components rig)
            header = tuple(column_name(name) for name in (reader.fieldnames or ()))
            reader.fieldnames = list(header)
            rows = list(reader)
    except OSError as error:
        raise UsageError(f"cannot read {path}: {error.strerror}") from None
    except (UnicodeDecodeError, csv.Error):
        raise UsageError(f"{path} is not a CSV text file") from None
    columns = history_columns(header, definition)
    if columns:
        return _history(path, _numbers(path, rows, columns), definition, columns)
    if set(TABLE_COLUMNS) <= set(header):
        return _table(path, _numbers(path, rows, TABLE_COLUMNS), definition)
    deflection, load = definition.inputs[0].name, definition.outputs[0].name
    raise UsageError(f"{path}: columns {','.join(header) or '(none)'}; expected "
                     f"{','.join(HISTORY_COLUMNS)} (a measured test; or {deflection} and "
                     f"{load}, as fmu-components simulate writes them) or "
                     f"{','.join(TABLE_COLUMNS)} (a rig table)")


def history_columns(header, definition):
    """(time, deflection, force) column names of a history: the generic names, or the
    component's own input and output names (what `fmu-components simulate` writes); None
    if the header has neither."""
    choices = (("time",), ("deflection", definition.inputs[0].name),
               ("force", definition.outputs[0].name))
    taken = tuple(next((name for name in names if name in header), None) for names in choices)
    return None if None in taken else taken


def deflection_limit(definition):
    low, high, _ = definition.measured_ranges[definition.inputs[0].name]
    return max(abs(v) for v in (low, high) if math.isfinite(v))


def _elastic_force(definition, x):
    values = definition.default_parameters()
    x = np.asarray(x, dtype=float)
    return sum(values[f"elastic.a{p}"] * x ** p for p in range(4))


def _units(definition):
    deflection, load = definition.inputs[0], definition.outputs[0]
    return deflection.unit, load.unit


def _check_deflection(path, definition, x):
    limit = deflection_limit(definition)
    unit, _ = _units(definition)
    reach = float(np.max(np.abs(x)))
    if reach > UNIT_FACTOR * limit:
        other = "deg" if unit == "rad" else "mm"
        raise UsageError(f"{path}: deflection reaches {reach:g}, beyond {UNIT_FACTOR:g} times "
                         f"what {definition.name} measured ({limit:.3g} {unit}): it looks like "
                         f"{other}; give {unit}")


def _history(path, values, definition, columns=HISTORY_COLUMNS):
    t, x, force = values.T
    if len(t) < MIN_SAMPLES:
        raise UsageError(f"{path}: {len(t)} samples; a test needs at least {MIN_SAMPLES}")
    if np.any(np.diff(t) <= 0.0):
        i = int(np.argmax(np.diff(t) <= 0.0))
        raise UsageError(f"{path}: time does not increase at line {i + 3} ({t[i + 1]:g} s "
                         f"after {t[i]:g} s); sort the samples and remove repeated times")
    _check_deflection(path, definition, x)
    moves = np.diff(x)
    moving = moves[np.abs(moves) > 1e-9 * max(np.ptp(x), 1e-300)]
    reversals = int(np.count_nonzero(np.diff(np.sign(moving)) != 0))
    held = float(np.sum(np.diff(t)[np.abs(moves) <= 1e-9 * max(np.ptp(x), 1e-300)]))
    if np.ptp(x) == 0.0:
        raise UsageError(f"{path}: the deflection never changes; a test must move the part")
    if reversals < 2 and held < 0.2 * (t[-1] - t[0]):
        raise UsageError(f"{path}: too few cycles ({reversals} reversal(s) of the motion); "
                         f"record at least one whole cycle, or a step and hold")
    _, load_unit = _units(definition)
    expected = float(np.ptp(_elastic_force(definition, x[x > 0] if _unilateral(definition)
                                           else x))) if np.any(x > 0) else 0.0
    if expected > 0.0:
        ratio = np.ptp(force) / expected
        if ratio < 1.0 / UNIT_FACTOR:
            raise UsageError(f"{path}: the force spans {np.ptp(force):.3g}, 1/{1 / ratio:.0f} "
                             f"of what {definition.name} carries over that deflection: it "
                             f"looks like k{load_unit}; give {load_unit}")
        if ratio > UNIT_FACTOR:
            raise UsageError(f"{path}: the force spans {np.ptp(force):.3g}, {ratio:.0f} times "
                             f"what {definition.name} carries over that deflection: give "
                             f"{load_unit}, not a smaller unit")
    return History(path, t, x, force, columns)


def _unilateral(definition):
    return definition.name == "RoadWheelTyre"


def _table(path, values, definition):
    if len(values) < 3:
        raise UsageError(f"{path}: {len(values)} row(s); a rig table needs at least 3 "
                         f"(preload, amplitude, frequency points)")
    preload, amplitude, frequency, stiffness, loss = values.T
    for name, column in (("amplitude", amplitude), ("frequency", frequency),
                         ("dynamic_stiffness", stiffness)):
        if np.any(column <= 0.0):
            raise UsageError(f"{path}: every {name} must be positive")
    if np.any(np.abs(loss) >= 90.0):
        raise UsageError(f"{path}: loss_angle_deg must lie within +-90 deg")
    _check_deflection(path, definition, np.abs(preload) + amplitude)
    unit, load_unit = _units(definition)
    thesis = definition.default_parameters()
    scale = max(abs(thesis["elastic.a1"]), sum(thesis[f"k{i}"] for i in (1, 2, 3)))
    ratio = float(np.median(stiffness)) / scale
    if not 1.0 / UNIT_FACTOR ** 2 < ratio < UNIT_FACTOR ** 2:
        size = f"1/{1 / ratio:.0f} of" if ratio < 1 else f"{ratio:.0f} times"
        raise UsageError(f"{path}: dynamic_stiffness about {np.median(stiffness):.3g}, {size} "
                         f"{definition.name}'s scale ({scale:.3g} {load_unit}/{unit}); give "
                         f"{load_unit}/{unit}")
    return RigTable(path, values)

