"""Verify the built FMUs against an independent solve of the same equations.

The thesis test programme runs through each FMU and is compared with the solve.

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

    fmu-components verify [--fmu NAME] [--case GLOB] [--report DIR]

prints a table, writes PNG plots in the style of the thesis figures and a summary page to
the report folder (default reports/verification), and exits non-zero if any case fails.
"""

import math
import sys
import time
from pathlib import Path

import numpy as np
from fmpy import simulate_fmu
from fmpy.util import validate_result
from tqdm import tqdm

from ..errors import UsageError
from ..runtime.catalog import COMPONENTS
from ..export.identity import NotOurFmu, read_identity
from . import cases as programme
from . import reference
from .outcome import CROSS_CHECK_LIMIT, STRICT_LIMIT, Outcome, table


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


def simulate_case(fmu_path, inputs, options, outputs):
    """(fmpy's result, wall time in s) of one case's input table run through an FMU with the
    case's options (StartTime, StopTime, StepSize, RelTol): the output interval is the step."""
    started = time.perf_counter()
    result = simulate_fmu(str(fmu_path), start_time=options["StartTime"],
                          stop_time=options["StopTime"], output_interval=options["StepSize"],
                          relative_tolerance=options["RelTol"], input=inputs, output=outputs)
    return result, time.perf_counter() - started


def run_case(case, fmu_path, reference_data=programme.REFERENCE_DATA, identity=None):
    """One case through one FMU. An engineer's own part, or another of the thesis's model
    structures, is compared with the independent solve under its own parameter values,
    made here; the thesis's FMUs with the committed references."""
    if identity is not None and (identity.own or identity.structure != "final"):
        spec = reference.spec_from_parameters(identity.component, identity.values,
                                              identity.structure)
        inputs, expected, options = programme.generate(case, spec)
        options = case.options()
        part = Path(fmu_path).stem
    else:
        inputs, expected, options = programme.read(case, reference_data)
        part = ""
    result, wall = simulate_case(fmu_path, inputs, options, list(expected.dtype.names[1:]))
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


EXAMPLES = """examples:
  fmu-components verify                                   every case, report in reports/verification
  fmu-components verify --fmu TrackBushTorsion --case 'II_*'
  fmu-components verify --fmus fmus/python --report reports/verification-python
"""


def configure(parser):
    parser.add_argument("--fmu", action="append", metavar="NAME",
                        help="only this FMU: a component (" + ", ".join(sorted(COMPONENTS))
                             + ") or an own part's name (repeatable)")
    parser.add_argument("--case", action="append", metavar="GLOB",
                        help="only cases whose name or FMU/name matches (repeatable)")
    parser.add_argument("--report", type=Path, default=Path("reports") / "verification",
                        help="folder for the plots and summary.md")
    parser.add_argument("--fmus", type=Path, default=Path("fmus"),
                        help="folder holding the built FMUs: the thesis's <Component>.fmu and "
                             "any own part (its reference is solved with its own values)")
    parser.add_argument("--reference-data", type=Path, default=programme.REFERENCE_DATA,
                        help="the thesis FMUs' committed references")


def run_command(args):
    found = built_fmus(args.fmus)
    unknown = [n for n in args.fmu or () if n not in found and n not in COMPONENTS]
    if unknown:
        raise UsageError(f"--fmu {unknown[0]}: no such FMU in {args.fmus} (it has: "
                         f"{', '.join(found) or 'none'})")
    wanted = args.fmu or [n for n in found] or sorted(COMPONENTS)
    component = {n: found[n][1].component if n in found else n for n in wanted}
    cases = {n: programme.select([component[n]], args.case) for n in wanted}
    if not any(cases.values()):
        raise UsageError("no case matches: see the case names in reference_data/<FMU>/")
    missing = sorted(str(args.fmus / f"{n}.fmu") for n in wanted if n not in found and cases[n])
    if missing:
        raise UsageError(f"not built: {', '.join(missing)} (run fmu-components build first)")
    runs = [(case, *found[name]) for name in wanted for case in cases[name]]
    selected = [case for case, _, _ in runs]

    outcomes = []
    # One bar over the simulations and the plots (the plots take most of the time). It draws
    # on a terminal; in a CI log (no terminal) it stays out of the way.
    progress = tqdm(total=len(selected), desc="simulating", unit="step", file=sys.stderr,
                    disable=None)
    for case, path, identity in runs:
        progress.set_postfix_str(f"{path.stem}/{case.name}")
        try:
            outcomes.append(run_case(case, path, args.reference_data, identity))
        except Exception as exc:  # a case that cannot run is a failed case, not a crash
            outcomes.append(Outcome(case, problem=f"{type(exc).__name__}: {exc}",
                                    part="" if path.stem == case.fmu else path.stem))
        progress.update(1)

    from .report import plot_count, write_report  # matplotlib only once there is something to plot
    progress.total = len(selected) + plot_count(outcomes)
    progress.set_description("plotting")
    progress.set_postfix_str("")
    progress.refresh()
    summary = write_report(outcomes, args.report, progress)
    progress.close()
    print(table(outcomes))
    failed = [o for o in outcomes if not o.passed]
    print(f"\n{len(outcomes) - len(failed)} of {len(outcomes)} cases pass (strict error <= "
          f"{STRICT_LIMIT:g} %, cross-check <= {100 * CROSS_CHECK_LIMIT:g} % outside the band); "
          f"report: {summary}")
    return 1 if failed else 0
