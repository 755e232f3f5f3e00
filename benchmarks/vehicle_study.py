"""The tracked vehicle's accuracy and cost study (examples/tracked_vehicle.py,
docs/vehicle.md): a benchmark, not a test (minutes to hours of CPU).

    python benchmarks/vehicle_study.py --end-time 0.05            # coupling's own error
    python benchmarks/vehicle_study.py --steps 4 2 1 0.5 --end-time 0.05
    python benchmarks/vehicle_study.py --solver exudyn  # the time loop in exudyn
    python benchmarks/vehicle_study.py --path python --solver exudyn  # the Python path

For each host step: the run with the default coupling and with `converged` at the same
step (the coupling's own error: the largest difference in hull vertical acceleration, in
% of the converged run's range, and where it is; the same for each wheel's tyre force,
each damper's torque and each joint's radial and torsion bush load, the largest over the
instances of a kind, each in % of its own range), the error against the finest step's
converged run (the step study), CPU seconds per simulated second, exudyn's Newton
iterations per solve and solves per host step, and the steps where `converged` stopped at
its pass limit before its loads agreed (its own error there); then the hull error by
time window (--window), where in the run it grows. With --spread TOL, a third run,
`converged` stopping where its loads agree to TOL instead of 1e-9: how far the run moves
for that small a change of the loads (the solution's own sensitivity, the scale below
which the coupling's own error says little). The runs are on the vehicle's own solver
(tracked_vehicle.py's default; --solver exudyn: in exudyn); its spectral radius and
Newton tolerance are the vehicle's unless given (--spectral-radius, --newton-tolerance),
the same in every run.

Like for like: runs are compared at the times both reached, never interpolated. exudyn
halves a step where its Newton fails, and where it does depends on the smallest
difference: two `converged` runs differing only in their tolerance (1e-9 and 1e-6, bump
at 5 m/s, 1 ms) halved different steps from 31.75 ms on and then differed by 1.9 % of
the range, as much as the coupling's own error. So the study lets Newton take up to
--newton-iterations iterations (exudyn's default is 25, the own solver's too: the limit
reaches both), and says where two runs' steps part if they still do. Where the default
run's Newton fails even so and exudyn halves steps `converged` does not (5 m/s, from
284 ms: docs/vehicle.md, Past 0.2 s and on the courses), --same-steps has `converged`
take the default run's steps (it refuses a solution whose step passes over a time that
run reached, and the solver, either, solves the step again at half its length), so that
the comparison goes on like for like past them. All
runs start from the same stored static point (one settling first, excluded from the
costs). CPU figures are this machine's, in one run, under whatever load it carries:
compare them within a table only.
"""

import argparse
import contextlib
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from fmu_components.coupling.schemes import Converged  # noqa: E402

import bank_path  # noqa: E402
from tracked_vehicle import (DEFAULT_SOLVER, SOLVER_NAMES, SOLVERS,  # noqa: E402
                             add_solver_arguments, check_solver_arguments, own_refusal,
                             simulate)
from vehicle import model, own_host, step_check  # noqa: E402

KEY = "hull_vertical_acceleration"
# each kind's loads, compared instance by instance (docs/vehicle.md, Outputs)
LOADS = {"tyre force": "tyre_force", "damper torque": "damper_torque",
         "radial bush force": "bush_radial_force", "torsion bush torque": "bush_torque"}
NEWTON_ITERATIONS = 100
SAME_STEPS = "; converged on the default run's steps"


def newton_limit(iterations):
    """The vehicle's run settings (model.run_settings) with exudyn's Newton allowed
    `iterations` per solve."""
    settings = model.run_settings

    def run_settings(*args):
        chosen = settings(*args)
        chosen.timeIntegration.newton.maxIterations = iterations
        return chosen
    return run_settings


def own_newton_limit(iterations):
    """The own solver's Newton policies (own_host.NEWTON) with its Newton allowed
    `iterations` per solve."""
    return {name: dict(policy, max_iterations=iterations)
            for name, policy in own_host.NEWTON.items()}


def nanoseconds(times):
    return np.round(np.asarray(times) * 1e9).astype(np.int64)


def same_steps(times, check=None):
    """The vehicle's step check (step_check.StepCheck, or `check`) that also refuses a
    solution whose step passes over a time the run of `times` reached: the solver
    (exudyn's or the own) solves that step again at half its length, as it did where its
    Newton failed in that run,
    so that the run takes the other's steps (a refused step is solved again from its
    start)."""
    reached = np.unique(nanoseconds(times))

    class SameSteps(check or step_check.StepCheck):
        def judge(self, t, h, *state):
            # both hosts judge through here: exudyn's hook (StepCheck.__call__) with the
            # step from its start, the own host directly
            jumped = super().judge(t, h, *state)
            start, end = int(nanoseconds(t - h)), int(nanoseconds(t))
            passed = reached[np.searchsorted(reached, start, "right"):
                             np.searchsorted(reached, end, "left")]
            if jumped is None and len(passed):
                return (f"the step to {t * 1e3:.4f} ms passes over {passed[0] * 1e-6:.4f} ms, "
                        f"a time the run it follows reached")
            return jumped
    return SameSteps


