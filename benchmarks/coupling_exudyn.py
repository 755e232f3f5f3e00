"""Benchmark: the coupling in exudyn, CPU seconds per simulated second, Python path against
compiled path (docs/coupling.md, "What it costs").

    python benchmarks/coupling_exudyn.py              # the station and the 40-link span
    python benchmarks/coupling_exudyn.py --quick      # seconds: checks that it runs
    python benchmarks/coupling_exudyn.py --only station --path compiled \
        --newton-tolerance 1e-4                       # one example, one path, a tolerance
    python benchmarks/coupling_exudyn.py --only station --step 4e-3   # another host step

Each run is timed by CPU (process time) over the dynamic solve alone (its exudyn solve,
timed inside): the same run to two end times, and the difference over the difference of
the end times, so that exudyn's start drops out too; each in a process of its own. The station drives at
8 m/s over the bump (`explicit` and `corrected`), the span (examples/track_span.py) has
40 links, 82 instances, `corrected`; 1 ms host steps (--step: another). The real-time factor by CPU is
simulated time over CPU time. The machine may be loaded: the load average is printed.
On this shared machine one run's figure moves by up to 1.7 times from the next one's (the
station's `explicit` 0.080 and 0.137 CPU s per simulated s in runs one after the other),
so the runs go in rounds (--rounds), each round every run once, one after the other; the
figures printed are the rounds' medians, and the station's ratio is each round's own
ratio's median (its range in brackets).
--newton-tolerance sets both examples' NEWTON_TOLERANCE (exudyn's Newton's absolute
tolerance; "default", exudyn's own), which decides whether a step's second solve starts
from the first's solution (exudyn_host).
"""

import argparse
import os
import statistics
import subprocess
import sys
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "examples"))

from run import ROOT, native_fmus  # noqa: E402

STEP = 1e-3


def cpu_per_simulated_second(run, start, end):
    """CPU seconds of the dynamic solve of run(end) less that of run(start), over
    end - start (after a first run to start, which reads and extracts the FMUs once per
    process). The solve's own CPU time (exudyn_host.solve's `solve_cpu`), so that the
    system's building, its static solve and the FMUs' instantiation, and Python's
    collections of what they made (a full collection of a heap with scipy's modules in
    it costs 60 ms, and fell in one run or the other: +-0.24 s per simulated second over
    a quarter of a second), stay out."""
    run(start)
    spent = [run(end_time)["solve_cpu"] for end_time in (start, end)]
    return (spent[1] - spent[0]) / (end - start)


# Each example is imported only in the process that runs it: importing the station's
# (scipy's modules with it) made the span's run in the same process half as costly again.

def station_run(fmu_dir, scheme, path, newton_tolerance, step=STEP):
    import road_wheel_station as station

    if newton_tolerance is not None:
        station.NEWTON_TOLERANCE = _tolerance(newton_tolerance)
    profile = station.RoadProfile()
    return lambda end_time: station.simulate(8.0, profile, step, fmu_dir, end_time=end_time,
                                             coupling=scheme, path=path)


def span_run(fmu_dir, links, path, newton_tolerance, step=STEP):
    import track_span as span

    if newton_tolerance is not None:
        span.NEWTON_TOLERANCE = _tolerance(newton_tolerance)
    return lambda end_time: span.simulate(step, links=links, fmu_dir=fmu_dir,
                                          end_time=end_time, coupling="corrected", path=path)


def _tolerance(text):
    return None if text == "default" else float(text)


def measure(args, kind, scheme, path):
    """CPU seconds per simulated second of one run, in a fresh process."""
    run = subprocess.run([sys.executable, __file__, "--fmus", str(args.fmus), "--links",
                          str(args.links), "--step", repr(args.step),
                          *(["--quick"] if args.quick else []),
                          *(["--newton-tolerance", args.newton_tolerance]
                            if args.newton_tolerance is not None else []),
                          "--one", kind, scheme, path],
                         capture_output=True, text=True, timeout=3600)
    if run.returncode != 0:
        raise RuntimeError(f"{kind} {scheme} {path}: {run.stderr}")
    return float(run.stdout.split()[-1])


