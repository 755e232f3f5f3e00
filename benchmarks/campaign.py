"""Campaigns on Dask (docs/campaigns.md): what two workers gain, what a task costs, and a
ride map's 60 station runs, each as ratios or times within one run of this script.

    python benchmarks/campaign.py [--case GLOB] [--end-time S] [--tasks N] [--fit-starts N]
                                  [--skip verify|overhead|fit|station ...]

* verify: ``fmu-components verify`` over every case (or --case), simulations and plots, on
  a local cluster of 2 workers against one of 1 worker (the target: 1.8 times faster or
  better on 2 cores), and in this process without a cluster (``--jobs 1``);
* overhead: N tasks that do nothing but carry an FMU (260 kB, as every campaign task
  does) through a 1-worker local cluster, end to end per task (the target: at most 50 ms);
* fit: ``lab.fit.fit`` of every fitted parameter of the radial bush (14) to two measured
  sines (--fit-cycles of 200 samples each, synthetic, 0.5 % noise) from --fit-starts starts, in this
  process (--jobs 1) against a local cluster of 2 workers (with 1 start, each Jacobian's
  columns in 2 tasks; with 2 starts, each start a task); the parameters must be equal;
* station: a ride map of 5 speeds x 3 courses x 4 parts = 60 runs of the road-wheel station
  example on a local cluster of one worker per core, --end-time seconds each (0.5 s by
  default: the bump, met at 0.5 m, within it at every speed; the example's own end, the bump
  passed + 1 s, takes four to ten times longer per run).

Figures are measurements, not pass/fail. Run it on an otherwise idle machine.
"""

import argparse
import json
import tempfile
import time
from pathlib import Path

from fmu_components.campaign.engine import Engine, one_thread_per_process

one_thread_per_process()  # before numpy loads, as the command line does

from fmu_components import cli  # noqa: E402
from fmu_components.campaign.grid import read_grid  # noqa: E402
from fmu_components.campaign.payload import Payload  # noqa: E402
from fmu_components.campaign.run import run_grid  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RIDE_MAP = {
    "run": "station", "speeds": [3, 5, 8, 11, 15],
    "courses": {"bump30": {"bump_start": 0.5},
                "bump60": {"bump_start": 0.5, "bump_height": 0.06},
                "ripple": {"bump_height": 0.0, "ripple_depth": 2e-3}},
    "parameter_sets": {"thesis": {},
                       "soft_tyre": {"RoadWheelTyre": {"k1": 1.05e6}},
                       "stiff_tyre": {"RoadWheelTyre": {"k1": 1.95e6}},
                       "stiff_gas_spring": {"RotaryDamper": {"C1": 1200.0}}},
}


def local_cluster(workers):
    from distributed import LocalCluster

    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                        dashboard_address=":0")


def time_verify(cases, workers, folder):
    """(wall seconds, this process's CPU seconds) of the verify command on a local cluster
    of `workers` (None: in this process, --jobs 1). On a cluster this process is the
    client: its CPU time is what does not run on the workers."""
    arguments = ["verify", "--report", str(folder)] + [f"--case={c}" for c in cases]
    if workers is None:
        started, cpu = time.perf_counter(), time.process_time()
        cli.main(arguments + ["--jobs", "1"])
        return time.perf_counter() - started, time.process_time() - cpu
    with local_cluster(workers) as cluster:
        started, cpu = time.perf_counter(), time.process_time()
        cli.main(arguments + ["--scheduler", cluster.scheduler_address])
        return time.perf_counter() - started, time.process_time() - cpu


def carry(fmu):
    return len(fmu)


def overhead(tasks):
    """Seconds per task of `tasks` tasks that only carry an FMU, on one local worker."""
    fmu = Payload.of(ROOT / "fmus" / "TrackBushRadial.fmu")
    with local_cluster(1) as cluster, Engine(cluster.scheduler_address) as engine:
        engine.map(carry, [(fmu,)] * 4)  # the worker's first imports, not counted
        started = time.perf_counter()
        engine.map(carry, [(fmu,)] * tasks)
        return (time.perf_counter() - started) / tasks


