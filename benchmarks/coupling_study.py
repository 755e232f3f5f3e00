"""The coupling study: every scheme of fmu_components.coupling at host steps of 4, 2, 1, 0.5
and 0.25 ms, in the road-wheel station (8 m/s over the bump and the track-link ripple)
and the track span (10 links on 8e7 N/m bushes). Prints Markdown tables.

    python benchmarks/coupling_study.py                  # both examples (minutes)
    python benchmarks/coupling_study.py --only station --speed 3
    python benchmarks/coupling_study.py --only station --damper-tangent
    python benchmarks/coupling_study.py --schemes corrected iterated converged

For each scheme and host step: the total error against a fine reference (the station:
its own equations of motion with the Model Exchange FMUs by Radau at rtol 1e-10; the
span: `converged` at 0.03125 ms), the own error against `converged` at the same host
step, the FMU doSteps, state saves and restores per host step and FMU, the host's solves
per step, and wall seconds per simulated second. Errors are the max of a history on a
4 ms grid in % of the reference's range (examples/coupling_study.py). Wall times are this
machine's, in one run; compare them within a table only.
"""

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from coupling_study import (STUDY_GRID, STUDY_SCHEMES, STUDY_STEPS, format_table,  # noqa: E402
                            progress, tightness)


def print_tightness(run, keys, steps):
    found = tightness(run, keys, steps or STUDY_STEPS)
    print("\n`converged` (to 1e-9 of the load) against `converged` to 1e-12, the worst "
          "history: " + ", ".join(f"{value:.1e} % at {step * 1e3:g} ms"
                                  for step, value in found.items()) + "\n")


def station(speed, damper_tangent=False, steps=None, end_time=None, schemes=None):
    import road_wheel_station as example

    profile = example.RoadProfile()
    schemes = schemes or example.STUDY_SCHEMES
    if damper_tangent:
        example.DAMPER_STEP_MODEL = "tangent"
        schemes = ("corrected", "converged")
    reference, agreement, table = example.coupling_study(
        speed, profile, steps=steps or example.STUDY_STEPS, schemes=schemes,
        end_time=end_time, progress=progress)
    print(f"## Road-wheel station at {speed:g} m/s"
          f"{', the damper stepped by its stiffness' if damper_tangent else ''}\n")
    print(f"{example.describe_reference(reference, agreement)}.\n")
    print(format_table(table, example.STUDY_KEYS, example.STUDY_LABELS))
    if not damper_tangent:
        print_tightness(lambda scheme, step: example.simulate(
            speed, profile, step, end_time=end_time, coupling=scheme), example.STUDY_KEYS,
            steps)
    print()


def span(steps=None, end_time=None, schemes=None):
    import track_span as example

    reference, table = example.coupling_study(end_time=end_time or 1.0,
                                              steps=steps or example.STUDY_STEPS,
                                              schemes=schemes or example.STUDY_SCHEMES,
                                              progress=progress)
    print("## Track span, 10 links, end lifted 10 mm at 6 Hz\n")
    print(f"Reference: `converged` at {example.FINE_STEP * 1e3:g} ms "
          f"({reference['wall']:.0f} s); errors the worst over the links (joints).\n")
    print(format_table(table, example.STUDY_KEYS, example.STUDY_LABELS))
    print_tightness(lambda scheme, step: example.simulate(step, end_time=end_time or 1.0,
                                                          coupling=scheme),
                    example.STUDY_KEYS, steps)
    print()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=("station", "span"))
    parser.add_argument("--speed", type=float, default=8.0, help="station, m/s")
    parser.add_argument("--damper-tangent", action="store_true",
                        help="station: the damper's `stiffness` as its step tangent instead "
                             "of its linearisation (corrected and converged only)")
    parser.add_argument("--steps", type=float, nargs="+", help="host steps, s (default: "
                        "4, 2, 1, 0.5 and 0.25 ms)")
    parser.add_argument("--end-time", type=float, help="s; default: the examples' runs")
    parser.add_argument("--schemes", nargs="+", choices=STUDY_SCHEMES,
                        help="some of the schemes (default all; converged is always run: "
                             "the own errors' measure)")
    args = parser.parse_args()
    started = time.perf_counter()
    print(f"Errors: max on a {STUDY_GRID * 1e3:g} ms grid, % of the reference's range. "
          f"Costs: per host step and FMU.\n")
    if args.only in (None, "station"):
        station(args.speed, args.damper_tangent, args.steps, args.end_time, args.schemes)
    if args.only in (None, "span"):
        span(args.steps, args.end_time, args.schemes)
    print(f"wall time {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
