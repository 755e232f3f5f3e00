"""Scale: many instances in one process, and long runs.

    python benchmarks/scale.py instances [--count 400] [--duration 1.0]
    python benchmarks/scale.py long-run [--steps 1000000]

`instances` builds a vehicle's mix of instances (by default 400: 24 tyres, 185 bush radial,
185 bush torsion, 6 dampers), steps them together at 1 ms, and checks each against a
single-instance run of the same input. `long-run` drives the torsion bush through a 1 Hz
sine for the given number of 1 ms steps and checks that it sits on a periodic steady state.
Both report memory (RSS) and time, print a summary and, with --json, the figures as JSON.
Figures are measurements, not pass/fail; the exit code is non-zero only if a check fails.
"""

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from fmu_components.lab.signals import THESIS_SINES, thesis_sine  # noqa: E402
from fmu_runner import FmuRunner  # noqa: E402

STEP = 1e-3
VEHICLE_MIX = {"RoadWheelTyre": 24, "TrackBushRadial": 185, "TrackBushTorsion": 185,
               "RotaryDamper": 6}
VARIANTS = 4  # instances of one FMU get one of four phases


def rss_mib():
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS in /proc/self/status")


def variant_input(name, variant, duration):
    _, x, v = thesis_sine(name, duration, STEP, phase=2 * math.pi * variant / VARIANTS)
    return x, v


def mix(count):
    """The vehicle mix scaled to `count` instances, at least one of each FMU."""
    total = sum(VEHICLE_MIX.values())
    counts = {name: max(1, round(n * count / total)) for name, n in VEHICLE_MIX.items()}
    counts["TrackBushRadial"] += count - sum(counts.values())
    return counts


def instances(fmu_dir, count, duration):
    counts = mix(count)
    inputs = {(name, k): variant_input(name, k, duration) for name in counts for k in range(VARIANTS)}

    # One instance at a time: the results every instance of the mix must reproduce.
    single = {}
    for (name, k), (x, v) in inputs.items():
        runner = FmuRunner(fmu_dir / f"{name}.fmu", f"single-{name}-{k}")
        runner.initialize(x[0], v[0])
        single[(name, k)] = runner.run(x, v, STEP)
        runner.free()

    rss_before = rss_mib()
    started = time.perf_counter()
    fleet = []
    for name, n in counts.items():
        for i in range(n):
            runner = FmuRunner(fmu_dir / f"{name}.fmu", f"{name}-{i}")
            x, v = inputs[(name, i % VARIANTS)]
            runner.initialize(x[0], v[0])
            fleet.append((runner, name, i % VARIANTS))
    load_time = time.perf_counter() - started
    rss_loaded = rss_mib()

    steps = len(next(iter(inputs.values()))[0]) - 1
    results = [np.empty((steps, len(runner.outputs))) for runner, _, _ in fleet]
    started = time.perf_counter()
    for k in range(steps):
        for (runner, name, variant), result in zip(fleet, results):
            x, v = inputs[(name, variant)]
            result[k] = runner.step(x[k], v[k], STEP)
    stepping_time = time.perf_counter() - started
    mismatches = sum(not np.array_equal(result, single[(name, variant)])
                     for (runner, name, variant), result in zip(fleet, results))
    for runner, _, _ in fleet:
        runner.free()
    return {
        "instances": len(fleet), "mix": counts, "steps": steps,
        "load_time_s": load_time, "load_time_per_instance_ms": load_time / len(fleet) * 1e3,
        "memory_per_instance_kib": (rss_loaded - rss_before) * 1024 / len(fleet),
        "rss_before_mib": rss_before, "rss_loaded_mib": rss_loaded, "rss_end_mib": rss_mib(),
        "stepping_time_s": stepping_time,
        "do_step_cycles_per_s": len(fleet) * steps / stepping_time,
        "mismatches": mismatches,
    }


def long_run(fmu_dir, steps):
    name = "TrackBushTorsion"
    mean, amplitude, frequency = THESIS_SINES[name]
    period = int(round(1.0 / frequency / STEP))
    runner = FmuRunner(fmu_dir / f"{name}.fmu", instance_name="long-run")
    omega = 2 * math.pi * frequency
    cycle_x = mean + amplitude * np.sin(omega * STEP * np.arange(period + 1))
    cycle_v = np.diff(cycle_x) / STEP
    runner.initialize(cycle_x[0], cycle_v[0])
    outputs = np.empty(period)
    previous = None
    rss = {}
    started = time.perf_counter()
    for k in range(steps):
        j = k % period
        runner.set_inputs(cycle_x[j], cycle_v[j])
        runner.fmu.doStep(k * STEP, STEP)  # the host's time, k * h, as a counter gives it
        outputs[j] = runner.fmu.getReal([runner.vr["torque"]])[0]
        if j == period - 1:
            cycles = (k + 1) // period
            if cycles == 2:
                rss["start_mib"] = rss_mib()  # after a warm-up cycle
            if cycles < steps // period:
                previous = outputs.copy()
    wall = time.perf_counter() - started
    rss["end_mib"] = rss_mib()
    runner.free()
    cycle_to_cycle = float(np.max(np.abs(outputs - previous)) / np.ptp(outputs))
    return {"steps": steps, "simulated_s": steps * STEP, "wall_time_s": wall,
            "us_per_cycle": wall / steps * 1e6,
            "rss_start_mib": rss["start_mib"], "rss_end_mib": rss["end_mib"],
            "rss_growth_mib": rss["end_mib"] - rss["start_mib"],
            "last_cycle_change_of_peak_to_peak": cycle_to_cycle,
            "torque_range_last_cycle": [float(outputs.min()), float(outputs.max())]}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("job", choices=["instances", "long-run"])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus")
    parser.add_argument("--count", type=int, default=400)
    parser.add_argument("--duration", type=float, default=1.0)
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if args.job == "instances":
        figures = instances(args.fmus, args.count, args.duration)
        failed = figures["mismatches"] > 0
    else:
        figures = long_run(args.fmus, args.steps)
        failed = figures["last_cycle_change_of_peak_to_peak"] > 1e-9 or figures["rss_growth_mib"] > 16
    if args.json:
        print(json.dumps(figures))
    else:
        for key, value in figures.items():
            print(f"{key:40s} {value:.6g}" if isinstance(value, float) else f"{key:40s} {value}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
