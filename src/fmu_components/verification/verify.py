"""The built FMUs against an independent solve of the same equations: each case of the
thesis test programme run through an FMU and compared with the solve.

This checks that the FMUs solve the model's equations right, not that the model describes
the real parts: ``measurements`` (``fmu-components validate``) compares the model with what
the thesis measured.

Every case of ``fmu_components.verification.cases`` is simulated with ``fmpy.simulate_fmu``
at its step size and tolerance (``<case>_ref.opt``), fed its ``<case>_in.csv``, and compared
with its ``<case>_ref.csv`` (the independent solve) in two ways:

* the FMI cross-check rule: ``fmpy.util.validate_result`` resamples the reference at 1000
  points, draws a band around it (+-10 % of its range, +-10 resampled points in time) and
  gives the share of samples outside it for the worst output; the case fails with more than
  10 % outside, as FMPy's cross-check does (``fmpy.cross_check.validate_result``). The band
  is coarse where a record is long and has fast features (the first tenth of a second of a
  200 s relaxation), so a few samples may fall outside while the strict norm is tiny;
* the strict norm: the largest |FMU - reference| of every output, in % of that output's
  peak-to-peak range in the reference; it must be <= 0.5 %.

``fmu-components verify`` (``commands/verify.py``) prints a table, writes PNG plots in the style of the thesis figures and a summary page to
the report folder (default reports/verification), and exits non-zero if any case fails.
"""

import math
from pathlib import Path

import numpy as np
from fmpy.util import validate_result

from ..export.identity import NotOurFmu, read_identity
from . import cases as programme
from . import reference
from .outcome import CROSS_CHECK_LIMIT, STRICT_LIMIT, Outcome

# The criteria a case passes by (module docstring), given here with the comparison.
__all__ = ["CROSS_CHECK_LIMIT", "STRICT_LIMIT", "Outcome", "built_fmus", "compare", "run_case"]


def compare(result, reference, stop_time):
    """(strict errors in % per output, cross-check outlier fraction, problem) of a result
    (structured array: time and outputs) against its reference table."""
    names = reference.dtype.names[1:]
    missing = [n for n in names if n not in result.dtype.names]
    if missing:
        return {}, 1.0, f"outputs missing: {', '.join(missing)}"
    if len(result) != len(reference) or not np.allclose(result["time"], reference["time"],
                                                        rtol=0, atol=1e-9):
        return {}, 1.0, (f"{len(result)} samples to t = {result['time'][-1]:g} s, the reference "
                         f"has {len(reference)} to {reference['time'][-1]:g} s")
    errors = {n: 100 * e if np.isfinite(e) else math.inf  # NaN fails
              for n, e in programme.column_errors(reference, result, names).items()}
    # validate_result nudges duplicate reference times in place: give it copies.
    outliers = float(validate_result(result[["time", *names]].copy(), reference.copy(),
                                     stop_time=stop_time))
    return errors, outliers, ""


def needs_own_reference(identity):
    """An engineer's own part, or another of the thesis's model structures: compared with
    the independent solve under its own parameter values, not the committed references."""
    return identity is not None and (identity.own or identity.structure != "final")


def run_case(case, fmu_path, reference_data=programme.REFERENCE_DATA, identity=None,
             tables=None):
    """One case through one FMU. An own part (``needs_own_reference``) is compared with
    the independent solve under its own values, made here; the thesis's FMUs with the
    committed references, read from `reference_data` unless given as `tables` (the
    (inputs, reference, options) of ``cases.read``: a campaign's worker gets them so)."""
    if needs_own_reference(identity):
        spec = reference.spec_from_parameters(identity.component, identity.values,
                                              identity.structure)
        inputs, expected, options = programme.generate(case, spec)
        options = case.options()
        part = Path(fmu_path).stem
    else:
        inputs, expected, options = tables or programme.read(case, reference_data)
        part = ""
    result, wall = programme.simulate_case(fmu_path, inputs, options,
                                           list(expected.dtype.names[1:]),
                                           label=f"{part or case.fmu}/{case.name}")
    errors, outliers, problem = compare(result, expected, options["StopTime"])
    return Outcome(case, errors, outliers, wall, result, expected, inputs, problem, part)


def built_fmus(folder):
    """{file name without .fmu: (path, Identity)} of every FMU this project built in
    `folder`: the thesis's under their components' names and any engineer's own part."""
    found = {}
    for path in sorted(Path(folder).glob("*.fmu")):
        try:
            identity = read_identity(path)
        except NotOurFmu:
            continue  # another tool's FMU: not one to verify
        found[path.stem] = (path, identity)
    return found
