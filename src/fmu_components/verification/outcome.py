"""One verification case's outcome (the FMU against its independent reference) and the
table of outcomes that the command prints and the report shows."""

from dataclasses import dataclass, field

import numpy as np

from . import cases as programme
from .junit import Check

STRICT_LIMIT = 0.5  # % of the reference's peak-to-peak range
CROSS_CHECK_LIMIT = 0.1  # share of samples outside the band


@dataclass
class Outcome:
    case: programme.Case
    errors: dict = field(default_factory=dict)  # output -> strict error, %
    outliers: float = 1.0  # fraction of samples outside the cross-check band (worst output)
    wall_time: float = 0.0
    result: np.ndarray = None
    reference: np.ndarray = None
    inputs: np.ndarray = None
    problem: str = ""  # why the case could not be compared at all
    part: str = ""  # an engineer's own part run through its component's cases: its name

    @property
    def name(self):
        """The FMU's model name: the component's, or an own part's."""
        return self.part or self.case.fmu

    @property
    def strict_error(self):
        return max(self.errors.values()) if self.errors else float("inf")

    @property
    def worst_output(self):
        return max(self.errors, key=self.errors.get) if self.errors else ""

    @property
    def passed(self):
        return (not self.problem and self.strict_error <= STRICT_LIMIT
                and self.outliers <= CROSS_CHECK_LIMIT)


def rows(outcomes):
    """The result table: a header and one row of strings per case."""
    table = [("FMU", "case", "strict error %", "worst output", "cross-check inside band",
              "result", "wall s")]
    for o in outcomes:
        table.append((o.name, o.case.name, f"{o.strict_error:.4f}" if o.errors else "-",
                      o.worst_output, f"{100 * (1 - o.outliers):.2f} %",
                      "pass" if o.passed else f"FAIL{': ' + o.problem if o.problem else ''}",
                      f"{o.wall_time:.2f}"))
    return table


def table(outcomes):
    return aligned(rows(outcomes), right=(2, 4, 6))


def aligned(lines, right=()):
    """Rows of strings as a plain-text table: columns padded to their widest cell, the
    `right` ones (numbers) flush right."""
    widths = [max(len(row[i]) for row in lines) for i in range(len(lines[0]))]
    return "\n".join("  ".join(cell.rjust(w) if i in right else cell.ljust(w)
                               for i, (cell, w) in enumerate(zip(row, widths))).rstrip()
                     for row in lines)


def junit_checks(outcomes):
    """A junit.Check per outcome, its table row as the output."""
    lines = table(outcomes).splitlines()
    return [Check(o.name, o.case.name, failure="" if o.passed else o.problem or (
        f"strict error {o.strict_error:.4g} % (limit {STRICT_LIMIT:g} %), "
        f"{100 * o.outliers:.2f} % outside the cross-check band (limit "
        f"{100 * CROSS_CHECK_LIMIT:g} %)"), time=o.wall_time, output=f"{lines[0]}\n{line}")
            for o, line in zip(outcomes, lines[1:])]
