"""Identify a rubber component's parameters from measured data: fmu-components fit.

    fmu-components fit --component TrackBushRadial --out bush.json loops_1hz.csv relax.csv

The data formats, the method and the report are described in ``lab.fit``.
"""

import sys
from pathlib import Path

from ..errors import UsageError
from ..runtime.catalog import STRUCTURES
from . import cluster

EXAMPLES = """examples:
  fmu-components fit --component TrackBushRadial --out bush.json test1.csv test2.csv
  fmu-components fit --component TrackBushTorsion --fix geometric.h elastic.a2 elastic.a3 \\
      --out torsion.json sweep.csv relaxation.csv
  fmu-components fit --component RoadWheelTyre --out tyre.json rig_table.csv

DATA.csv: time,deflection,force (a measured test, SI) or
preload,amplitude,frequency,dynamic_stiffness,loss_angle_deg (a rig table, SI and deg).
"""

RUBBER = ("RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion")


def configure(parser):
    parser.add_argument("--component", required=True, metavar="NAME",
                        help=f"the FMU's name: {', '.join(RUBBER)}")
    parser.add_argument("--fix", nargs="+", default=[], metavar="NAME",
                        help="parameters kept at their thesis values (fitted: k1 c1 xi1 ... "
                             "of each Maxwell element, elastic.a0..a3, geometric.h)")
    parser.add_argument("--structure", default="final", choices=list(STRUCTURES),
                        help="the thesis's model structure (default: final)")
    parser.add_argument("--out", required=True, type=Path, metavar="PARAMS.json",
                        help="the fitted parameters (JSON); PARAMS.ssv (SSP) and the report go "
                             "beside it")
    parser.add_argument("--starts", type=int, default=4,
                        help="starting points, fitted in parallel (default: 4; each a task "
                             "on the cluster)")
    cluster.add_arguments(parser)
    parser.add_argument("data", nargs="+", type=Path, metavar="DATA.csv",
                        help="one measured test (time,deflection,force) or rig table per file")


def run_command(args):
    from ..lab.fit import fit, fitted_names, write_parameters
    from ..lab.fit_report import write_report
    from ..lab.history import HistoryError, component_definition
    from ..lab.measured import History, read_data

    if args.component not in RUBBER:
        raise UsageError(f"--component {args.component}: the fit identifies a rubber "
                         f"component's parameters; give one of {', '.join(RUBBER)}")
    try:
        definition = component_definition(args.component, args.structure)
    except KeyError as error:
        raise UsageError(f"--structure {args.structure}: {error.args[0]}") from None
    unknown = [n for n in args.fix if n not in fitted_names(definition)]
    if unknown:
        raise UsageError(f"--fix {unknown[0]}: not a fitted parameter of {args.component} "
                         f"({args.structure}); give any of {' '.join(fitted_names(definition))}")
    if args.starts < 1:
        raise UsageError("--starts must be 1 or more")
    tests = [read_data(path, definition) for path in args.data]
    for test in tests:
        if isinstance(test, History):
            _, deflection, force = test.columns
            print(f"{test.path}: deflection from column {deflection!r}, load from column "
                  f"{force!r}", file=sys.stderr)
    from ..campaign.tasks import fit_runner

    try:
        with cluster.engine(args) as engine:  # the starts on a Dask cluster (commands/cluster.py)
            result = fit(args.component, tests, args.fix, args.structure, args.starts,
                         runner=fit_runner(engine, engine.say))
    except HistoryError as error:
        raise UsageError(str(error)) from None
    args.out.parent.mkdir(parents=True, exist_ok=True)
    ssv = write_parameters(args.out, result.values, definition)
    report = write_report(result, args.out)
    print(f"wrote {args.out}, {ssv} and {report} (fit in {result.wall_time:.1f} s)")
    for note in result.warnings():
        print(f"warning: {note}", file=sys.stderr)
    return 0
