"""Benchmark: the coupling at vehicle scale, its Python path (Coupling) against its
compiled path (Bank), and both against the C host's corrected cycle.

    python benchmarks/coupling_scale.py               # 10, 100, 362, 1000 instances (minutes)
    python benchmarks/coupling_scale.py --quick       # seconds: checks that it runs
    python benchmarks/coupling_scale.py --long        # also 10^6 bank steps: memory

The vehicle mix: 2 x (14 tyre halves + 7 dampers + 80 links x 2 bush elements) = 362
instances, scaled to each count. The host is synthetic (no multibody engine): each
instance follows its thesis sine at 1 ms steps (four phases), and the `corrected` scheme
makes two passes per step, the second at a deflection a little off the first (as a host's
second solve is), so every step saves, steps, restores and steps each FMU again, and
makes every law. Per count and path: microseconds per host step and per instance step,
the real-time factor (simulated time over wall time), and the ratio of the per-instance
cost to the C host's corrected cycle (c_host/bench_host.c `rollback`, as
rollback_cost.py measures it), mix-weighted, measured in this run, wall time to wall time
and CPU time to CPU time (on a loaded machine the wall times of both stretch unevenly:
compare CPU times there). The machine's pace moves by up to a factor of two between
runs of a few milliseconds, so the C host and the compiled path are measured in rounds, one
after the other, and each ratio is taken within its round; the figures printed are the
rounds' medians. The load average is printed with them.
"""

import argparse
import math
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from rollback_cost import measure  # noqa: E402
from run import ROOT, native_fmus  # noqa: E402

from fmu_components.coupling import Coupling, FmuComponent  # noqa: E402
from fmu_components.coupling.bank import Bank  # noqa: E402
from fmu_components.lab.signals import thesis_sine  # noqa: E402

STEP = 1e-3
VEHICLE = {"RoadWheelTyre": 28, "RotaryDamper": 14, "TrackBushRadial": 160,
           "TrackBushTorsion": 160}
PHASES = 4
SECOND_PASS = 1e-3  # the second solve's deflection: off the first by this share of the sine


def mix(count):
    """The vehicle mix scaled to `count` instances, at least one of each FMU."""
    total = sum(VEHICLE.values())
    counts = {name: max(1, round(n * count / total)) for name, n in VEHICLE.items()}
    counts["TrackBushRadial"] += count - sum(counts.values())
    return counts


def inputs(counts, steps):
    """Per instance, its deflection at each step and the second pass's."""
    rows, names = [], []
    for name, n in counts.items():
        for i in range(n):
            _, x, _ = thesis_sine(name, (steps + 1) * STEP, STEP,
                                  phase=2 * math.pi * (i % PHASES) / PHASES)
            rows.append(x[:steps + 1])
            names.append(name)
    x = np.array(rows)
    second = x + SECOND_PASS * (x.max(axis=1, keepdims=True) - x.min(axis=1, keepdims=True))
    return names, x, second


def components(fmus, names):
    return [FmuComponent(fmus[name], f"{name}_{i}", unilateral=name == "RoadWheelTyre")
            for i, name in enumerate(names)]


def run_python(fmus, names, x, second, steps):
    """Seconds (wall, CPU) per host step on the Python path."""
    made = components(fmus, names)
    coupling = Coupling("corrected")
    now = [0, x]
    for i, component in enumerate(made):
        coupling.add(component, lambda i=i: (now[1][i, now[0]], 0.0))
    coupling.start(0.0)
    wall, cpu = time.perf_counter(), time.process_time()
    for k in range(1, steps + 1):
        now[:] = k, x
        coupling.begin_step(k * STEP)
        coupling.end_pass(k * STEP)
        now[1] = second
        coupling.end_pass(k * STEP)
        coupling.accept(k * STEP)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    coupling.free()
    return wall / steps, cpu / steps


def run_bank(fmus, names, x, second, steps):
    """Seconds (wall, CPU) per host step on the compiled path."""
    bank = Bank(components(fmus, names), "corrected")
    bank.start(0.0, x[:, 0])
    columns, seconds = np.ascontiguousarray(x.T), np.ascontiguousarray(second.T)
    wall, cpu = time.perf_counter(), time.process_time()
    for k in range(1, steps + 1):
        t = k * STEP
        bank.begin_step(t)  # begun already by the accept before it, but for the first
        bank.end_pass(t, columns[k])
        bank.end_pass(t, seconds[k])
        # the next step begins in accept's call: its end as begin_step will be given it
        # ((k + 1) * STEP, not t + STEP: a different float begins the step again)
        bank.accept(t, (k + 1) * STEP if k < steps else None)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    bank.free()
    return wall / steps, cpu / steps


def c_host_cycles(fmus, repeats, steps):
    """{FMU: (median microseconds of the C host's corrected cycle, wall and CPU)}
    (rollback_cost.py's)."""
    return {name: (statistics.median(r["corrected"]), statistics.median(r["corrected_cpu"]))
            for name, r in measure(fmus, repeats, steps).items()}


