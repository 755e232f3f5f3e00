"""Verify the built FMUs against an independent solve of the same equations.

The thesis test programme runs through each FMU and is compared with the solve
(``verification.verify``; how, and the criteria, are said there).

    fmu-components verify [--fmu NAME] [--case GLOB] [--report DIR] [--junit FILE]
                          [--scheduler ADDRESS] [--jobs N]

The cases run on a local Dask cluster (one worker per core), or on an existing one with
--scheduler (docs/campaigns.md); REPORT/results.csv gets each case's row as it finishes.

Given FMU files (any tool's), it replays the FMI-LS-REF reference experiments they carry
instead (``verification.replay``; every FMU this project builds carries its cases so):

    fmu-components verify path/to/X.fmu [--case GLOB] [--limit L] [--junit FILE]
"""

import sys
from pathlib import Path

from ..errors import UsageError
from ..runtime.catalog import COMPONENTS
from ..verification.cases import REFERENCE_DATA
from . import cluster


EXAMPLES = """examples:
  fmu-components verify                                   every case, report in reports/verification
  fmu-components verify --fmu TrackBushTorsion --case 'II_*'
  fmu-components verify --fmus fmus/python --report reports/verification-python
  fmu-components verify --scheduler tcp://head:8786       on a Dask cluster (docs/campaigns.md)
  fmu-components verify fmus/RoadWheelTyre.fmu --junit results.xml
                                                          the experiments the FMU carries
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
    parser.add_argument("--reference-data", type=Path, default=REFERENCE_DATA,
                        help="the thesis FMUs' committed references")
    parser.add_argument("fmu_files", nargs="*", type=Path, metavar="FMU",
                        help="FMU files, any tool's: replay the FMI-LS-REF reference "
                             "experiments each carries (docs/references.md)")
    parser.add_argument("--limit", type=float, metavar="L",
                        help="with FMU files: hold every experiment's deviation (largest "
                             "|FMU - reference| over the reference's range) to L, whatever "
                             "the experiment says")
    parser.add_argument("--junit", type=Path, metavar="FILE",
                        help="also write the results as JUnit XML, for CI")

    cluster.add_arguments(parser)


def _run(runs, args):
    """Every (case, FMU, identity) run on the engine the options name (commands/cluster.py),
    each case's plot drawn in its task, each case's row in REPORT/results.csv as it
    finishes; then the report, the tests' plots drawn on the same engine and the rest
    assembled here: (the Outcomes in the runs' order, the summary's path). A case that
    cannot run is a failed case, not a crash."""
    from tqdm import tqdm

    from ..campaign.grid import verification_grid
    from ..campaign.run import run_grid
    from ..verification.outcome import Outcome

    grid = verification_grid(runs, args.reference_data, drawn=True)
    with cluster.engine(args) as engine:
        done = run_grid(grid, args.report, engine, keep=True, what="simulating and plotting")
        from ..verification.report import case_plot_name, plot_count, write_report

        failed = {run.key: message for run, message in done.failures}
        outcomes, pngs = [], {}
        for run, (case, path, _) in zip(grid.runs, runs):
            if run.key in failed:
                outcomes.append(Outcome(case, problem=failed[run.key],
                                        part="" if path.stem == case.fmu else path.stem))
                continue
            outcome, png = done.results[run.key]
            outcomes.append(outcome)
            if png is not None:
                pngs[case_plot_name(outcome)] = png
        progress = tqdm(total=plot_count(outcomes, pngs), desc="plotting", unit="plot",
                        file=sys.stderr, disable=None)
        drawn = _drawn(engine) if engine.client is not None else None
        summary = write_report(outcomes, args.report, progress, drawn, pngs)
        progress.close()
    return outcomes, summary


def _drawn(engine):
    """The report's plots drawn on the engine's workers (verification.report.plot_png)."""
    from ..campaign.engine import Failure
    from ..verification.report import plot_png

    def drawn(jobs):
        for index, png in engine.stream(plot_png, jobs):
            if isinstance(png, Failure):
                raise RuntimeError(f"a plot of the report failed: {png.message}")
            yield index, png
    return drawn


def run_command(args):
    if args.fmu_files:
        return replay_command(args)
    if args.limit is not None:
        raise UsageError("--limit goes with FMU files (verify X.fmu --limit L); the thesis "
                         "programme's criteria are fixed (docs/validation.md)")
    from ..verification import cases as programme
    from ..verification.outcome import CROSS_CHECK_LIMIT, STRICT_LIMIT, table
    from ..verification.verify import built_fmus

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
    outcomes, summary = _run(runs, args)
    print(table(outcomes))
    failed = [o for o in outcomes if not o.passed]
    print(f"\n{len(outcomes) - len(failed)} of {len(outcomes)} cases pass (strict error <= "
          f"{STRICT_LIMIT:g} %, cross-check <= {100 * CROSS_CHECK_LIMIT:g} % outside the band); "
          f"report: {summary}")
    if args.junit:
        from ..verification.junit import write_junit
        from ..verification.outcome import junit_checks
        print(f"JUnit XML: {write_junit(args.junit, 'verify', junit_checks(outcomes))}")
    return 1 if failed else 0


def replay_command(args):
    """The reference experiments of FMU files, replayed."""
    from ..verification.replay import replay_files, table

    if args.fmu:
        raise UsageError("--fmu picks among the built FMUs of --fmus; with FMU files, give "
                         "only the files (and --case to pick experiments)")
    if args.limit is not None and not args.limit > 0:  # NaN too
        raise UsageError(f"--limit {args.limit}: give a positive fraction of the reference's "
                         f"range, e.g. 0.005")
    missing = [str(p) for p in args.fmu_files if not p.is_file()]
    if missing:
        raise UsageError(f"no such FMU file: {', '.join(missing)}")
    replays, checks = replay_files(args.fmu_files, args.case, args.limit)
    print(table(replays))
    failed = [c for c in checks if c.failure]
    print(f"\n{len(checks) - len(failed)} of {len(checks)} experiments pass")
    if args.junit:
        from ..verification.junit import write_junit
        print(f"JUnit XML: {write_junit(args.junit, 'verify', checks)}")
    return 1 if failed else 0