def measure_one(args, kind, scheme, path):
    fmu_dir = Path(native_fmus(args.fmus)["TrackBushRadial"]).parent
    # the station from before the bump to its end; the span from its start
    if kind == "station":
        run = station_run(fmu_dir, scheme, path, args.newton_tolerance, args.step)
        times = (0.05, 0.1) if args.quick else (0.1, 0.6)
    else:
        run = span_run(fmu_dir, 3 if args.quick else args.links, path,
                       args.newton_tolerance, args.step)
        times = (0.01, 0.03) if args.quick else (0.05, 0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the bushes' range warnings, once per instance
        return cpu_per_simulated_second(run, *times)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus")
    parser.add_argument("--links", type=int, default=40)
    parser.add_argument("--step", type=float, default=STEP, help="the host step (s)")
    parser.add_argument("--quick", action="store_true", help="seconds: short runs")
    parser.add_argument("--newton-tolerance", help="both examples' Newton tolerance "
                        "(exudyn's absolute tolerance, or 'default'); else each one's own")
    parser.add_argument("--rounds", type=int, default=5,
                        help="rounds of runs, each run once a round (their medians)")
    parser.add_argument("--only", choices=("station", "span"))
    parser.add_argument("--path", choices=("python", "compiled"), help="this path only")
    parser.add_argument("--one", nargs=3, metavar=("KIND", "SCHEME", "PATH"),
                        help="one run in this process (what the others spawn)")
    args = parser.parse_args(argv)
    if args.one:
        print(measure_one(args, *args.one))
        return
    links = 3 if args.quick else args.links
    rounds = 1 if args.quick else args.rounds
    load_before = os.getloadavg()[0]
    runs = []  # (name, path, kind, scheme)
    paths = (args.path,) if args.path else ("python", "compiled")
    if args.only in (None, "station"):
        for scheme in ("explicit", "corrected"):
            for path in paths:
                runs.append((f"station at 8 m/s, `{scheme}`", path, "station", scheme))
    if args.only in (None, "span"):
        for path in paths:
            runs.append((f"track span, {links} links ({2 * (links + 1)} instances), "
                         f"`corrected`", path, "span", "corrected"))
    figures = {(name, path): [] for name, path, _, _ in runs}
    for _ in range(rounds):
        for name, path, kind, scheme in runs:
            figures[name, path].append(measure(args, kind, scheme, path))
    cost = {key: statistics.median(values) for key, values in figures.items()}
    print(f"# The coupling in exudyn: CPU seconds per simulated second "
          f"({args.step * 1e3:g} ms host steps; medians of {rounds} rounds)\n")
    print("| run | path | CPU s per simulated s | real-time factor by CPU | the rounds |")
    print("|---|---|---|---|---|")
    for (name, path), cpu in cost.items():
        print(f"| {name} | {path} | {cpu:.3f} | {1 / cpu:.2f} | "
              f"{', '.join(f'{v:.3f}' for v in figures[name, path])} |")
    for path in paths:
        explicit = figures.get(("station at 8 m/s, `explicit`", path))
        if explicit:
            ratios = [c / e for c, e in zip(figures["station at 8 m/s, `corrected`", path],
                                            explicit)]
            print(f"\nstation, {path} path: `corrected` / `explicit` = "
                  f"{statistics.median(ratios):.2f} (the rounds' ratios "
                  f"{min(ratios):.2f} to {max(ratios):.2f})")
    python_explicit = cost.get(("station at 8 m/s, `explicit`", "python"))
    if python_explicit and ("station at 8 m/s, `corrected`", "compiled") in cost:
        print(f"compiled `corrected` / Python `explicit` = "
              f"{cost[('station at 8 m/s, `corrected`', 'compiled')] / python_explicit:.2f}")
    if args.newton_tolerance is not None:
        print(f"Newton tolerance: {args.newton_tolerance}")
    print(f"load average (1 min) {load_before:.2f} before, {os.getloadavg()[0]:.2f} after, "
          f"{os.cpu_count()} CPUs")


if __name__ == "__main__":
    main()