def long_run(fmus, steps):
    """RSS before and after `steps` corrected bank steps of one instance of each rubber FMU."""
    def rss_mib():
        return int(Path("/proc/self/statm").read_text().split()[1]) * 4 / 1024

    names = ["RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion"]
    _, x, second = inputs({n: 1 for n in names}, 4000)
    bank = Bank(components(fmus, names), "corrected")
    bank.start(0.0, x[:, 0])
    columns, seconds = np.ascontiguousarray(x.T), np.ascontiguousarray(second.T)
    started = time.perf_counter()
    for k in range(1, steps + 1):
        j = (k - 1) % 4000 + 1  # the sine's first 4 s again and again (its period divides 4 s)
        t = k * STEP
        bank.begin_step(t)
        bank.end_pass(t, columns[j])
        bank.end_pass(t, seconds[j])
        bank.accept(t, (k + 1) * STEP if k < steps else None)
        if k == 10_000:
            early = rss_mib()
    wall = time.perf_counter() - started
    bank.free()
    return early, rss_mib(), wall


def c_host_per_instance(cycles, counts):
    """The C host's corrected cycle per instance of a mix, mix-weighted: (wall, CPU) us."""
    n = sum(counts.values())
    return tuple(sum(cycles[name][j] * k for name, k in counts.items()) / n for j in (0, 1))


def compiled_rounds(fmus, mixes, steps, rounds, c_steps):
    """Per round, the C host's cycles and then the compiled path at each count, so that each
    ratio is taken against the C host measured beside it: {count: [(wall, CPU, ratio wall,
    ratio CPU), ...]} and the rounds' C host cycles."""
    figures, all_cycles = {count: [] for count in mixes}, []
    driven = {count: inputs(counts, steps) for count, counts in mixes.items()}  # made once
    for _ in range(rounds):
        cycles = c_host_cycles(fmus, 1, c_steps)
        all_cycles.append(cycles)
        for count, counts in mixes.items():
            n = sum(counts.values())
            wall, cpu = run_bank(fmus, *driven[count], steps)
            c_wall, c_cpu = c_host_per_instance(cycles, counts)
            figures[count].append((wall, cpu, wall * 1e6 / n / c_wall, cpu * 1e6 / n / c_cpu))
    return figures, all_cycles


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus")
    parser.add_argument("--counts", type=int, nargs="+", default=[10, 100, 362, 1000])
    parser.add_argument("--steps", type=int, default=1000, help="host steps, compiled path")
    parser.add_argument("--rounds", type=int, default=5,
                        help="rounds of the C host and the compiled path (their medians)")
    parser.add_argument("--python-steps", type=int, default=20, help="host steps, Python path")
    parser.add_argument("--quick", action="store_true", help="seconds: small sizes")
    parser.add_argument("--long", action="store_true", help="also 10^6 bank steps: memory")
    args = parser.parse_args(argv)
    if args.quick:
        args.counts, args.steps, args.python_steps, args.rounds = [10, 40], 50, 5, 1
    fmus = native_fmus(args.fmus)
    load_before = os.getloadavg()[0]
    mixes = {count: mix(count) for count in args.counts}
    figures, all_cycles = compiled_rounds(fmus, mixes, args.steps, args.rounds,
                                          2000 if args.quick else 10000)
    cycles = {name: tuple(statistics.median(c[name][j] for c in all_cycles) for j in (0, 1))
              for name in all_cycles[0]}
    print("# The coupling at vehicle scale: Python path, compiled path (bank), C host\n")
    print(f"C host's corrected cycle (us, median of {args.rounds} rounds, wall / CPU): "
          + ", ".join(f"{n} {c:.3f} / {u:.3f}" for n, (c, u) in cycles.items()) + "\n")
    print("| instances | path | us per host step (wall) | us per instance step (wall) | "
          "CPU us per host step | real-time factor (wall) | per instance / C host (wall) | "
          "per instance / C host (CPU) |")
    print("|---|---|---|---|---|---|---|---|")
    for count, counts in mixes.items():
        n = sum(counts.values())
        c_wall, c_cpu = c_host_per_instance(cycles, counts)
        names, x, second = inputs(counts, args.python_steps)
        wall, cpu = run_python(fmus, names, x, second, args.python_steps)
        print(f"| {n} | Python | {wall * 1e6:.1f} | {wall * 1e6 / n:.3f} | {cpu * 1e6:.1f} | "
              f"{STEP / wall:.3g} | {wall * 1e6 / n / c_wall:.2f} | "
              f"{cpu * 1e6 / n / c_cpu:.2f} |", flush=True)
        wall, cpu, ratio, ratio_cpu = (statistics.median(f[j] for f in figures[count])
                                       for j in range(4))
        spread = (f" ({min(f[3] for f in figures[count]):.2f} to "
                  f"{max(f[3] for f in figures[count]):.2f})" if args.rounds > 1 else "")
        print(f"| {n} | compiled | {wall * 1e6:.1f} | {wall * 1e6 / n:.3f} | {cpu * 1e6:.1f} | "
              f"{STEP / wall:.3g} | {ratio:.2f} | {ratio_cpu:.2f}{spread} |", flush=True)
    print(f"\nload average (1 min) {load_before:.2f} before, {os.getloadavg()[0]:.2f} after, "
          f"{os.cpu_count()} CPUs; 1 ms host steps, `corrected`, two passes per step; "
          f"the compiled path's figures are medians over {args.rounds} rounds, each ratio "
          f"taken against the C host measured in its round (the CPU ratio's range in "
          f"brackets); the Python path runs once, against the rounds' median C host.")
    if args.long:
        steps = 1_000_000
        early, late, wall = long_run(fmus, steps)
        print(f"\n{steps} corrected bank steps of three instances: RSS {early:.1f} MiB after "
              f"10,000 steps, {late:.1f} MiB at the end; {wall:.1f} s wall")


if __name__ == "__main__":
    main()
