"""Where the tracked vehicle's run on its own solver parts from exudyn's (docs/vehicle.md,
"The vehicle on its own solver"): the same run (examples/tracked_vehicle.py's simulate,
the vehicle's coupling, 1 ms) in exudyn and on the own solver with exudyn's full Newton
(--newton: another policy, own_host.NEWTON).

    python benchmarks/vehicle_parting.py [--course bump] [--speed 3] [--end-time 2]
    python benchmarks/vehicle_parting.py ... --exudyn-retry
    python benchmarks/vehicle_parting.py ... --newton reuse

Prints each run's steps and the steps begun again at a shorter length (their start, the
length and, on the own solver, the pass whose Newton failed), whether the two runs
recorded the same times (else the histories compared at the times both did), the first
recorded time where the histories (every array simulate returns) part by more than
--threshold % of their range and the largest differences before it and over the run (outputs.largest_difference, the hull's vertical
acceleration, and it with the tyre and bush forces and the pitch acceleration). In the
exudyn run its pre-step function reads the solver's algorithmic accelerations against
their start-of-step copy (GetAAlgorithmic, GetStartOfStepStateAAlgorithmic): apart only
where exudyn begins a step again after its Newton failed, without setting them back.
--exudyn-retry: the own run again with that done as exudyn does it (the first pass of a
step begun again after a Newton failure from the failed pass's predicted algorithmic
accelerations, (alpha_f a0 - alpha_m a_alg) / (1 - alpha_m); its later passes from the
step's start), and its comparison. A diagnostic: it reads and writes the solver core's
state through alpha_solver.h's struct (checked against the core's own accessors).
"""

import argparse
import ctypes
import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from tracked_vehicle import DEFAULT_STEP, simulate  # noqa: E402
from vehicle import alpha_solver as alpha  # noqa: E402
from vehicle import own_host  # noqa: E402
from vehicle.outputs import largest_difference  # noqa: E402

KEYS = ("hull_vertical_acceleration", "hull_pitch_acceleration", "tyre_force",
        "bush_radial_force")


def exudyn_run(course, speed, end):
    """(histories, statistics, steps begun again, largest stale |a_alg - a_alg0|)."""
    from fmu_components.coupling.exudyn_host import ExudynCoupling

    again, stale, last = [], [], [None]
    pre = ExudynCoupling._pre_step

    def pre_step(self, t):
        solver = self.mbs.sys["dynamicSolver"]
        gap = np.abs(np.asarray(solver.GetAAlgorithmic())
                     - np.asarray(solver.GetStartOfStepStateAAlgorithmic())).max()
        if self.coupling.time == last[0]:  # the step begun again
            again.append((self.coupling.time, t - self.coupling.time))
        last[0] = self.coupling.time
        if gap > 0:
            stale.append((self.coupling.time, float(gap)))
        return pre(self, t)

    ExudynCoupling._pre_step = pre_step
    try:
        vehicle, result, _, _ = simulate(course, speed, end, DEFAULT_STEP, solver="exudyn")
    finally:
        ExudynCoupling._pre_step = pre
    return result, vehicle.solver_statistics(), again, stale


class _Triplets(ctypes.Structure):
    """alpha_solver.h's alpha_triplets."""
    _fields_ = [("capacity", ctypes.c_int), ("count", ctypes.c_int)] + \
        [(name, ctypes.c_void_p) for name in ("row", "col", "value")]


_REALS = ctypes.POINTER(ctypes.c_double)


class _Core(ctypes.Structure):
    """alpha_solver.h's alpha_solver up to the step's start (a diagnostic's view)."""
    _fields_ = ([("nq", ctypes.c_int), ("nm", ctypes.c_int), ("n", ctypes.c_int),
                 ("set", alpha.Settings)]
                + [(name, ctypes.c_double) for name in ("alpha_m", "alpha_f", "beta", "gamma")]
                + [("mass", _REALS)]
                + [(name, ctypes.c_void_p)
                   for name in ("evaluate", "jacobian", "context", "matrix")]
                + [(name, _Triplets) for name in ("K", "D", "G")]
                + [("t", ctypes.c_double)]
                + [(name, _REALS) for name in ("q", "v", "a", "a_alg", "lam")]
                + [("t0", ctypes.c_double)]
                + [(name, _REALS) for name in ("q0", "v0", "a0", "a_alg0", "lam0")])


def _vector(solver, name):
    core = _Core.from_address(solver.handle)
    coefficients = solver.coefficients()
    if core.nq != solver.nq or core.alpha_m != coefficients["alpha_m"]:
        raise RuntimeError("alpha_solver.h's struct is not _Core's")
    return core, np.ctypeslib.as_array(getattr(core, name), shape=(solver.nq,))


