"""Verify the built FMUs against an independent solve of the same equations.

The thesis test programme runs through each FMU and is compared with the solve
(``verification.verify``; how, and the criteria, are said there).

    fmu-components verify [--fmu NAME] [--case GLOB] [--report DIR]
"""

import sys
from pathlib import Path

from ..errors import UsageError
from ..runtime.catalog import COMPONENTS
from ..verification.cases import REFERENCE_DATA


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
    parser.add_argument("--reference-data", type=Path, default=REFERENCE_DATA,
                        help="the thesis FMUs' committed references")


def run_command(args):
    from tqdm import tqdm

    from ..verification import cases as programme
    from ..verification.outcome import CROSS_CHECK_LIMIT, STRICT_LIMIT, Outcome, table
    from ..verification.verify import built_fmus, run_case

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

    from ..verification.report import plot_count, write_report  # matplotlib only once there is something to plot
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
