"""Replay the FMI-LS-REF reference experiments of any FMU (``ls_ref``) through fmpy and hold
its outputs to the references: ``fmu-components verify X.fmu``.

Each experiment runs from its startTime to its stopTime with fmpy.simulate_fmu, the output
interval (and a co-simulation FMU's communication step) its stepSize, the relative
tolerance its tolerance, the inputs its stimuli CSV, the start values its ``.ssv``
(values in another unit of the same kind than the variable's converted by the units' SSP
and modelDescription definitions).

The deviation measure, for each output the references CSV gives: the largest |FMU -
reference| over the reference's time points in [startTime, stopTime] (the FMU's result
interpolated linearly to them), divided by the reference's peak-to-peak range (its largest
magnitude if it is constant, 1 if it is zero). The experiment passes when every output's
deviation is within its limit: the command line's ``--limit`` if given, else the one the
experiment's acceptance annotation states (this project's FMUs: 0.005), else the
experiment's tolerance (the standards define no acceptance bound: then the tolerance the
FMU ran with bounds the deviation too), else ``DEFAULT_LIMIT``.
"""

import fnmatch
import math
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from fmpy import read_model_description
from fmpy.util import read_csv

from ..ssv import SsvError, read_ssv
from . import cases as programme
from .junit import Check
from .ls_ref import LsRefError, read_experiments
from .outcome import STRICT_LIMIT, aligned

DEFAULT_LIMIT = STRICT_LIMIT / 100


@dataclass
class Replay:
    """One experiment of one FMU, replayed."""
    fmu: Path
    experiment: object  # ls_ref.Experiment
    deviations: dict = field(default_factory=dict)  # output -> deviation measure
    limit: float = DEFAULT_LIMIT
    wall_time: float = 0.0
    problem: str = ""

    @property
    def name(self):
        return self.experiment.name

    @property
    def deviation(self):
        return max(self.deviations.values()) if self.deviations else math.inf

    @property
    def worst_output(self):
        return max(self.deviations, key=self.deviations.get) if self.deviations else ""

    @property
    def passed(self):
        return not self.problem and self.deviation <= self.limit

    @property
    def verdict(self):
        if self.problem:
            return f"FAIL: {self.problem}"
        if self.passed:
            return "pass"
        return (f"FAIL: {self.worst_output} deviates {self.deviation:.3g} of its range "
                f"(limit {self.limit:g})")


def deviations(result, references, start_time, stop_time):
    """{output: deviation measure} (module docstring) of a result against references
    (structured arrays with a time column)."""
    t = references["time"]
    inside = (t >= start_time - 1e-12) & (t <= stop_time + 1e-12)
    found = {}
    for name in references.dtype.names[1:]:
        expected = references[name][inside]
        actual = np.interp(t[inside], result["time"], result[name])
        error = float(np.max(np.abs(actual - expected))) / programme.column_scale(expected)
        found[name] = error if math.isfinite(error) else math.inf  # NaN fails
    return found


def _unit_factors(description):
    """{unit name: (base-unit exponents, factor, offset)} of a modelDescription."""
    units = {}
    for unit in description.unitDefinitions:
        base = unit.baseUnit
        if base is not None:
            exponents = {k: getattr(base, k) for k in ("kg", "m", "s", "A", "K", "mol", "cd",
                                                      "rad") if getattr(base, k)}
            units[unit.name] = (exponents, base.factor, base.offset)
    return units


def start_values(path, description):
    """{variable: value} of an .ssv for an FMU, each in the variable's unit; LsRefError
    naming the file, the parameter and the value for one that does not fit."""
    try:
        _, parameters, units = read_ssv(path)
    except SsvError as error:
        raise LsRefError(str(error)) from None
    variables = {v.name: v for v in description.modelVariables}
    fmu_units = _unit_factors(description)
    values = {}
    for name, value, unit in parameters:
        variable = variables.get(name)
        if variable is None:
            raise LsRefError(f"{Path(path).name}: parameter {name} = {value!r}: the FMU has "
                             f"no such variable")
        declared = variable.unit or (variable.declaredType.unit if variable.declaredType
                                     else None)
        if unit is None or unit == declared:
            values[name] = value
            continue
        if unit not in units or declared not in fmu_units:
            raise LsRefError(f"{Path(path).name}: parameter {name} = {value!r} {unit}: cannot "
                             f"convert it to the variable's unit {declared or '(none)'}")
        exponents, factor, offset = units[unit]
        fmu_exponents, fmu_factor, fmu_offset = fmu_units[declared]
        if exponents != fmu_exponents:
            raise LsRefError(f"{Path(path).name}: parameter {name} = {value!r} {unit} is not "
                             f"of the kind of the variable's unit {declared}")
        values[name] = (factor * value + offset - fmu_offset) / fmu_factor
    return values