def fit_problem(cycles):
    """Two measured sines of the radial bush (1 and 10 Hz, `cycles` cycles of 200 samples),
    from the independent solve with 0.5 % noise."""
    import math

    import numpy as np

    from fmu_components.verification import synthetic

    component = "TrackBushRadial"
    truth = synthetic.scaled(component, {"k": 1.5, "c": 0.7})
    tests = []
    for frequency in (1.0, 10.0):
        times = np.arange(200 * cycles + 1) / (frequency * 200)
        tests.append(synthetic.measure_path(
            component, f"{frequency:g}Hz.csv", times,
            lambda t, f=frequency: 3e-4 + 1e-4 * np.sin(2 * math.pi * f * t), truth, 0.005,
            0)[0])
    return component, tests


def time_fit(starts, cycles, workers):
    """(wall seconds, the fitted values) of the fit in this process (workers None) or on a
    local cluster of `workers`."""
    from fmu_components.campaign.tasks import fit_runner
    from fmu_components.lab.fit import fit

    component, tests = fit_problem(cycles)
    if workers is None:
        engine = Engine(jobs=1)
    else:
        cluster = local_cluster(workers)
        engine = Engine(cluster.scheduler_address)
    with engine:
        engine.start()
        started = time.perf_counter()
        # pays=0: the Jacobian's columns on the workers whatever an evaluation costs
        result = fit(component, tests, starts=starts, runner=fit_runner(engine, pays=0))
        wall = time.perf_counter() - started
    if workers is not None:
        cluster.close()
    return wall, result.values


def station(end_time, folder):
    grid_file = folder / "ride_map.json"
    grid_file.write_text(json.dumps(dict(RIDE_MAP, end_time=end_time)))
    grid = read_grid(grid_file)
    with Engine() as engine:  # one worker per core
        started = time.perf_counter()
        outcome = run_grid(grid, folder / "ride_map", engine)
        wall = time.perf_counter() - started
        workers = engine.workers
    return len(grid.runs), len(outcome.failures), wall, workers, outcome.table


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", action="append", default=[],
                        help="only these verify cases (default: every case)")
    parser.add_argument("--end-time", type=float, default=0.5,
                        help="s simulated by each station run (default 0.5)")
    parser.add_argument("--tasks", type=int, default=200, help="tasks of the overhead test")
    parser.add_argument("--fit-starts", type=int, default=1, help="starts of the fit (1)")
    parser.add_argument("--fit-cycles", type=int, default=10,
                        help="cycles of each measured sine of the fit, 200 samples each (10)")
    parser.add_argument("--skip", nargs="+", default=[],
                        choices=["verify", "overhead", "fit", "station"])
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        if "verify" not in args.skip:
            timed = {n: time_verify(args.case, n, scratch / f"verify{n}") for n in (1, 2, None)}
            walls = {n: wall for n, (wall, _) in timed.items()}
            print(f"verify{' ' + ' '.join(args.case) if args.case else ', every case'}: "
                  f"2 workers {walls[2]:.1f} s, 1 worker {walls[1]:.1f} s, in this process "
                  f"{walls[None]:.1f} s: 2 workers {walls[1] / walls[2]:.2f} times as fast as 1; "
                  f"the client's CPU {timed[2][1]:.1f} s on 2 workers, {timed[1][1]:.1f} s on "
                  f"1 (in this process, everything: {timed[None][1]:.1f} s)")
        if "overhead" not in args.skip:
            per_task = overhead(args.tasks)
            print(f"overhead: {per_task * 1e3:.1f} ms per task carrying an FMU "
                  f"({args.tasks} tasks, 1 worker)")
        if "fit" not in args.skip:
            (serial, expected), (two, values) = (time_fit(args.fit_starts, args.fit_cycles, n)
                                                for n in (None, 2))
            assert values == expected, "the fit on 2 workers differs from the serial fit"
            print(f"fit, 14 parameters, {args.fit_starts} start(s), 2 x "
                  f"{200 * args.fit_cycles + 1} samples: in this process "
                  f"{serial:.1f} s, 2 workers {two:.1f} s: {serial / two:.2f} times as fast; "
                  f"the same parameters")
        if "station" in args.skip:
            return
        runs, failed, wall, workers, table = station(args.end_time, scratch)
        walls = [row["wall_s"] for row in table.rows.values() if "wall_s" in row]
        print(f"station ride map: {runs} runs of {args.end_time:g} s on {workers} local workers "
              f"in {wall:.1f} s ({failed} failed); one run {min(walls):.1f} to "
              f"{max(walls):.1f} s, {sum(walls):.1f} s in all")


if __name__ == "__main__":
    main()
