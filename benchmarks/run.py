"""Benchmark: cost against the floor, where the time goes, accuracy against cost, and the
vehicle scale. Prints a Markdown report and writes it to a file.

    python benchmarks/run.py                 # the full run (several minutes)
    python benchmarks/run.py --quick         # a few seconds: checks that it all runs

Every figure comes from this one run. Costs are medians over repetitions, with the range;
each repetition measures every FMU and the floor back to back, and the ratios are taken
within a repetition, so a busy machine slows numerator and denominator alike.

* The floor: a pythonfmu FMU built in this run with the same inputs and outputs as the
  rubber FMUs and no work in it (force = deflection).
* Each FMU at h = 1 ms on the standard input, a 1 Hz sine in the thesis range (the damper's
  test A, 0.75 Hz), through fmpy's FMU2Slave: per doStep, and per setReal + doStep + getReal.
* The model alone: the same steps through the Python model and integrator, no FMI.
* Accuracy against cost for h = 1e-4 ... 1e-1 s: the FMU's error against the independent
  reference solve of the same sampled input (fmu_components.reference.solve_held_rate) and
  against the continuous-input solve (solve_smooth), and the cost per simulated second.
* Vehicle scale: 370 instances (24 tyres, 170 bush radial, 170 bush torsion, 6 dampers)
  stepped together for 1 s at 1 ms; wall time and real-time factor.
* A profile of one FMU's doStep (pyinstrument).
"""

import argparse
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "src")]

from fmpy import simulate_fmu  # noqa: E402

from fmu_components import reference  # noqa: E402
from fmu_components.runtime.catalog import COMPONENTS  # noqa: E402
from fmu_components.runtime.cosim import CoSimulation  # noqa: E402
from fmu_components.signals import THESIS_SINES, input_table, thesis_sine, time_grid  # noqa: E402
from fmu_runner import FmuRunner  # noqa: E402

STEP = 1e-3
FLOOR = "Floor"
VEHICLE = {"RoadWheelTyre": 24, "TrackBushRadial": 170, "TrackBushTorsion": 170, "RotaryDamper": 6}

FLOOR_SOURCE = '''"""The floor: the inputs and outputs of a component FMU, and no work."""
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class Floor(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.deflection = self.deflection_rate = 0.0
        self.force = self.force_elastic = self.force_viscoelastic = self.stiffness = 0.0
        self.register_variable(Real("deflection", causality=Fmi2Causality.input, start=0.0))
        self.register_variable(Real("deflection_rate", causality=Fmi2Causality.input, start=0.0))
        for name in ("force", "force_elastic", "force_viscoelastic", "stiffness"):
            self.register_variable(Real(name, causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.force = self.deflection
        return True
'''


def build_floor(directory):
    from pythonfmu.builder import FmuBuilder

    script = directory / "Floor.py"
    script.write_text(FLOOR_SOURCE)
    return Path(FmuBuilder.build_FMU(script, dest=directory))


def timer_overhead():
    """The cost of one perf_counter call: each timed doStep pays for one (the time between
    reading the clock before the call and after it includes one clock call's return and
    the next one's entry)."""
    clock = time.perf_counter
    samples = []
    for _ in range(5):
        start = clock()
        for _ in range(10000):
            clock()
        samples.append((clock() - start) / 10000)
    return statistics.median(samples)


class Timed:
    """One FMU instance on the standard input, stepped in blocks."""

    def __init__(self, path, name, steps):
        self.runner = FmuRunner(path, instance_name=f"bench-{name}")
        self.t, self.x, self.v = thesis_sine(name, steps * STEP, STEP)
        self.k = 0
        self.runner.initialize(self.x[0], self.v[0])
        self.xs, self.vs = self.x.tolist(), self.v.tolist()
        fmu = self.runner.fmu
        self.inputs = [self.runner.vr[n] for n in self.runner.inputs]
        self.outputs = [self.runner.vr[n] for n in self.runner.outputs]
        self.set_real, self.do_step, self.get_real = fmu.setReal, fmu.doStep, fmu.getReal

    def block(self, n, overhead):
        """Mean microseconds per doStep and per setReal + doStep + getReal over n steps."""
        clock = time.perf_counter
        set_real, do_step, get_real = self.set_real, self.do_step, self.get_real
        inputs, outputs, xs, vs = self.inputs, self.outputs, self.xs, self.vs
        stepping = 0.0
        k = self.k
        started = clock()
        for _ in range(n):
            set_real(inputs, [xs[k], vs[k]])
            before = clock()
            do_step(k * STEP, STEP)
            stepping += clock() - before
            get_real(outputs)
            k += 1
        total = clock() - started
        self.k = k
        return (stepping / n - overhead) * 1e6, total / n * 1e6


