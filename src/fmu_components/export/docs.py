"""Markdown tables of each FMU's variables, generated from the catalog.

    python -m fmu_components.export.docs    # the tables in README.md come from here
"""

import re

from ..runtime.catalog import COMPONENTS
from ..runtime.units import UNITS

TABLE_POINT = re.compile(r"^dashpot\.(rate|torque)\[(\d+)\]$")


def _start(variable):
    if variable.start is None:
        return ""
    text = f"{variable.start:.6g}"
    if variable.display_unit:
        factor = dict(UNITS[variable.unit][1])[variable.display_unit]
        text += f" ({variable.start * factor:.6g} {variable.display_unit})"
    return text


def _cell(text):
    return text.replace("|", "\\|")


def _unit(variable):
    return variable.unit + (f" [{variable.display_unit}]" if variable.display_unit else "")


def variables_table(name):
    definition = COMPONENTS[name]
    lines = [f"#### {name}", "",
             "| variable | causality | unit [display] | start | description |",
             "|---|---|---|---|---|"]
    table_rows = 0
    for variable in definition.variables:
        if TABLE_POINT.match(variable.name):
            table_rows += 1
            continue
        lines.append(f"| `{variable.name}` | {variable.causality} | {_unit(variable)} | "
                     f"{_start(variable)} | {_cell(variable.description)} |")
    if table_rows:
        lines.append(f"| `dashpot.rate[1..{table_rows // 2}]`, `dashpot.torque[1..{table_rows // 2}]` "
                     f"| parameter | rad/s [deg/s], N.m | Table A6-1 | Dashpot curve points: "
                     f"rates strictly increasing, torques non-decreasing and of the rate's sign "
                     f"(`reference_data/thesis/table_A6-1.csv`, smoothed column) |")
    for switch in definition.switches:  # Boolean parameters
        lines.append(f"| `{switch.name}` | parameter (Boolean) | | "
                     f"{'true' if switch.start else 'false'} | {_cell(switch.description)} |")
    return "\n".join(lines)


def all_tables():
    return "\n\n".join(variables_table(name) for name in COMPONENTS)


if __name__ == "__main__":
    print(all_tables())
