"""A virtual test rig: the sine and step-and-hold tests of an elastomer test machine.

    fmu-components rig --component NAME [--params PARAMS.json] [--structure S]
                       --preload P... --amplitude A... --frequency F... --out DIR
                       [--scheduler ADDRESS] [--jobs N]

The engine, the drivers and the rig table are ``lab.rig`` (its docstring says how a point
runs to periodic steady state); the plots and the structure study ``lab.rig_plots``.
"""

import sys
import time
from pathlib import Path

from ..errors import UsageError
from ..lab.rig import (DRIVERS, HOLD_TIME, MAX_CYCLES, MAX_STEP, RATES, RIG_RTOL, RISE_TIME,
                       SAMPLES_PER_CYCLE, STEADY, RigError, make_setup, relaxation_record,
                       run_rig, units, write_relaxation, write_rows)
from ..lab.signals import check_deflection
from ..runtime.catalog import COMPONENTS, STRUCTURES
from ..runtime.integrator import DEFAULT_RTOL
from . import cluster


EXAMPLES = """examples:
  fmu-components rig --component TrackBushRadial --preload 3e-4 --amplitude 2e-5 1e-4 3e-4 \\
      --frequency 0.1 1 10 --out rig_radial
  fmu-components rig --component TrackBushTorsion --params fitted.json --preload 0.1745 \\
      --amplitude 0.0873 --frequency 1 --engine fmu --fmu fmus/TrackBushTorsion.fmu --out rig_fmu
  fmu-components rig --component RotaryDamper --preload 0 --amplitude 0.05 0.21 \\
      --frequency 0.1 0.5 1 3 --out rig_damper     (adds equivalent.csv: K' and c_eq)
  fmu-components rig --component TrackBushTorsion --compare-structures --out structures
"""


def configure(parser):
    parser.add_argument("--component", required=True, metavar="NAME",
                        help=f"the FMU's name: {', '.join(sorted(COMPONENTS))}")
    parser.add_argument("--params", metavar="PARAMS.json",
                        help="FMU parameter names to SI values; the rest keep the thesis values")
    parser.add_argument("--structure", default="final", choices=list(STRUCTURES),
                        help="the thesis's model structure (default final, section 6.4)")
    parser.add_argument("--preload", type=float, nargs="+", metavar="P",
                        help="mean deflections (m or rad)")
    parser.add_argument("--amplitude", type=float, nargs="+", metavar="A",
                        help="sine amplitudes (m or rad)")
    parser.add_argument("--frequency", type=float, nargs="+", metavar="F", help="Hz")
    parser.add_argument("--out", type=Path, required=True, metavar="DIR",
                        help="folder for rig.csv, relaxation.csv and the plots")
    parser.add_argument("--engine", choices=sorted(DRIVERS), default="model",
                        help="the Python model (default) or a built FMU (--fmu)")
    parser.add_argument("--fmu", metavar="PATH", help="the FMU for --engine fmu (either flavour)")
    parser.add_argument("--relaxation", type=float, metavar="STEP",
                        help="the step-and-hold test's step from the first preload (default: "
                             "the largest amplitude)")
    parser.add_argument("--hold", type=float, default=HOLD_TIME, metavar="SECONDS",
                        help=f"how long the step is held (default {HOLD_TIME:g} s)")
    parser.add_argument("--rise", type=float, default=RISE_TIME, metavar="SECONDS",
                        help=f"the step's ramp time (default {RISE_TIME:g} s)")
    parser.add_argument("--samples-per-cycle", type=int, default=SAMPLES_PER_CYCLE,
                        help=f"the fewest steps per cycle (default {SAMPLES_PER_CYCLE}; a "
                             f"multiple of 4)")
    parser.add_argument("--max-step", type=float, default=MAX_STEP, metavar="SECONDS",
                        help=f"the longest sine step (default {MAX_STEP:g} s)")
    parser.add_argument("--rate", choices=RATES, default="secant",
                        help="the rate held over each step: the secant to the next sample "
                             "(default) or the sine's own rate at the sample")
    parser.add_argument("--steady", type=float, default=STEADY,
                        help=f"periodic steady state: the relative change still to come of "
                             f"the harmonic result (default {STEADY:g})")
    parser.add_argument("--max-cycles", type=int, default=MAX_CYCLES,
                        help="the most cycles run towards periodic steady state")
    parser.add_argument("--rtol", type=float, default=RIG_RTOL,
                        help=f"the integrator's relative tolerance (default {RIG_RTOL:g}; "
                             f"the FMUs' own default is {DEFAULT_RTOL:g})")
    cluster.add_arguments(parser, aliases=("--processes",))
    parser.add_argument("--compare-structures", action="store_true",
                        help="run the torsion bush's three structures on the dual sine and "
                             "step-and-hold tests instead (structures.png, structures.md)")


