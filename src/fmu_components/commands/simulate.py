"""Simulate one FMU (either flavour) on an input CSV with fmpy, and write the result.

    fmu-components simulate FMU.fmu INPUT.csv --out RESULT.csv [--plot PLOT.png]

The input is read and checked, run and written by ``lab.simulate``; docs/simulate.md
describes the command.
"""

import sys

from ..errors import UsageError
from ..export.parameters import ParameterError
from ..lab.simulate import (Component, check_columns, check_times, check_tolerance, check_units,
                            finer_grid, plot_loop, prepare_output, read_input, simulate,
                            write_result)

EXAMPLES = """examples:
  fmu-components signal RoadWheelTyre sine --mean 3.5e-3 --amplitude 1e-3 > tyre_in.csv
  fmu-components simulate fmus/RoadWheelTyre.fmu tyre_in.csv --out tyre_out.csv --plot tyre_loop.png
  fmu-components simulate fmus/python/TrackBushRadial.fmu measured.csv --out out.csv --derive-rate

The CSV's first column is time (s); the others are named as the FMU's inputs, in SI units
(m, m/s, rad, rad/s). Without a rate column, --derive-rate has the FMU derive the rate
from the deflection samples (parameter rate_from_deflection; it lags by about one step).
"""


def configure(parser):
    parser.add_argument("fmu", metavar="FMU.fmu", help="an FMU of either flavour")
    parser.add_argument("input", metavar="INPUT.csv", help="time and the FMU's inputs, SI units")
    parser.add_argument("--out", metavar="RESULT.csv", required=True,
                        help="the result: time, deflection, rate and every output")
    parser.add_argument("--plot", metavar="PLOT.png",
                        help="the force-deflection loop beside the inputs and outputs against "
                             "time (200 dpi)")
    parser.add_argument("--derive-rate", action="store_true",
                        help="the CSV has no rate column: the FMU derives the rate from the "
                             "deflection (parameter rate_from_deflection)")
    parser.add_argument("--stop-time", type=float, metavar="T",
                        help="end of the simulation (s); default: the input's end")
    parser.add_argument("--step", type=float, metavar="H",
                        help="communication step (s); default: the input's sample interval")
    parser.add_argument("--tolerance", type=float, metavar="TOL",
                        help="the FMU integrator's relative tolerance (default: the FMU's)")
    parser.add_argument("--params", metavar="PARAMS.json",
                        help="parameter values to run with (FMU names, SI; fmu-components fit "
                             "writes them); the others keep the FMU's own")
    parser.add_argument("--param", action="append", metavar="NAME=VALUE",
                        help="one parameter value to run with, SI (repeatable; after --params)")


def run_command(args):
    component = Component(args.fmu)
    try:
        parameters = component.parameters(args.params, args.param)
    except ParameterError as error:
        raise UsageError(str(error)) from None
    names, values = read_input(args.input)
    feed = check_columns(component, names, args.derive_rate, args.input)
    check_units(component, names, values, args.input)
    times = values[:, 0]
    stop_time, step = check_times(times, args.stop_time, args.step, args.input)
    check_tolerance(args.tolerance)
    prepare_output(args.out, args.plot)
    times, columns = finer_grid(times, {name: values[:, names.index(name)] for name in feed},
                                stop_time, step, *component.inputs)
    warnings, errors = [], []
    try:
        result = simulate(component, times, columns, stop_time, step, args.tolerance,
                          args.derive_rate, warnings, errors, parameters)
    except Exception as exc:
        said = errors[-1] if errors else str(exc)
        raise UsageError(f"{component.name} stopped the simulation: {said}") from None
    for message in warnings + errors:
        print(f"{component.name}: {message}", file=sys.stderr)
    written = write_result(args.out, component, result, times, columns, args.derive_rate)
    print(f"wrote {args.out}: {len(result)} rows of " + ", ".join(written))
    if args.plot:
        plot_loop(args.plot, component, written)
        print(f"wrote {args.plot}")
    return 0
