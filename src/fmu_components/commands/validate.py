"""Validate the model against every number the thesis measured on its rigs.

    fmu-components validate [--fmu NAME] [--case GLOB] [--fmus DIR] [--report DIR] [--strict]
                            [--junit FILE] [--scheduler ADDRESS] [--jobs N]

Runs every selected row of ``reference_data/thesis/measurements.csv`` that names a metric
through the built FMUs (``verification.measurements``), prints the table of measured and
model values, and writes the report (``verification.measurements_report``: summary.md and
plots, default reports/validation; results.csv gets each case's row as it finishes, as
verify's). Exit status 0 when every row ran, 1 when an FMU failed to run; with
``--strict`` also 1 when a judged row lies outside the +-10 % band or breaks its bound.
``fmu-components verify`` is the other check: the FMUs against an independent solve of the
same equations.
"""

from pathlib import Path

from ..errors import UsageError
from ..runtime.catalog import COMPONENTS
from ..verification.measurements import BAND
from . import cluster

EXAMPLES = """examples:
  fmu-components validate                    every measured quantity, report in reports/validation
  fmu-components validate --fmu RotaryDamper --case 'damper-A6-1-*'
  fmu-components validate --fmus fmus/python --report reports/validation-python --strict
  fmu-components validate --scheduler tcp://head:8786     on a Dask cluster (docs/campaigns.md)
"""


def configure(parser):
    parser.add_argument("--fmu", action="append", choices=sorted(COMPONENTS),
                        help="only this FMU's measurements (repeatable)")
    parser.add_argument("--case", action="append", metavar="GLOB",
                        help="only rows whose id matches (repeatable; the ids are in "
                             "reference_data/thesis/measurements.csv)")
    parser.add_argument("--fmus", type=Path, default=Path("fmus"),
                        help="folder holding the built <FMU>.fmu files (default fmus/, the "
                             "native flavour; fmus/python for the Python one)")
    parser.add_argument("--report", type=Path, default=Path("reports") / "validation",
                        help="folder for the plots and summary.md (default reports/validation)")
    parser.add_argument("--strict", action="store_true",
                        help=f"exit 1 also when a measured quantity lies outside +-{BAND:g} %% "
                             f"(or its bound); see docs/validation.md")
    parser.add_argument("--junit", type=Path, metavar="FILE",
                        help="also write the results as JUnit XML, for CI (a row fails there "
                             "as it counts against the exit status)")
    cluster.add_arguments(parser)


def _run_cases(runs, cases, engine, folder):
    """Each case through its FMU on the engine (the FMU travels with the task), its result
    kept in `runs` and its row in FOLDER/results.csv as it finishes."""
    from ..campaign.grid import validation_grid
    from ..campaign.run import run_grid

    done = run_grid(validation_grid(cases, runs.fmu), folder, engine, keep=True,
                    what="simulating")
    failed = {run.key: message for run, message in done.failures}
    for case in cases:
        runs.keep(case, failed[case.key] if case.key in failed else done.results[case.key][0])


def run_command(args):
    from ..verification.measurements import (Runs, compare_all, read_measurements, select,
                                             table, tally)

    selected = select(read_measurements(), args.fmu, args.case)
    if not selected:
        raise UsageError("no measured quantity matches: the ids are in "
                         "reference_data/thesis/measurements.csv (the cases of the test "
                         "programme against the independent solve are run by "
                         "`fmu-components verify`)")
    needed = sorted({m.component for m in selected if m.metric})
    missing = [str(args.fmus / f"{name}.fmu") for name in needed
               if not (args.fmus / f"{name}.fmu").exists()]
    if missing:
        raise UsageError(f"not built: {', '.join(missing)} (run fmu-components build first)")
    runs = Runs(args.fmus)
    cases = {c.key: c for m in selected if m.metric for c in runs.select(m)}
    with cluster.engine(args) as engine:  # every case runs once, on the engine
        _run_cases(runs, list(cases.values()), engine, args.report)
    comparisons = compare_all(selected, runs)

    from ..verification.measurements_report import write_report  # matplotlib only once there is a result
    summary = write_report(comparisons, runs, args.report)
    print(table(comparisons))
    print(f"\n{tally(comparisons)}\nreport: {summary}")
    if args.junit:
        from ..verification.junit import write_junit
        from ..verification.measurements import junit_checks
        checks = junit_checks(comparisons, args.strict)
        print(f"JUnit XML: {write_junit(args.junit, 'validate', checks)}")
    failed = any(c.problem for c in comparisons)
    outside = any(c.inside is False for c in comparisons)
    return 1 if failed or (args.strict and outside) else 0
