"""Benchmark: exudyn's Newton tolerance in the coupled examples, what it saves and what it
moves (docs/coupling.md, "The station, the span and exudyn's Newton").

    python benchmarks/coupling_newton.py                          # station and span
    python benchmarks/coupling_newton.py --only span --tolerances 1e-5 1e-4
    python benchmarks/coupling_newton.py --quick                  # seconds: checks that it runs

An absolute tolerance (exudyn's `newton.absoluteTolerance`, its residual in N and N.m) lets
a step's second solve start from the first's solution (exudyn_host). For each tolerance,
against exudyn's default (None): the coupling's own error (`corrected` against `converged`
at the same host step and tolerance) at 4, 1 and 0.5 ms, how far each history of both
schemes moves against the default's run (max on a 4 ms grid, % of the range: history_error),
and exudyn's Newton iterations per solve, the step's first and second, at 1 ms. The station
at 8 m/s over the bump, the span with 10 links (the study's), compiled path. Figures of one
run; CPU times are coupling_exudyn.py's.
"""

import argparse
import sys
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

import numpy as np  # noqa: E402

from coupling_study import history_error  # noqa: E402
from fmu_components.coupling import exudyn_host  # noqa: E402

STEPS = (4e-3, 1e-3, 5e-4)


def counting_passes():
    """(pass, Newton iterations) of every solve from here on (a wrapper of the post-Newton
    hook); returns the list it fills and a function that stops it."""
    passes, original = [], exudyn_host.ExudynCoupling._post_newton

    def counted(self, t):
        it = self.mbs.sys["dynamicSolver"].it
        passes.append((it.discontinuousIteration, it.newtonSteps))
        return original(self, t)

    exudyn_host.ExudynCoupling._post_newton = counted
    return passes, lambda: setattr(exudyn_host.ExudynCoupling, "_post_newton", original)


def example(name, quick):
    """(module, run(scheme, step), history keys)."""
    if name == "station":
        import road_wheel_station as module

        profile = module.RoadProfile()
        end = 0.3 if quick else None
        return module, (lambda scheme, step: module.simulate(
            8.0, profile, step, end_time=end, coupling=scheme)), module.STUDY_KEYS
    import track_span as module

    end = 0.1 if quick else 1.0
    return module, (lambda scheme, step: module.simulate(
        step, links=10, end_time=end, coupling=scheme)), module.STUDY_KEYS


def figures(runs, run, reference, keys):
    """history_error of run against reference ((tolerance, scheme) each) for every key
    ("a / b / c"), at every host step ("...; ...")."""
    (tolerance, scheme), (base, base_scheme) = run, reference
    cells = []
    for step in STEPS:
        got, expected = runs[tolerance, step, scheme], runs[base, step, base_scheme]
        cells.append(" / ".join(f"{history_error(got, expected, key):.2g}" for key in keys))
    return "; ".join(cells)


def measure(name, tolerances, quick):
    module, run, keys = example(name, quick)
    kept = module.NEWTON_TOLERANCE
    runs, iterations = {}, {}
    try:
        for tolerance in (None,) + tuple(tolerances):
            module.NEWTON_TOLERANCE = tolerance
            for step in STEPS:
                passes, stop = counting_passes()
                try:
                    for scheme in ("corrected", "converged"):
                        runs[tolerance, step, scheme] = run(scheme, step)
                        if scheme == "corrected" and step == 1e-3:
                            found = np.array(passes)
                            iterations[tolerance] = [found[found[:, 0] == k, 1].mean()
                                                     for k in (0, 1)]
                finally:
                    stop()
    finally:
        module.NEWTON_TOLERANCE = kept
    print(f"## {name}\n")
    print("| Newton tolerance | own error at 4 / 1 / 0.5 ms (" + ", ".join(keys)
          + ") | moved against the default, corrected | moved, converged "
          "| Newton iterations, first / second solve (1 ms) |")
    print("|---|---|---|---|---|")
    for tolerance in (None,) + tuple(tolerances):
        own = figures(runs, (tolerance, "corrected"), (tolerance, "converged"), keys)
        moved = [figures(runs, (tolerance, scheme), (None, scheme), keys)
                 if tolerance is not None else "-" for scheme in ("corrected", "converged")]
        first, second = iterations[tolerance]
        print(f"| {tolerance if tolerance is not None else 'default'} | {own} | {moved[0]} "
              f"| {moved[1]} | {first:.2f} / {second:.2f} |")
    print()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=("station", "span"))
    parser.add_argument("--tolerances", type=float, nargs="+",
                        default=[1e-5, 1e-4, 1e-3, 1e-2, 0.1])
    parser.add_argument("--quick", action="store_true", help="seconds: short runs")
    args = parser.parse_args()
    print("Errors in % of each history's range, max on a 4 ms grid; each cell's figures at "
          "4 / 1 / 0.5 ms, each figure the histories in the header's order.\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the bushes' range warnings, converged's limit
        for name in ("station", "span"):
            if args.only in (None, name):
                measure(name, args.tolerances, args.quick)


if __name__ == "__main__":
    main()
