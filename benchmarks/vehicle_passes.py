"""Where the tracked vehicle's coupling passes go (docs/vehicle.md, "What sets the passes"
and "A kink in the first law"): the default run (examples/tracked_vehicle.py, the own
solver, `iterated`) with every pass of the bank recorded, the law's load at the pass's
deflections taken before Bank.end_pass and the FMUs' answers after it. Per solve of a
step (first, second, ...): the steps that take it; each kind's worst instance's mismatch,
|FMU load - law load| over the instance's peak load so far, median and 90th percentile
over the steps; and the instances above the scheme's tolerance per step. With
--straight the first laws without the reversal's kink (own_host.kinked_first_laws off,
as exudyn's runs have them).

    python benchmarks/vehicle_passes.py [--speed 5] [--end-time 0.4] [--course bump]
                                        [--straight]
"""

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from fmu_components.coupling.bank import Bank  # noqa: E402
from tracked_vehicle import DEFAULT_STEP, simulate  # noqa: E402
from vehicle import own_host  # noqa: E402
from vehicle.course import COURSES  # noqa: E402
from vehicle.model import static_points  # noqa: E402

KINDS = ("radial", "torsion", "tyre", "damper")


def recorded_run(course, speed, end_time, straight):
    """(vehicle, each step's passes: per step a list of (each instance's mismatch, the
    bank's verdict's worst mismatch) per pass, the scheme's tolerance); Bank.begin_step
    and end_pass wrapped for the run. The mismatch is the bank's own (bank.c's
    bank_end_pass: the scale the instance's peak load, at least 1e-12)."""
    steps, taken = [], (Bank.begin_step, Bank.end_pass)

    def begin_step(bank, time):
        steps.append([])
        return taken[0](bank, time)

    def end_pass(bank, time, deflection):
        law = np.array(bank.law_loads(deflection), dtype=float)
        verdict = taken[1](bank, time, deflection)
        answer = bank.trial_outputs.reshape(-1)[bank.load_cells]
        scale = np.maximum(bank._seen[:, 0], 1e-12)
        steps[-1].append((np.abs(answer - law) / scale, verdict.mismatch))
        return verdict

    Bank.begin_step, Bank.end_pass = begin_step, end_pass
    kinked = own_host.kinked_first_laws
    if straight:
        own_host.kinked_first_laws = lambda settings: False
    try:
        vehicle, _, _, _ = simulate(course, speed, end_time, DEFAULT_STEP,
                                    statics=static_points())
    finally:
        Bank.begin_step, Bank.end_pass = taken
        own_host.kinked_first_laws = kinked
    # a step begun again (halved or refused) keeps its last beginning's passes
    return (vehicle, [passes for passes in steps if passes],
            vehicle.coupling.scheme.tolerance)


def table(vehicle, steps, tolerance):
    """Per solve of a step: the steps taking it, each kind's worst mismatch (median, 90th
    percentile), instances above the tolerance per step."""
    rows = {kind: np.asarray(vehicle.rows[kind], dtype=int) for kind in KINDS}
    print(f"{len(steps)} steps; the scheme's tolerance {tolerance:g}\n")
    print("| after solve | steps that take it | " + " | ".join(
        f"{kind}: worst mismatch (90th pct)" for kind in KINDS) + " | above the tolerance "
        "per step |")
    print("|---" * (3 + len(KINDS)) + "|")
    for number in range(max(len(passes) for passes in steps)):
        solved = [passes[number][0] for passes in steps if len(passes) > number]
        cells = []
        for kind in KINDS:
            worst = [mismatch[rows[kind]].max() for mismatch in solved if rows[kind].size]
            cells.append(f"{np.median(worst):.2g} ({np.percentile(worst, 90):.2g})"
                         if worst else "-")
        above = np.mean([np.count_nonzero(mismatch > tolerance) for mismatch in solved])
        print(f"| {number + 1} | {len(solved)} | " + " | ".join(cells) + f" | {above:.2f} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speed", type=float, default=5.0)
    parser.add_argument("--end-time", type=float, default=0.4)
    parser.add_argument("--course", choices=sorted(COURSES), default="bump")
    parser.add_argument("--straight", action="store_true",
                        help="the first laws without the reversal's kink")
    args = parser.parse_args(argv)
    vehicle, steps, tolerance = recorded_run(args.course, args.speed, args.end_time,
                                             args.straight)
    print(f"{args.course} at {args.speed:g} m/s, {args.end_time:g} s, the own solver, "
          f"{'straight' if args.straight else 'kinked'} first laws; solver statistics: "
          f"{vehicle.solver_statistics()['passes_per_step']:.2f} solves per step")
    table(vehicle, steps, tolerance)


if __name__ == "__main__":
    main()