def replay_one(fmu, experiment, folder, description, limit=None):
    """A Replay of one experiment; the FMU's files extracted in `folder`."""
    chosen = (limit if limit is not None else experiment.limit if experiment.limit is not None
              else experiment.tolerance if experiment.tolerance is not None else DEFAULT_LIMIT)
    outcome = Replay(Path(fmu), experiment, limit=chosen)
    if experiment.problem:
        outcome.problem = experiment.problem
        return outcome
    try:
        references = read_csv(str(folder / experiment.references))
        stimuli = read_csv(str(folder / experiment.stimuli)) if experiment.stimuli else None
        values = (start_values(folder / experiment.parameters, description)
                  if experiment.parameters else {})
        outputs = {v.name for v in description.modelVariables}
        missing = [n for n in references.dtype.names[1:] if n not in outputs]
        if missing:
            raise LsRefError(f"the references give {', '.join(missing)}, which the FMU does "
                             f"not have")
        start = experiment.start_time if experiment.start_time is not None else \
            float(references["time"][0])
        stop = experiment.stop_time if experiment.stop_time is not None else \
            float(references["time"][-1])
        options = {"StartTime": start, "StopTime": stop,
                   "StepSize": experiment.step_size, "RelTol": experiment.tolerance}
        result, outcome.wall_time = programme.simulate_case(
            fmu, stimuli, options, list(references.dtype.names[1:]),
            label=f"{Path(fmu).name}/{experiment.name}", start_values=values)
        outcome.deviations = deviations(result, references, start, stop)
    except (LsRefError, OSError, ValueError) as error:
        outcome.problem = str(error)
    except Exception as error:  # the FMU failed: a failed experiment, not a crash
        outcome.problem = f"{type(error).__name__}: {error}"
    return outcome


def replay(fmu, patterns=None, limit=None, roles=None):
    """[Replay] of every experiment of the FMU at `fmu` whose name matches a glob of
    `patterns` (all without) and whose file's role is one of `roles` (e.g.
    experiment/smoke-test; all without). LsRefError for an FMU without experiments."""
    _, experiments = read_experiments(fmu)
    chosen = [e for e in experiments
              if (not patterns or any(fnmatch.fnmatchcase(e.name, p) for p in patterns))
              and (not roles or e.role in roles)]
    if not experiments:
        raise LsRefError("its manifest names no experiments file")
    description = read_model_description(str(fmu))
    with tempfile.TemporaryDirectory(prefix="fmu_components_replay_") as folder:
        with zipfile.ZipFile(fmu) as archive:
            # what experiments name may lie anywhere in the FMU; the binaries are fmpy's
            archive.extractall(folder, [n for n in archive.namelist()
                                        if not n.startswith("binaries/")])
        return [replay_one(fmu, e, Path(folder), description, limit) for e in chosen]


def table(replays):
    """The printed table of replays."""
    lines = [("FMU", "experiment", "worst output", "deviation", "limit", "result", "wall s")]
    for r in replays:
        lines.append((str(r.fmu), r.name, r.worst_output,
                      f"{r.deviation:.3g}" if r.deviations else "-", f"{r.limit:g}",
                      "pass" if r.passed else r.verdict, f"{r.wall_time:.2f}"))
    return aligned(lines, right=(3, 4, 6))


def replay_files(paths, patterns=None, limit=None):
    """([Replay], [junit.Check]) of the experiments of every FMU in `paths`: a check per
    experiment, and a failed one for an FMU whose experiments cannot be read or of which
    no experiment matches `patterns`."""
    replays, checks = [], []
    for path in paths:
        try:
            found = replay(path, patterns, limit)
            if not found:
                raise LsRefError(f"no experiment matches {' '.join(patterns)}")
        except LsRefError as error:
            checks.append(Check(str(path), "reference experiments",
                                failure=f"{path}: {error}"))
            continue
        replays += found
        lines = table(found).splitlines()
        checks += [Check(str(r.fmu), r.name, "" if r.passed else r.verdict,
                         time=r.wall_time, output=f"{lines[0]}\n{line}")
                   for r, line in zip(found, lines[1:])]
    return replays, checks
