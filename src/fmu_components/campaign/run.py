"""A campaign's run: every run of a grid not yet in the results table goes to the engine,
and each row joins the table as its run finishes (``table``: written whole every time).

Interrupted (Ctrl-C, the client killed), the table holds every run that finished;
``resume=True`` runs only the others, so that nothing is computed twice. A run that fails
is a row with status ``failed`` and the message, reported at the end with its values; the
rest of the campaign goes on, and a resumed campaign tries the failed runs again.
"""

import sys
from dataclasses import dataclass, field

from .engine import Failure, Progress
from .table import MESSAGE, STATUS, ResultsTable


@dataclass
class Outcome:
    table: ResultsTable
    ran: int  # runs computed by this call
    skipped: int  # runs the table held already
    failures: list = field(default_factory=list)  # (Run, message)
    results: dict = field(default_factory=dict)  # run key -> the task's own result


def run_grid(grid, folder, engine, resume=False, keep=False, what=None):
    """Run `grid` (``grid.Grid``) on `engine`, its table in `folder`. keep: also return
    each task's own result (the verification's outcomes, for their report)."""
    table = ResultsTable(folder, resume)
    # the costliest first: the last runs to finish are short ones, and no worker idles long
    todo = sorted((run for run in grid.runs if run.key not in table), key=lambda r: -r.cost)
    outcome = Outcome(table, len(todo), len(grid.runs) - len(todo))
    if outcome.skipped:
        print(f"resuming: {outcome.skipped} of {len(grid.runs)} runs done in {table.path}, "
              f"{len(todo)} to run", file=sys.stderr)
    progress = Progress(len(grid.runs), outcome.skipped, what or grid.kind)
    try:
        for index, result in engine.stream(grid.function, [run.arguments for run in todo]):
            run = todo[index]
            row = {"run": run.key, **run.values}
            if isinstance(result, Failure):
                row.update({STATUS: "failed", MESSAGE: result.message})
                outcome.failures.append((run, result.message))
            else:
                row.update({k: v for k, v in grid.to_row(run, result).items() if k != "run"})
                row[STATUS] = "ok"
                if keep:
                    outcome.results[run.key] = result
            table.add(row)
            progress.update(run.key)
    finally:
        progress.close()
    if not todo:
        table.write()
    table.write_parquet()
    return outcome
