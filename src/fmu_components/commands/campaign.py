"""Run a campaign: the station or vehicle example, the rig or the test programme over a
grid of parameters, on a local or a remote Dask cluster.

    fmu-components campaign GRID.json [--report DIR] [--scheduler ADDRESS] [--jobs N] [--resume]

The grid file says what to run over which values (``campaign.grid``); every run's row joins
DIR/results.csv as it finishes (``campaign.table``); ``--resume`` goes on with an
interrupted campaign. docs/campaigns.md is the user's guide.
"""

from pathlib import Path

from ..errors import UsageError
from . import cluster

EXAMPLES = """examples:
  fmu-components campaign ride_map.json --report reports/ride_map
  fmu-components campaign ride_map.json --report reports/ride_map --resume
  fmu-components campaign sweep.json --scheduler tcp://scheduler:8786

GRID.json: {"run": "station", "speeds": [3, 8, 15], "courses": {"bump": {}},
            "parameter_sets": {"thesis": {}, "part": "part.ssv"}}
"""


def configure(parser):
    parser.add_argument("grid", type=Path, metavar="GRID.json",
                        help="what to run over which values (docs/campaigns.md)")
    parser.add_argument("--report", type=Path, default=None, metavar="DIR",
                        help="folder for results.csv (default reports/campaign/<GRID>)")
    parser.add_argument("--resume", action="store_true",
                        help="go on with the campaign in DIR: run only what is not done")
    cluster.add_arguments(parser)


def run_command(args):
    from ..campaign.grid import GridError, read_grid
    from ..campaign.run import run_grid

    try:
        grid = read_grid(args.grid)
    except GridError as error:
        raise UsageError(str(error)) from None
    report = args.report or Path("reports") / "campaign" / args.grid.stem
    if (report / "results.csv").exists() and not args.resume:
        raise UsageError(f"{report / 'results.csv'} holds an earlier campaign's results: give "
                         f"--resume to go on with it, or another --report folder")
    with cluster.engine(args) as engine:
        outcome = run_grid(grid, report, engine, resume=args.resume)
    for run, message in outcome.failures:
        print(f"failed: {run.key}: {message}")
    done = len(grid.runs) - len(outcome.failures)
    print(f"{done} of {len(grid.runs)} runs done ({outcome.ran} run now, {outcome.skipped} "
          f"before){f', {len(outcome.failures)} failed' if outcome.failures else ''}; "
          f"results: {outcome.table.path}")
    return 1 if outcome.failures else 0
