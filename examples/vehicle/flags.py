"""The flags both vehicle scripts take (tracked_vehicle.py, ground_vehicle.py): speed,
course, how long, the host step, the coupling's scheme and its path."""

from fmu_components.coupling import DEFAULT_SCHEME, SCHEMES

import bank_path

from .course import COURSES


def add_run_arguments(parser, end_time, step, speed=5.0, coupling=DEFAULT_SCHEME):
    parser.add_argument("--speed", type=float, default=speed, help=f"m/s (default {speed:g})")
    parser.add_argument("--course", choices=sorted(COURSES), default="bump")
    parser.add_argument("--end-time", type=float, default=end_time, help="s of driving")
    parser.add_argument("--step", type=float, default=step, help="host step, s")
    parser.add_argument("--coupling", choices=sorted(SCHEMES), default=coupling,
                        help=f"coupling scheme (default {coupling}; docs/coupling.md)")
    bank_path.add_argument(parser)