@contextlib.contextmanager
def converged_tolerance(tolerance):
    """Runs within stop `converged` where its loads agree to `tolerance` (None: its own).
    The compiled path makes its scheme from the name (bank.py), so the scheme's default
    is set, and put back after."""
    kept = Converged.tolerance
    if tolerance is not None:
        Converged.tolerance = tolerance
    try:
        yield
    finally:
        Converged.tolerance = kept


def run(args, step, scheme, statics, tolerance=None):
    """The run's histories and costs (`converged` to `tolerance` where given); None where
    the run stopped (its message printed)."""
    cpu = time.process_time()
    what = scheme if tolerance is None else f"{scheme} to {tolerance:g}"
    try:
        with converged_tolerance(tolerance):
            vehicle, result, _, run_cpu = simulate(
                args.course, args.speed, args.end_time, step, scheme, None, statics,
                args.settle_time, path=args.path, spectral_radius=args.spectral_radius,
                newton_tolerance=args.newton_tolerance, solver=args.solver)
    except model.VehicleError as error:
        print(f"  {what} at {step * 1e3:g} ms stopped: {error}", flush=True)
        return None
    solver = vehicle.solver_statistics()
    refused = f", {solver['refused']} solves refused" if solver["refused"] else ""
    print(f"  {what} at {step * 1e3:g} ms: {run_cpu:.1f} s CPU "
          f"({time.process_time() - cpu:.1f} with the set-up), {solver['steps']} steps "
          f"for {solver['host_steps']}{refused}", flush=True)
    return {"time": result["time"], **{key: result[key] for key in (KEY, *LOADS.values())},
            "cpu": run_cpu / (result["time"][-1] - result["time"][0]),
            "unconverged": vehicle.coupling.unconverged_steps, **solver}


def converged_run(args, step, statics, default):
    """`converged` at the step; with --same-steps on the default run's steps."""
    if not args.same_steps or default is None:
        return run(args, step, "converged", statics)
    check = step_check.StepCheck
    step_check.StepCheck = same_steps(default["time"])
    try:
        return run(args, step, "converged", statics)
    finally:
        step_check.StepCheck = check


def common_times(run, reference):
    """Indices into run and reference of the times both reached (to the nanosecond)."""
    mine, theirs = (nanoseconds(r["time"]) for r in (run, reference))
    _, i, j = np.intersect1d(mine, theirs, return_indices=True)
    return i, j


def difference(run, reference, key=KEY):
    """(largest |difference| at the times both reached, in % of the reference's range
    there, and its time). For a history of several instances, each in % of its own
    range, the largest over them."""
    i, j = common_times(run, reference)
    if not len(i):
        return float("nan"), float("nan")
    mine, theirs = np.asarray(run[key])[i], np.asarray(reference[key])[j]
    span = np.ptp(theirs, axis=0)
    error = 100 * np.abs(mine - theirs) / np.where(span > 0, span, 1.0)
    at = np.unravel_index(np.argmax(error), error.shape)[0]
    return float(np.max(error)), float(np.asarray(reference["time"])[j][at])


def parting(run, reference):
    """The first time one run reached that the other did not (None: the same steps)."""
    mine, theirs = (set(nanoseconds(r["time"]).tolist()) for r in (run, reference))
    apart = sorted(mine ^ theirs)
    return apart[0] * 1e-9 if apart else None


def by_window(run, reference, width):
    """The hull error (% of the reference's whole range) in each window of `width` s,
    at the times both runs reached: where in the run it grows."""
    i, j = common_times(run, reference)
    times = np.asarray(reference["time"])[j]
    error = 100 * np.abs(np.asarray(run[KEY])[i] - np.asarray(reference[KEY])[j]) / (
        np.ptp(reference[KEY]) or 1.0)
    window = np.floor(times / width + 1e-9).astype(int)
    return [(k * width, float(error[window == k].max())) for k in np.unique(window)]


