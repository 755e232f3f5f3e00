"""Benchmark: cost against the floor in two hosts, the model without FMI, accuracy against
cost, and the vehicle scale. Prints a Markdown report and writes it to a file.

    python benchmarks/run.py                 # the full run (a few minutes)
    python benchmarks/run.py --quick         # seconds: checks that it all runs

Every figure comes from this one run. Costs are medians over repetitions, with the range;
each repetition measures every FMU and the floors back to back, and the ratios are taken
within a repetition, so a busy machine slows numerator and denominator alike.

* Hosts: fmpy (``FMU2Slave``, Python's ctypes) and a C host (``c_host/bench_host.c``,
  compiled here: it loads the binary with dlopen and times the calls itself).
* Floors, built in this run with a component's inputs and outputs and no work in them
  (force = deflection): a native one (``c_host/floor.c``) in each host, and a pythonfmu one
  in fmpy (the Python flavour's own floor).
* Each FMU of both flavours at h = 1 ms on the standard input, a 1 Hz sine in the thesis
  range (the damper's test A, 0.75 Hz): per doStep, and per setReal + doStep + getReal.
* The model without FMI: the Python model and integrator (``CoSimulation``), and the native
  model compiled with its FMU's sources (``c_host/bench_model.c``).
* Accuracy against cost for h = 1e-4 ... 1e-1 s (native FMUs; the Python ones give the same
  bits): the error against the independent reference solve of the same sampled input
  (``fmu_components.verification.reference.solve_held_rate``) and against the continuous-input solve
  (``solve_smooth``), and the cost per simulated second.
* Vehicle scale: 370 instances (24 tyres, 170 bush radial, 170 bush torsion, 6 dampers)
  stepped together for 1 s at 1 ms, in the C host and in fmpy, each flavour; wall time and
  real-time factor.
* A profile of one Python FMU's doStep (pyinstrument).
"""

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
HERE = ROOT / "benchmarks"
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "src")]

from fmpy import read_model_description, simulate_fmu  # noqa: E402

from fmu_components.verification import reference  # noqa: E402
from fmu_components.runtime.catalog import COMPONENTS  # noqa: E402
from fmu_components.runtime.cosim import CoSimulation  # noqa: E402
from fmu_components.lab.signals import THESIS_SINES, input_table, thesis_sine, time_grid  # noqa: E402
from fmu_runner import FmuRunner  # noqa: E402

STEP = 1e-3
FLOOR, PYTHON_FLOOR = "Floor", "Floor (pythonfmu)"
FLAVOURS = ("native", "python")
VEHICLE = {"RoadWheelTyre": 24, "TrackBushRadial": 170, "TrackBushTorsion": 170, "RotaryDamper": 6}