def cost_table(fmus, floor, repeats, block_steps):
    """{name: {'do_step': [us per repeat], 'cycle': [...]}} with the floor among them."""
    overhead = timer_overhead()
    paths = {FLOOR: floor, **fmus}
    timed = {name: Timed(path, name if name != FLOOR else "RoadWheelTyre", repeats * block_steps + 2)
             for name, path in paths.items()}
    results = {name: {"do_step": [], "cycle": []} for name in paths}
    for _ in range(repeats):
        for name, instance in timed.items():
            step, cycle = instance.block(block_steps, overhead)
            results[name]["do_step"].append(step)
            results[name]["cycle"].append(cycle)
    for instance in timed.values():
        instance.runner.free()
    return results


def model_alone(name, repeats, block_steps):
    """Microseconds per set_inputs + do_step + outputs through the Python model."""
    definition = COMPONENTS[name]
    model = definition.build_model(definition.default_parameters())
    t, x, v = thesis_sine(name, (repeats * block_steps + 1) * STEP, STEP)
    xs, vs = x.tolist(), v.tolist()
    cosim = CoSimulation(model, definition.default_experiment["tolerance"], 0.0, xs[0], vs[0])
    samples = []
    k = 0
    for _ in range(repeats):
        started = time.perf_counter()
        for _ in range(block_steps):
            cosim.set_inputs(xs[k], vs[k])
            cosim.do_step(k * STEP, STEP)
            cosim.outputs()
            k += 1
        samples.append((time.perf_counter() - started) / block_steps * 1e6)
    return samples


def accuracy_against_cost(fmus, steps, periods):
    rows = []
    for name, path in fmus.items():
        mean, amplitude, frequency = THESIS_SINES[name]
        omega = 2 * math.pi * frequency
        duration = periods / frequency
        fine = time_grid(duration, min(steps) / 4)
        smooth = reference.solve_smooth(name, fine, lambda t: mean + amplitude * math.sin(omega * t),
                                        lambda t: amplitude * omega * math.cos(omega * t))
        output = COMPONENTS[name].outputs[0].name
        scale = float(np.ptp(smooth[output]))
        for h in steps:
            t, x, v = thesis_sine(name, duration, h)
            started = time.perf_counter()
            result = simulate_fmu(str(path), stop_time=t[-1], output_interval=h,
                                  input=input_table(name, t, x), output=[output])
            wall = time.perf_counter() - started
            held = reference.solve_held_rate(name, t, x, v)[output]
            truth = np.interp(t, fine, smooth[output])
            rows.append({"fmu": name, "h": h,
                         "error_held_pct": float(np.max(np.abs(result[output] - held)) / scale * 100),
                         "error_smooth_pct": float(np.max(np.abs(result[output] - truth)) / scale * 100),
                         "cost_s_per_s": wall / duration})
    return rows


def vehicle_scale(fmus, counts, duration):
    fleet = []
    for name, n in counts.items():
        fleet += [Timed(fmus[name], name, int(round(duration / STEP)) + 2) for _ in range(n)]
    steps = int(round(duration / STEP))
    started = time.perf_counter()
    for k in range(steps):
        for instance in fleet:
            instance.set_real(instance.inputs, [instance.xs[k], instance.vs[k]])
            instance.do_step(k * STEP, STEP)
            instance.get_real(instance.outputs)
    wall = time.perf_counter() - started
    for instance in fleet:
        instance.runner.free()
    return {"instances": len(fleet), "simulated_s": duration, "wall_s": wall,
            "real_time_factor": duration / wall, "us_per_cycle": wall / (steps * len(fleet)) * 1e6}