def before(run, time):
    """The run's hull acceleration before `time`."""
    kept = np.asarray(run["time"]) < time - 1e-9
    return {key: np.asarray(run[key])[kept] for key in ("time", KEY)}


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[1.0], help="ms")
    parser.add_argument("--end-time", type=float, default=0.05)
    parser.add_argument("--speed", type=float, default=5.0)
    parser.add_argument("--course", default="bump")
    parser.add_argument("--scheme", default=model.COUPLING)
    parser.add_argument("--settle-time", type=float, default=3.0)
    parser.add_argument("--window", type=float, default=0.025,
                        help="s, the windows the hull error is also given in")
    parser.add_argument("--newton-iterations", type=int, default=NEWTON_ITERATIONS,
                        help=f"exudyn's Newton iterations per solve at most (default "
                             f"{NEWTON_ITERATIONS}: no step halved; exudyn's own, 25, halves "
                             f"some)")
    parser.add_argument("--spread", type=float,
                        help=f"also run `converged` stopping where its loads agree to this "
                             f"(its own: {Converged.tolerance:g}), e.g. 1e-6: how far so small "
                             f"a change moves the run")
    add_solver_arguments(parser)
    parser.add_argument("--solver", choices=SOLVERS, default=DEFAULT_SOLVER,
                        help=f"the time integration of every run: the vehicle's own solver "
                             f"(default {DEFAULT_SOLVER}) or exudyn's")
    parser.add_argument("--same-steps", action="store_true",
                        help="converged takes the default run's steps (a solution whose step "
                             "passes over a time that run reached is refused, the step "
                             "halved)")
    bank_path.add_argument(parser)
    args = parser.parse_args(argv)
    check_solver_arguments(parser, args)
    refusal = own_refusal(args.path, args.scheme) if args.solver == "own" else None
    if refusal:
        parser.error(f"{refusal}; add --solver exudyn to run the study in exudyn")
    if args.newton_iterations < 1:
        parser.error(f"--newton-iterations {args.newton_iterations}: give 1 or more")
    if not args.window > 0:
        parser.error(f"--window {args.window}: give a length in s, more than 0")
    if args.spread is not None and not args.spread > 0:
        parser.error(f"--spread {args.spread:g}: give a tolerance above 0")
    return args


def spread(runs, key):
    """A step's (default, converged, converged to --spread) runs: the last against
    `converged`, in % of range ('-': no such run)."""
    converged, other = runs[1], runs[2] if len(runs) > 2 else None
    if other is None or converged is None:
        return "-"
    return f"{difference(other, converged, key)[0]:.3g}"


def main(argv=None):
    args = parse(argv)
    model.run_settings = newton_limit(args.newton_iterations)
    own_host.NEWTON = own_newton_limit(args.newton_iterations)
    statics = model.static_points()
    runs = {}
    for step in sorted(args.steps, reverse=True):
        h = step * 1e-3
        default = run(args, h, args.scheme, statics)
        runs[step] = (default, converged_run(args, h, statics, default))
        if args.spread is not None:
            runs[step] += (run(args, h, "converged", statics, args.spread),)
    finest = runs[min(runs)][1] or {"time": [], KEY: []}
    print(f"\n{args.course} at {args.speed:g} m/s, {args.end_time:g} s, the coupling's "
          f"{args.path} path, solver {SOLVER_NAMES[args.solver]}, Newton up to "
          f"{args.newton_iterations} iterations to "
          f"{args.newton_tolerance:g}, spectral radius {args.spectral_radius:g}"
          f"{SAME_STEPS if args.same_steps else ''}; errors in % "
          f"of range at the times both runs reached\n")
    print(f"| step (ms) | {args.scheme} against converged: hull vertical acceleration | "
          + " | ".join(LOADS) + f" | steps part at | converged's unconverged steps | "
          f"against converged at {min(runs):g} ms | CPU s / s | Newton per solve | "
          f"solves per step | converged to {args.spread or '-'} against converged: hull, "
          f"radial bush |")
    print("|---" * (9 + len(LOADS)) + "|")
    for step, (default, converged, *_) in sorted(runs.items(), reverse=True):
        if default is None or converged is None:
            print(f"| {step:g} | stopped (above) |" + " |" * (7 + len(LOADS)))
            continue
        error, at = difference(default, converged)
        loads = " | ".join(f"{difference(default, converged, key)[0]:.3g}"
                           for key in LOADS.values())
        part = parting(default, converged)
        if part is not None:
            error = f"{error:.3g} (at {at * 1e3:.1f} ms; before the steps part " \
                    f"{difference(before(default, part), before(converged, part))[0]:.3g})"
        else:
            error = f"{error:.3g} (at {at * 1e3:.1f} ms)"
        print(f"| {step:g} | {error} | {loads} | "
              f"{'-' if part is None else f'{part * 1e3:.3f} ms'} | "
              f"{converged['unconverged']} of {converged['steps']} | "
              f"{difference(default, finest)[0]:.3g} | {default['cpu']:.3g} | "
              f"{default['newton_per_pass']:.1f} | {default['passes_per_step']:.2f} | "
              f"{spread(runs[step], KEY)}, "
              f"{spread(runs[step], LOADS['radial bush force'])} |")
    for step, (default, converged, *_) in sorted(runs.items(), reverse=True):
        if default is not None and converged is not None:
            print(f"\n{step:g} ms, hull error by {args.window * 1e3:g} ms from: " + ", ".join(
                f"{start * 1e3:g} ms {error:.2g} %"
                for start, error in by_window(default, converged, args.window)))


if __name__ == "__main__":
    main()