PYTHON_FLOOR_SOURCE = '''"""The floor: the inputs and outputs of a component FMU, and no work."""
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

FLOOR_GUID = "{floor-0000-0000-0000-000000000000}"


def fmi_headers():
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def compile_c(sources, output, *flags):
    subprocess.run(["gcc", "-O2", "-std=c99", f"-I{fmi_headers()}", *flags, *map(str, sources),
                    "-o", str(output), "-lm", "-ldl"], check=True)
    return output


def build_floors(directory):
    """{FLOOR: native floor FMU, PYTHON_FLOOR: pythonfmu floor FMU}."""
    from pythonfmu.builder import FmuBuilder

    binary = compile_c([HERE / "c_host" / "floor.c"], directory / "Floor.so", "-shared", "-fPIC")
    variables = "".join(
        f'<ScalarVariable name="{name}" valueReference="{vr}" causality="{causality}">'
        f'<Real{start}/></ScalarVariable>'
        for vr, (name, causality, start) in enumerate(
            [("deflection", "input", ' start="0"'), ("deflection_rate", "input", ' start="0"')]
            + [(n, "output", "") for n in ("force", "force_elastic", "force_viscoelastic",
                                           "stiffness")]))
    description = (
        '<?xml version="1.0" encoding="UTF-8"?><fmiModelDescription fmiVersion="2.0" '
        f'modelName="Floor" guid="{FLOOR_GUID}"><CoSimulation modelIdentifier="Floor" '
        f'needsExecutionTool="false"/><ModelVariables>{variables}</ModelVariables>'
        '<ModelStructure><Outputs><Unknown index="3"/><Unknown index="4"/><Unknown index="5"/>'
        '<Unknown index="6"/></Outputs></ModelStructure></fmiModelDescription>')
    native = directory / "Floor.fmu"
    with zipfile.ZipFile(native, "w") as archive:
        archive.writestr("modelDescription.xml", description)
        archive.write(binary, "binaries/linux64/Floor.so")
        archive.writestr("resources/README.txt", "the benchmark's floor\n")
    script = directory / "python" / "Floor.py"
    script.parent.mkdir()
    script.write_text(PYTHON_FLOOR_SOURCE)
    return {FLOOR: native, PYTHON_FLOOR: Path(FmuBuilder.build_FMU(script, dest=script.parent))}


def timer_overhead():
    """The cost of one perf_counter call: each timed doStep pays for one. The least of the
    batches, so that a batch a busy machine interrupted does not inflate it."""
    clock = time.perf_counter
    samples = []
    for _ in range(5):
        start = clock()
        for _ in range(10000):
            clock()
        samples.append((clock() - start) / 10000)
    return min(samples)


def standard_input(name):
    """The standard input of a component (floors: the tyre's)."""
    return name if name in COMPONENTS else "RoadWheelTyre"


class Timed:
    """One FMU instance in fmpy on the standard input, stepped in blocks."""

    def __init__(self, path, name, steps):
        self.runner = FmuRunner(path, instance_name=f"bench-{name}")
        self.t, self.x, self.v = thesis_sine(standard_input(name), steps * STEP, STEP)
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


class Unpacked:
    """FMUs extracted once, and what a C host needs to load each."""

    def __init__(self, directory):
        self.directory = directory
        self.places = {}

    def spec(self, path, name, count=1):
        """The C host's ten arguments for `count` instances of an FMU."""
        path = Path(path)
        if path not in self.places:
            target = self.directory / f"{len(self.places)}_{path.stem}"
            with zipfile.ZipFile(path) as archive:
                archive.extractall(target)
            self.places[path] = target
        target = self.places[path]
        description = read_model_description(str(target / "modelDescription.xml"))
        vr = {v.name: v.valueReference for v in description.modelVariables}
        inputs = [v.name for v in description.modelVariables if v.causality == "input"]
        outputs = [str(vr[v.name]) for v in description.modelVariables if v.causality == "output"]
        identifier = description.coSimulation.modelIdentifier
        mean, amplitude, frequency = THESIS_SINES[standard_input(name)]
        return [str(count), str(target / "binaries" / "linux64" / f"{identifier}.so"),
                (target / "resources").as_uri(), description.guid, str(vr[inputs[0]]),
                str(vr[inputs[1]]), ",".join(outputs), repr(mean), repr(amplitude),
                repr(frequency)]


def native_fmus(folder, subfolder=""):
    """{name: path} of the four native FMUs in folder/subfolder, or exit saying to build."""
    fmus = {n: Path(folder) / subfolder / f"{n}.fmu" for n in COMPONENTS}
    missing = [str(p) for p in fmus.values() if not p.exists()]
    if missing:
        sys.exit(f"missing {', '.join(missing)}: build the FMUs first (python build_fmus.py)")
    return fmus


def run_c_host(host, *arguments):
    run = subprocess.run([str(host), *arguments], capture_output=True, text=True, timeout=900)
    if run.returncode != 0:
        raise RuntimeError(f"{host.name} {arguments[0]} failed: {run.stderr}")
    return [[float(v) for v in line.split()] for line in run.stdout.splitlines()]


def cost_table(fmus, floors, unpacked, host, repeats, block_steps):
    """{host: {name: {'do_step': [us per repeat], 'cycle': [...]}}}, names as
    'flavour/FMU' and the floors."""
    fmpy_paths = {**floors, **{f"{f}/{n}": p for f, paths in fmus.items() for n, p in paths.items()}}
    c_paths = {k: v for k, v in fmpy_paths.items() if k != PYTHON_FLOOR}
    overhead = timer_overhead()
    timed = {name: Timed(path, name.split("/")[-1], repeats * block_steps + 2)
             for name, path in fmpy_paths.items()}
    results = {"fmpy": {n: {"do_step": [], "cycle": []} for n in fmpy_paths},
               "c_host": {n: {"do_step": [], "cycle": []} for n in c_paths}}
    for _ in range(repeats):
        for name, instance in timed.items():
            step, cycle = instance.block(block_steps, overhead)
            results["fmpy"][name]["do_step"].append(step)
            results["fmpy"][name]["cycle"].append(cycle)
        for name, path in c_paths.items():
            (step, cycle), = run_c_host(host, "cost", str(block_steps), "1",
                                        *unpacked.spec(path, name.split("/")[-1]))
            results["c_host"][name]["do_step"].append(step)
            results["c_host"][name]["cycle"].append(cycle)
    for instance in timed.values():
        instance.runner.free()
    return results


def python_model_alone(name, repeats, block_steps):
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


def native_model_alone(path, name, unpacked, directory, repeats, block_steps):
    """Microseconds per inputs + step + outputs of the native model compiled with its
    FMU's sources, no FMI calls (c_host/bench_model.c)."""
    spec = unpacked.spec(path, name)
    sources = Path(spec[1]).parents[2] / "sources"
    program = compile_c([HERE / "c_host" / "bench_model.c", *sorted(sources.glob("*.c"))],
                        directory / f"bench_model_{name}", f"-I{sources}", "-flto",
                        "-ffp-contract=off")
    rows = run_c_host(program, str(block_steps), str(repeats), spec[2], *spec[7:10])
    return [row[0] for row in rows]


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


def fmpy_vehicle(fmus, counts, duration):
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
    return wall, len(fleet)


def vehicle_scale(fmus, counts, duration, host, unpacked):
    """{'host/flavour': figures} for 370 instances (or the quick counts) for `duration`."""
    steps = int(round(duration / STEP))
    results = {}
    for flavour, paths in fmus.items():
        specs = [a for name, n in counts.items() for a in unpacked.spec(paths[name], name, n)]
        (wall, instances), = run_c_host(host, "vehicle", str(steps), *specs)
        results[f"c_host/{flavour}"] = (wall, int(instances))
        results[f"fmpy/{flavour}"] = fmpy_vehicle(paths, counts, duration)
    return {key: {"instances": n, "simulated_s": duration, "wall_s": wall,
                  "real_time_factor": duration / wall, "us_per_cycle": wall / (steps * n) * 1e6}
            for key, (wall, n) in results.items()}


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
    return f"{statistics.median(samples):.3g} ({min(samples):.3g}-{max(samples):.3g})"


def ratios(a, b):
    return [x / y for x, y in zip(a, b)]


def report(costs, alone, accuracy, scale, profile_text):
    lines = ["# Benchmark", "",
             "Medians over repetitions, range in brackets; ratios are taken within each "
             "repetition against the floor measured in it, in the same host: the native floor "
             "(an FMU with the same inputs and outputs and no work) for every FMU, and in "
             "fmpy also the pythonfmu floor for the Python flavour.", "",
             "## Cost at h = 1 ms, standard input", "",
             "| host | FMU | doStep (us) | doStep / floor | set + step + get (us) | "
             "cycle / floor | cycle / pythonfmu floor |",
             "|---|---|---|---|---|---|---|"]
    for host, results in costs.items():
        floor = results[FLOOR]
        for name, result in results.items():
            python_floor = (spread(ratios(result["cycle"], results[PYTHON_FLOOR]["cycle"]))
                            if PYTHON_FLOOR in results else "-")
            lines.append(f"| {host} | {name} | {spread(result['do_step'])} | "
                         f"{spread(ratios(result['do_step'], floor['do_step']))} | "
                         f"{spread(result['cycle'])} | "
                         f"{spread(ratios(result['cycle'], floor['cycle']))} | {python_floor} |")
    lines += ["", "## The model without FMI", "",
              "Microseconds per inputs + step + outputs through the model itself (Python: "
              "`CoSimulation`; native: the co-simulation layer compiled with the FMU's sources), "
              "and the cost of the same cycle through FMI in the host of its flavour against it "
              "(medians).", "",
              "| FMU | flavour | model alone (us) | through FMI (us) | host | FMI / alone |",
              "|---|---|---|---|---|---|"]
    for flavour, per_fmu in alone.items():
        host = "c_host" if flavour == "native" else "fmpy"
        for name, samples in per_fmu.items():
            through = costs[host][f"{flavour}/{name}"]["cycle"]
            lines.append(f"| {name} | {flavour} | {spread(samples)} | {spread(through)} | "
                         f"{host} | {statistics.median(through) / statistics.median(samples):.2f} |")
    lines += ["", "## Accuracy against cost (native FMUs in fmpy)", "",
              "Error in % of the output's peak-to-peak range: against the independent solve of "
              "the same sampled input (the FMU's own error), and against the continuous-input "
              "solve (adds the co-simulation's sampling of the input). The Python FMUs give the "
              "same numbers to the bit.", "",
              "| FMU | h (s) | error, same input (%) | error, continuous input (%) | cost per simulated s (s) |",
              "|---|---|---|---|---|"]
    for row in accuracy:
        lines.append(f"| {row['fmu']} | {row['h']:g} | {row['error_held_pct']:.2e} | "
                     f"{row['error_smooth_pct']:.3f} | {row['cost_s_per_s']:.4f} |")
    lines += ["", "## Vehicle scale", "",
              "| host / flavour | instances | simulated (s) | wall (s) | real-time factor | "
              "us per set + step + get |", "|---|---|---|---|---|---|"]
    for key, figures in scale.items():
        lines.append(f"| {key} | {figures['instances']} | {figures['simulated_s']:g} | "
                     f"{figures['wall_s']:.3f} | {figures['real_time_factor']:.2f} | "
                     f"{figures['us_per_cycle']:.3f} |")
    lines += ["", "## Profile of one Python FMU's doStep", "", "```", profile_text.strip(),
              "```", ""]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus",
                        help="folder of the native FMUs, the Python ones in its python/")
    parser.add_argument("--output", type=Path, default=HERE / "results.md")
    parser.add_argument("--quick", action="store_true", help="seconds: small sizes")
    parser.add_argument("--json", type=Path, help="also write the figures as JSON")
    args = parser.parse_args(argv)
    if args.quick:
        repeats, block, steps, periods, counts = 3, 300, [1e-2, 1e-1], 0.2, {n: 1 for n in VEHICLE}
        profile_steps, duration = 300, 0.2
    else:
        repeats, block, steps, periods, counts = 7, 20000, [1e-4, 1e-3, 1e-2, 1e-1], 1.0, VEHICLE
        profile_steps, duration = 20000, 1.0
    fmus = {"native": {n: args.fmus / f"{n}.fmu" for n in COMPONENTS},
            "python": {n: args.fmus / "python" / f"{n}.fmu" for n in COMPONENTS}}
    missing = [str(p) for paths in fmus.values() for p in paths.values() if not p.exists()]
    if missing:
        sys.exit(f"missing {', '.join(missing)}: build the FMUs first (python build_fmus.py)")
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        floors = build_floors(directory)
        host = compile_c([HERE / "c_host" / "bench_host.c"], directory / "bench_host")
        unpacked = Unpacked(directory / "unpacked")
        costs = cost_table(fmus, floors, unpacked, host, repeats, block)
        alone = {"native": {n: native_model_alone(p, n, unpacked, directory, repeats, block)
                            for n, p in fmus["native"].items()},
                 "python": {n: python_model_alone(n, repeats, min(block, 2000))
                            for n in COMPONENTS}}
        scale = vehicle_scale(fmus, counts, duration, host, unpacked)
    accuracy = accuracy_against_cost(fmus["native"], steps, periods)
    profile_text = profile(fmus["python"]["TrackBushTorsion"], "TrackBushTorsion", profile_steps)
    text = report(costs, alone, accuracy, scale, profile_text)
    print(text)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(text)
    if args.json:
        args.json.write_text(json.dumps({"costs": costs, "model_alone": alone,
                                         "accuracy": accuracy, "vehicle_scale": scale}))


if __name__ == "__main__":
    main()
