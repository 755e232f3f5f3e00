"""The coupling study both examples run (`--coupling-study`) and benchmarks/coupling_study.py
prints: every scheme at every host step, against a fine reference and against `converged`
at the same step, with what it cost.

    total error  max |run - reference| of a history on the STUDY_GRID, in % of the
                 reference's range (the host's own step error included)
    own error    the same against `converged` at the same host step: what the coupling
                 adds to the host's error
    cost         per host step and FMU: doSteps, state saves and restores; the host's
                 solves per step; wall seconds per simulated second

Also the example scripts' `--csv`: each run's histories as CSV, each column headed by its
name and SI unit.
"""

import contextlib
import csv
import math
import sys
import time
import warnings

import numpy as np
from tqdm import tqdm

from fmu_components.coupling import DEFAULT_SCHEME, SCHEMES

STUDY_STEPS = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)
STUDY_GRID = 4e-3  # s: on every host step's grid
# The schemes in the order of the table: the non-iterative ones, then the repeating ones.
STUDY_SCHEMES = ("explicit", "predicted", "nepce", "corrected", "iterated", "converged")
assert set(STUDY_SCHEMES) == set(SCHEMES)


def history_error(result, reference, key):
    """Max |result - reference| of one history (or of each column of a 2-D one) on the
    study grid, in % of the reference's range (the largest over the columns)."""
    end = min(result["time"][-1], reference["time"][-1])
    grid = np.arange(0.0, end + 1e-12, STUDY_GRID)
    got, expected = np.asarray(result[key]), np.asarray(reference[key])
    if got.ndim == 1:
        got, expected = got[:, None], expected[:, None]
    worst = 0.0
    for column in range(got.shape[1]):
        a = np.interp(grid, result["time"], got[:, column])
        b = np.interp(grid, reference["time"], expected[:, column])
        worst = max(worst, np.max(np.abs(a - b)) / np.ptp(expected[:, column]))
    return 100.0 * worst


def timed_run(run, scheme, step):
    """run(scheme, step) -> histories with "costs"; adds "wall per simulated second"."""
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # converged's pass-limit warning is counted instead
        result = run(scheme, step)
    result["wall_per_s"] = (time.perf_counter() - started) / result["time"][-1]
    return result


def study(run, reference, keys, steps=STUDY_STEPS, schemes=STUDY_SCHEMES, progress=None):
    """Rows of the study: {(scheme, step): {"total": {key: %}, "own": {key: %},
    "costs": {...}, "wall_per_s": s}} or, for a run that failed, the failure's first
    line."""
    table = {}
    for step in steps:
        runs = {}
        for scheme in ("converged",) + tuple(s for s in schemes if s != "converged"):
            try:
                runs[scheme] = timed_run(run, scheme, step)
            except Exception as failure:  # a coupling that goes unstable fails the host
                runs[scheme] = str(failure).strip().splitlines()[0]
            if progress:
                progress(scheme, step)
        for scheme in schemes:
            result = runs[scheme]
            if isinstance(result, str):
                table[scheme, step] = result
                continue
            converged = runs["converged"]
            table[scheme, step] = {
                "total": {k: history_error(result, reference, k) for k in keys},
                "own": ({k: history_error(result, converged, k) for k in keys}
                        if not isinstance(converged, str) else {}),
                "costs": result["costs"], "wall_per_s": result["wall_per_s"]}
    return table


def tightness(run, keys, steps=STUDY_STEPS, tolerance=1e-12):
    """How converged `converged` is: at each host step, its histories against the same
    scheme converged to `tolerance` (% of the latter's range, the worst over `keys`)."""
    from fmu_components.coupling.schemes import Converged

    found = {}
    for step in steps:
        default, tight = (timed_run(run, scheme, step)
                          for scheme in ("converged", Converged(tolerance=tolerance, passes=50)))
        found[step] = max(history_error(default, tight, key) for key in keys)
    return found


def format_table(table, keys, labels=None):
    """The study as a Markdown table: errors in %, costs per host step and FMU."""
    labels = labels or {k: k.replace("_", " ") for k in keys}
    head = (["scheme", "host step"] + [f"total: {labels[k]}" for k in keys]
            + [f"own: {labels[k]}" for k in keys]
            + ["doSteps", "saves", "restores", "host solves", "wall s per s"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for (scheme, step), row in table.items():
        cells = [scheme, f"{step * 1e3:g} ms"]
        if isinstance(row, str):
            cells += [f"failed: {row}"] + [""] * (len(head) - 3)
        else:
            cells += [_percent(row["total"][k]) for k in keys]
            cells += [_percent(row["own"][k]) if row["own"] else "-" for k in keys]
            costs = row["costs"]
            cells += [f"{costs['do_steps']:.2f}", f"{costs['saves']:.2f}",
                      f"{costs['restores']:.2f}", f"{costs['passes']:.2f}",
                      f"{row['wall_per_s']:.3g}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _percent(value):
    if value == 0.0:
        return "0 %"
    if value >= 100:
        return f"{value:.0f} %"
    return f"{value:.2g} %" if value >= 0.01 else f"{value:.1e} %"


def write_csv(path, columns, units):
    """Histories as CSV, each column headed by its name and SI unit ("time (s)"):
    `columns` maps a name to a history (1-D) or a list of (name, 1-D) for a history with one
    column per joint or link; `units` maps each of its names to the unit."""
    names, data = [], []
    for name, values in columns.items():
        for sub, column in values if isinstance(values, list) else [(name, values)]:
            names.append(f"{sub} ({units[name]})")
            data.append(np.asarray(column, dtype=float))
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(names)
        for row in zip(*data):
            writer.writerow([repr(float(v)) if math.isfinite(v) else "nan" for v in row])


# --- what both example scripts' command lines share ---------------------------------------

def add_arguments(parser, study_help):
    parser.add_argument("--coupling", choices=sorted(SCHEMES), default=DEFAULT_SCHEME,
                        help=f"coupling scheme (default {DEFAULT_SCHEME}; docs/coupling.md)")
    parser.add_argument("--csv", action="store_true",
                        help="also write each run's histories to --out as CSV (SI units)")
    parser.add_argument("--coupling-study", action="store_true", help=study_help)


def progress(scheme, step):
    """A study's progress, on stderr (the table goes to stdout)."""
    print(f"  {scheme} at {step * 1e3:g} ms done", file=sys.stderr, flush=True)


@contextlib.contextmanager
def time_progress(description, end_time, show=True):
    """A bar on stderr over the simulated time of a long run; yields the function that
    moves it to a time reached (None when not shown)."""
    if not show:
        yield None
        return
    with tqdm(total=end_time, desc=description, file=sys.stderr, unit="s",
              bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.3f}/{total:.3f} s "
                         "simulated [{elapsed}<{remaining}]") as bar:
        def reached(t):
            if t > bar.n:
                bar.update(min(t, end_time) - bar.n)

        yield reached


def write_study(out, text):
    """Print the study and write it to out/coupling_study.md."""
    print("\n" + text)
    (out / "coupling_study.md").write_text(text)
