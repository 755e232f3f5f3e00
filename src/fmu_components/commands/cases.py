"""The thesis test programme's cases (``verification.cases``): list them, regenerate their
reference data with the independent solver, or check the committed files.

    python -m fmu_components.commands.cases --list
    python -m fmu_components.commands.cases --regenerate [--fmu NAME] [--case GLOB]
    python -m fmu_components.commands.cases --check [--fmu NAME] [--case GLOB]
"""

import argparse
import sys
import time
from pathlib import Path

from ..runtime.catalog import COMPONENTS
from ..verification.cases import REFERENCE_DATA, check, generate, select, write


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="The thesis test programme: list the cases, regenerate their reference "
                    "data with the independent solver, or check the committed files.")
    action = parser.add_mutually_exclusive_group(required=True)
    action.add_argument("--list", action="store_true", help="list the cases")
    action.add_argument("--regenerate", action="store_true",
                        help="solve every selected case and write its files")
    action.add_argument("--check", action="store_true",
                        help="solve every selected case and compare with the committed files")
    parser.add_argument("--fmu", action="append", choices=sorted(COMPONENTS),
                        help="only this FMU (repeatable)")
    parser.add_argument("--case", action="append", metavar="GLOB",
                        help="only cases whose name or FMU/name matches (repeatable)")
    parser.add_argument("--reference-data", type=Path, default=REFERENCE_DATA)
    args = parser.parse_args(argv)
    cases = select(args.fmu, args.case)
    if not cases:
        parser.error("no case matches")
    if args.list:
        print(f"{'FMU':17s} {'case':26s} {'test':15s} {'step s':>7s} {'stop s':>7s} "
              f"{'samples':>7s}  thesis")
        for c in cases:
            print(f"{c.fmu:17s} {c.name:26s} {c.test:15s} {c.step:7g} {c.stop_time:7g} "
                  f"{len(c.times()):7d}  {c.figure}")
        return 0
    failed = 0
    started = time.perf_counter()
    for c in cases:
        case_started = time.perf_counter()
        if args.regenerate:
            write(c, generate(c), args.reference_data)
            outcome = "written"
        else:
            problems = check(c, args.reference_data)
            failed += bool(problems)
            outcome = "; ".join(problems) if problems else "reproduced"
        print(f"{c.key:45s} {time.perf_counter() - case_started:7.1f} s  {outcome}", flush=True)
    print(f"{len(cases)} cases in {time.perf_counter() - started:.0f} s"
          + (f", {failed} not reproduced" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