def profile(path, name, steps):
    from pyinstrument import Profiler

    instance = Timed(path, name, steps + 2)
    profiler = Profiler(interval=0.0001)
    profiler.start()
    instance.block(steps, 0.0)
    profiler.stop()
    instance.runner.free()
    return profiler.output_text(unicode=False, color=False, show_all=False)


def spread(samples):
    return f"{statistics.median(samples):.2f} ({min(samples):.2f}-{max(samples):.2f})"


def report(costs, alone, accuracy, scale, profile_text):
    lines = ["# Benchmark", "",
             "Medians over repetitions, range in brackets; ratios are taken within each "
             "repetition against the floor measured in it.", "",
             "## Cost at h = 1 ms, standard input", "",
             "| FMU | doStep (us) | doStep / floor | set + step + get (us) | cycle / floor | model alone (us) |",
             "|---|---|---|---|---|---|"]
    floor = costs[FLOOR]
    for name, result in costs.items():
        ratio_step = [a / b for a, b in zip(result["do_step"], floor["do_step"])]
        ratio_cycle = [a / b for a, b in zip(result["cycle"], floor["cycle"])]
        model = spread(alone[name]) if name in alone else "-"
        lines.append(f"| {name} | {spread(result['do_step'])} | {spread(ratio_step)} | "
                     f"{spread(result['cycle'])} | {spread(ratio_cycle)} | {model} |")
    lines += ["", "## Accuracy against cost", "",
              "Error in % of the output's peak-to-peak range: against the independent solve of "
              "the same sampled input (the FMU's own error), and against the continuous-input "
              "solve (adds the co-simulation's sampling of the input).", "",
              "| FMU | h (s) | error, same input (%) | error, continuous input (%) | cost per simulated s (s) |",
              "|---|---|---|---|---|"]
    for row in accuracy:
        lines.append(f"| {row['fmu']} | {row['h']:g} | {row['error_held_pct']:.2e} | "
                     f"{row['error_smooth_pct']:.3f} | {row['cost_s_per_s']:.4f} |")
    lines += ["", "## Vehicle scale", "",
              f"{scale['instances']} instances stepped together for {scale['simulated_s']:g} s at "
              f"1 ms: wall time {scale['wall_s']:.2f} s, real-time factor "
              f"{scale['real_time_factor']:.4f} ({scale['us_per_cycle']:.1f} us per "
              f"set + step + get).", "",
              "## Profile of one doStep", "", "```", profile_text.strip(), "```", ""]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus")
    parser.add_argument("--output", type=Path, default=ROOT / "benchmarks" / "results.md")
    parser.add_argument("--quick", action="store_true", help="a few seconds: small sizes")
    parser.add_argument("--json", type=Path, help="also write the figures as JSON")
    args = parser.parse_args(argv)
    if args.quick:
        repeats, block, steps, periods, counts = 3, 300, [1e-2, 1e-1], 0.2, {n: 1 for n in VEHICLE}
        profile_steps, duration = 300, 0.2
    else:
        repeats, block, steps, periods, counts = 9, 2000, [1e-4, 1e-3, 1e-2, 1e-1], 1.0, VEHICLE
        profile_steps, duration = 20000, 1.0
    fmus = {name: args.fmus / f"{name}.fmu" for name in COMPONENTS}
    with tempfile.TemporaryDirectory() as tmp:
        floor = build_floor(Path(tmp))
        costs = cost_table(fmus, floor, repeats, block)
    alone = {name: model_alone(name, repeats, block) for name in COMPONENTS}
    accuracy = accuracy_against_cost(fmus, steps, periods)
    scale = vehicle_scale(fmus, counts, duration)
    profile_text = profile(fmus["TrackBushTorsion"], "TrackBushTorsion", profile_steps)
    text = report(costs, alone, accuracy, scale, profile_text)
    print(text)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(text)
    if args.json:
        args.json.write_text(json.dumps({"costs": costs, "model_alone": alone,
                                         "accuracy": accuracy, "vehicle_scale": scale}))


if __name__ == "__main__":
    main()
