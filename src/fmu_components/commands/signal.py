"""Input histories for the FMUs: deflection samples on the communication grid with the
rate each step should hold.

    fmu-components signal RoadWheelTyre sine --mean 3.5e-3 --amplitude 1e-3 \\
        --frequency 1 --stop-time 2 --step 1e-3 > tyre_in.csv

The history and its secant rates come from ``lab.signals``.
"""

import sys

from ..errors import UsageError
from ..runtime.catalog import COMPONENTS
from ..lab.signals import (THESIS_SINES, check_deflection, input_table, ramp_and_hold, sine,
                           time_grid, write_csv)

EXAMPLES = """examples:
  fmu-components signal RoadWheelTyre sine --mean 3.5e-3 --amplitude 1e-3 --frequency 1 > in.csv
  fmu-components signal TrackBushTorsion ramp --mean 0.1745 --amplitude 0.2618 --stop-time 200
"""


def configure(parser):
    parser.add_argument("fmu", choices=sorted(COMPONENTS), help="the component the input is for")
    parser.add_argument("shape", choices=["sine", "ramp"],
                        help="sine: mean + amplitude sin(2 pi f t); ramp: from mean, rising "
                             "by amplitude over the ramp time, then held")
    parser.add_argument("--mean", type=float, required=True,
                        help="sine mean, or ramp start (m or rad)")
    parser.add_argument("--amplitude", type=float, required=True,
                        help="sine amplitude, or ramp rise (m or rad)")
    parser.add_argument("--frequency", type=float, default=1.0, help="sine frequency (Hz)")
    parser.add_argument("--ramp-time", type=float, default=0.1, help="ramp duration (s)")
    parser.add_argument("--stop-time", type=float, default=2.0, help="end of the signal (s)")
    parser.add_argument("--step", type=float, default=1e-3,
                        help="sample interval, the communication step to feed it at (s)")


def thesis_sine_options(fmu_name):
    mean, amplitude, frequency = THESIS_SINES[fmu_name]
    return f"--mean {mean:.6g} --amplitude {amplitude:.6g} --frequency {frequency:g}"


def run_command(args):
    if not (args.step > 0 and args.stop_time >= args.step):
        raise UsageError("--step must be > 0 and --stop-time at least one step (seconds), "
                         "e.g. --stop-time 2 --step 1e-3")
    if args.shape == "sine" and args.frequency <= 0:
        raise UsageError("--frequency must be > 0 (Hz), e.g. --frequency 1")
    if args.shape == "ramp" and args.ramp_time <= 0:
        raise UsageError("--ramp-time must be > 0 (seconds), e.g. --ramp-time 0.1")
    t = time_grid(args.stop_time, args.step)
    if args.shape == "sine":
        x = sine(t, args.mean, args.amplitude, args.frequency)
    else:
        x = ramp_and_hold(t, args.mean, args.mean + args.amplitude, args.ramp_time)
    if args.shape == "sine" and args.amplitude == 0.0:
        raise UsageError("--amplitude 0 makes the sine a constant; give the amplitude (m or "
                         "rad), e.g. the thesis sine of this component: "
                         + thesis_sine_options(args.fmu))
    check_deflection(COMPONENTS[args.fmu], x)
    write_csv(input_table(args.fmu, t, x), sys.stdout)
    return 0