def exudyn_retry():
    """The own solver core's step, repeat and restart with exudyn's algorithmic
    accelerations on a step begun again after a Newton failure; undo()."""
    A = alpha.AlphaSolver
    kept = A.step, A.repeat, A.restart

    def step(self, h, t_new):
        pending, self.pending = getattr(self, "pending", None), None
        _, now = _vector(self, "a_alg")
        true = now.copy()
        if pending is not None:
            now[:] = pending  # the step's start copies it: its predictor's
        self.used = now.copy()
        self.status = kept[0](self, h, t_new)
        if pending is not None:  # the later passes (and a restart) from the step's start
            _vector(self, "a_alg0")[1][:] = true
            if self.status != 0:
                now[:] = true
        return self.status

    def repeat(self, h, t_new, warm=False):
        self.used = _vector(self, "a_alg0")[1].copy()
        self.status = kept[1](self, h, t_new, warm)
        return self.status

    def restart(self):
        kept[2](self)
        if getattr(self, "status", 0) == 1:  # Newton failed (alpha_solver.h)
            core, a0 = _vector(self, "a0")
            self.pending = (core.alpha_f * a0 - core.alpha_m * self.used) / (1 - core.alpha_m)
        self.status = 0

    A.step, A.repeat, A.restart = step, repeat, restart

    def undo():
        A.step, A.repeat, A.restart = kept
    return undo


def own_run(course, speed, end, newton="full"):
    """(histories, statistics, steps begun again after a Newton failure)."""
    failed = []
    solve = own_host.OwnHost._solve

    def logged(self, h, t_new, first, warm):
        self.pass_number = 1 if first else self.pass_number + 1
        status = solve(self, h, t_new, first, warm)
        if status:
            failed.append((t_new - h, h, self.pass_number, self.solver.report()["residual"]))
        return status

    own_host.OwnHost._solve = logged
    try:
        vehicle, result, _, _ = simulate(course, speed, end, DEFAULT_STEP, solver="own",
                                         own_newton=newton)
    finally:
        own_host.OwnHost._solve = solve
    return result, vehicle.solver_statistics(), failed


def parting(a, b, threshold):
    """The first recorded time the two runs' histories part by more than threshold % of
    range, the largest difference before it and over the run."""
    keys = [k for k, v in a.items() if k != "time" and np.ndim(v) > 0
            and len(v) == len(a["time"]) and np.ptp(np.asarray(v, dtype=float)) > 0]
    worst = np.zeros(len(a["time"]))
    for key in keys:
        x, y = np.asarray(a[key], dtype=float), np.asarray(b[key], dtype=float)
        gap = np.abs(x - y).reshape(len(x), -1).max(axis=1) / np.ptp(x) * 100
        worst = np.maximum(worst, gap)
    apart = np.flatnonzero(worst > threshold)
    first = int(apart[0]) if len(apart) else len(worst)
    before = {k: v[:first] for k, v in a.items() if k in KEYS or k == "time"}
    other = {k: v[:first] for k, v in b.items() if k in KEYS or k == "time"}
    return (a["time"][first] if first < len(worst) else None,
            largest_difference(before, other, KEYS) if first > 1 else None,
            largest_difference(a, b, KEYS[:1]), largest_difference(a, b, KEYS))


def _common(run, other):
    """The run's histories at the times the other recorded too."""
    times = [np.round(np.asarray(r["time"]) * 1e9).astype(np.int64) for r in (run, other)]
    kept = np.isin(times[0], times[1])
    return {k: np.asarray(v)[kept] for k, v in run.items()
            if np.ndim(v) > 0 and len(v) == len(run["time"])}


def compare(name, a, b, threshold):
    same = np.array_equal(a["time"], b["time"])
    if not same:
        print(f"  {name}: the runs recorded different times ({len(a['time'])} and "
              f"{len(b['time'])} records), compared where both did")
        a, b = _common(a, b), _common(b, a)
    at, before, hull, every = parting(a, b, threshold)
    print(f"  {name}: {len(a['time'])} recorded times; parting above {threshold:g} % at "
          f"t = {at} s; before it {before}; over the run: {hull}, {every}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--course", default="bump")
    parser.add_argument("--speed", type=float, default=3.0)
    parser.add_argument("--end-time", type=float, default=2.0)
    parser.add_argument("--threshold", type=float, default=1e-3, help="%% of range")
    parser.add_argument("--exudyn-retry", action="store_true")
    parser.add_argument("--newton", default="full", choices=sorted(own_host.NEWTON),
                        help="the own solver's Newton policy (default full: exudyn's)")
    args = parser.parse_args()
    run = (args.course, args.speed, args.end_time)
    print(f"{args.course} at {args.speed:g} m/s, {args.end_time:g} s; load "
          f"{os.getloadavg()}", flush=True)
    ex, ex_stats, again, stale = exudyn_run(*run)
    print(f"exudyn: {ex_stats}\n  steps begun again (start, length): {again}\n"
          f"  a_alg apart from its start-of-step copy at pre-step (start, largest): "
          f"{stale}", flush=True)
    own, own_stats, failed = own_run(*run, args.newton)
    print(f"own, {args.newton} Newton: steps {own_stats['steps']}, halved {own_stats['halved']}\n"
          f"  Newton failed (start, length, pass, residual): {failed}", flush=True)
    compare("exudyn vs own", ex, own, args.threshold)
    if args.exudyn_retry:
        undo = exudyn_retry()
        try:
            retried, _, _ = own_run(*run, args.newton)
        finally:
            undo()
        compare("exudyn vs own with exudyn's retry", ex, retried, args.threshold)
        compare("own vs own with exudyn's retry", own, retried, args.threshold)
    print(f"load {os.getloadavg()}")


if __name__ == "__main__":
    main()