def run_command(args):
    try:
        return _run(args)
    except RigError as error:
        raise UsageError(str(error)) from None


def _run(args):
    if args.compare_structures:
        if args.component != "TrackBushTorsion":
            raise RigError("--compare-structures runs the torsion bush (the thesis compares "
                           "the structures on it): use --component TrackBushTorsion")
        from ..campaign.tasks import structures_runner
        from ..lab.rig_plots import compare_structures, structures_table

        started = time.perf_counter()
        with cluster.engine(args) as engine:  # a structure a task (commands/cluster.py)
            table = compare_structures(args.out, runner=structures_runner(engine))
        print(structures_table(table))
        print(f"wrote {args.out / 'structures.png'} and {args.out / 'structures.md'} "
              f"({time.perf_counter() - started:.1f} s)")
        return 0
    for option in ("preload", "amplitude", "frequency"):
        if not getattr(args, option):
            raise RigError(f"give --{option} (one or more values, SI units)")
    from ..campaign.tasks import rig_runner

    started = time.perf_counter()
    with cluster.engine(args) as engine:  # the points on a Dask cluster (commands/cluster.py)
        rows = run_rig(args.component, args.preload, args.amplitude, args.frequency,
                       params=args.params, structure=args.structure, engine=args.engine,
                       fmu=args.fmu, rtol=args.rtol, samples_per_cycle=args.samples_per_cycle,
                       steady=args.steady, max_cycles=args.max_cycles, rate=args.rate,
                       max_step=args.max_step, runner=rig_runner(engine))
    sweep_time = time.perf_counter() - started
    setup = make_setup(args.component, args.structure, args.params, args.engine, args.fmu,
                       args.rtol)
    step = args.relaxation if args.relaxation is not None else max(args.amplitude)
    if args.relaxation is not None:  # the sine's points are checked by run_rig
        check_deflection(COMPONENTS[args.component], [args.preload[0], args.preload[0] + step])
    record = relaxation_record(setup, args.preload[0], step, args.rise, args.hold)
    files = write_rows(rows, args.out, args.component)
    files.append(write_relaxation(record, args.out / "relaxation.csv", args.component))
    length = units(args.component)[0]
    label = f"{args.preload[0]:g} to {args.preload[0] + step:g} {length} in {args.rise:g} s"
    from ..lab.rig_plots import plot_rows

    files += plot_rows(rows, args.out, args.component, {label: (*record, args.rise)})
    _print_rows(rows, args.component)
    unsteady = [r for r in rows if not r.steady]
    for row in unsteady:
        print(f"warning: preload {row.preload:g} {length}, amplitude {row.amplitude:g} {length}, "
              f"frequency {row.frequency:g} Hz not periodic after {row.cycles} cycles (last change "
              f"{row.change:.2g}); raise --max-cycles", file=sys.stderr)
    print(f"{len(rows)} points in {sweep_time:.1f} s ({args.engine}); wrote "
          + ", ".join(str(f) for f in files))
    return 0


def _print_rows(rows, component):
    length, load, stiffness = units(component)
    print(f"{'preload ' + length:>11s} {'amplitude ' + length:>13s} {'f Hz':>7s} "
          f"{'|K*| ' + stiffness:>16s} {'delta deg':>9s} {'E/cycle J':>11s} "
          f"{'secant ' + stiffness:>16s} {'cycles':>6s}")
    for r in rows:
        print(f"{r.preload:11.4g} {r.amplitude:13.4g} {r.frequency:7.3g} "
              f"{r.dynamic_stiffness:16.6g} {r.loss_angle_deg:9.4f} {r.energy_per_cycle:11.5g} "
              f"{r.secant_stiffness:16.6g} {r.cycles:6d}")
