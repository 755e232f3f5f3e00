"""A campaign's results table: one row per run, written as the runs finish.

``results.csv`` in the report folder is rewritten whole (``lab.files.written_whole``: a
temporary file renamed over it) after every finished run, so that a campaign stopped at
any moment (Ctrl-C, the client killed) leaves a whole table of the runs done, never a
half-written one; ``results.parquet`` is written beside it at the end where pyarrow is
installed. Each row's ``run`` column names the run by its parameters; ``--resume`` reads
the table, keeps its finished rows and runs only the others.

Numbers are written with ``repr``: read back, they are the same floats bit for bit.
Columns that time a run end in ``_s`` (``wall_s``), so that a reader comparing two
campaigns can leave them out (``TIMING_SUFFIX``); ``status`` is ``ok`` or ``failed``, and
``message`` says why a run failed.
"""

import csv

from ..lab.files import written_whole

FILE = "results.csv"
TIMING_SUFFIX = "_s"
STATUS, MESSAGE = "status", "message"


def _text(value):
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if hasattr(value, "item"):  # a numpy scalar
        return _text(value.item())
    return "" if value is None else str(value)


def _value(text):
    """A cell read back: a number where it is one (the same float), else the text."""
    if text in ("True", "False"):
        return text == "True"
    try:
        number = float(text)
    except ValueError:
        return text
    return int(text) if number.is_integer() and text.lstrip("-").isdigit() else number


class ResultsTable:
    """The table of `folder`: rows by run, in the order they finished."""

    def __init__(self, folder, resume=False):
        self.folder = folder
        self.path = folder / FILE
        self.rows = {}
        if resume and self.path.exists():  # else an earlier table is replaced
            for row in read(self.path):
                if row.get(STATUS) == "ok":
                    self.rows[row["run"]] = row

    def __contains__(self, run):
        return run in self.rows

    def add(self, row):
        """Keep `row` (a dict with a `run` key) and write the table."""
        self.rows[row["run"]] = row
        self.write()

    def columns(self):
        columns = ["run"]
        for row in self.rows.values():
            columns += [c for c in row if c not in columns]
        # the outcome and the timings last, so that the parameters and results lead
        tail = [STATUS, MESSAGE] + [c for c in columns if c.endswith(TIMING_SUFFIX)]
        return [c for c in columns if c not in tail] + [c for c in tail if c in columns]

    def write(self):
        self.folder.mkdir(parents=True, exist_ok=True)
        columns = self.columns()
        with written_whole(self.path) as whole, open(whole, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(columns)
            for row in self.rows.values():
                writer.writerow([_text(row.get(c)) for c in columns])
        return self.path

    def write_parquet(self):
        """results.parquet beside the CSV, where pyarrow is installed: its path or None."""
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            return None
        path = self.folder / "results.parquet"
        columns = self.columns()
        rows = list(self.rows.values())
        table = pa.table({c: [_cell(r.get(c)) for r in rows] for c in columns})
        with written_whole(path) as whole:
            pq.write_table(table, whole)
        return path


def _cell(value):
    if hasattr(value, "item"):
        return value.item()
    return value


def read(path):
    """The rows of a results table as dicts, numbers as numbers."""
    with open(path, newline="") as f:
        return [{k: _value(v) for k, v in row.items()} for row in csv.DictReader(f)]


def without_timings(rows):
    """The rows without their timing columns: what two campaigns of the same runs share."""
    return [{k: v for k, v in row.items() if not k.endswith(TIMING_SUFFIX)} for row in rows]
