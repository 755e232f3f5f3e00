"""Benchmark: the Python flavour's set + step + get cycle in a C host against fmpy, and
against an earlier build in the same C host.

    python benchmarks/python_c_host.py                          # fmus/python
    python benchmarks/python_c_host.py --before OLD/python      # and an earlier build's FMUs
    python benchmarks/python_c_host.py --fmus fmus --before OLD # the native flavour likewise
    python benchmarks/python_c_host.py --quick                  # seconds: checks that it runs

Every figure comes from this one run: each repetition measures every FMU in both hosts back
to back, and the ratios are taken within a repetition, so a busy machine slows numerator
and denominator alike. Medians over repetitions, range in brackets.

* fmpy: ``FMU2Slave`` through Python's ctypes, in this process (run.Timed).
* C host: ``c_host/bench_host.c`` in a subprocess: it loads the FMU's binary with dlopen,
  which loads Python itself, and times the calls.
* ``--before``: an earlier build of the Python FMUs, in the C host only. In fmpy it would
  share this process with the current build, and a build from before the module isolation
  of spec section 8 runs whatever ``fmu_components`` the process has loaded, not its own.
"""

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

from run import HERE, ROOT, Timed, Unpacked, compile_c, run_c_host, timer_overhead

from fmu_components.runtime.catalog import COMPONENTS


def spread(samples):
    return f"{statistics.median(samples):.3g} ({min(samples):.3g}-{max(samples):.3g})"


def measure(current, before, repeats, steps):
    """{name: {'fmpy': [us], 'c_host': [us], 'c_host_before': [us]}}, per repetition."""
    results = {name: {"fmpy": [], "c_host": [], "c_host_before": []} for name in current}
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        host = compile_c([HERE / "c_host" / "bench_host.c"], directory / "bench_host")
        unpacked = Unpacked(directory / "unpacked")
        overhead = timer_overhead()
        timed = {name: Timed(path, name, repeats * steps + 2) for name, path in current.items()}
        for _ in range(repeats):
            for name, path in current.items():
                results[name]["fmpy"].append(timed[name].block(steps, overhead)[1])
                (_, cycle), = run_c_host(host, "cost", str(steps), "1", *unpacked.spec(path, name))
                results[name]["c_host"].append(cycle)
                if before:
                    (_, cycle), = run_c_host(host, "cost", str(steps), "1",
                                             *unpacked.spec(before[name], name))
                    results[name]["c_host_before"].append(cycle)
        for instance in timed.values():
            instance.runner.free()
    return results


def report(results, repeats, steps, before):
    lines = ["# FMUs in a C host and in fmpy", "",
             f"Microseconds per fmi2SetReal (both inputs) + fmi2DoStep + fmi2GetReal (every "
             f"output) at h = 1 ms on the standard input; {repeats} repetitions of {steps} "
             f"steps, medians with the range; ratios within each repetition.", "",
             "| FMU | fmpy | C host | C host / fmpy |"
             + (" C host, before | before / now |" if before else ""),
             "|---|---|---|---|" + ("---|---|" if before else "")]
    for name, figures in results.items():
        ratio = [c / f for c, f in zip(figures["c_host"], figures["fmpy"])]
        row = (f"| {name} | {spread(figures['fmpy'])} | {spread(figures['c_host'])} | "
               f"{spread(ratio)} |")
        if before:
            gain = [b / c for b, c in zip(figures["c_host_before"], figures["c_host"])]
            row += f" {spread(figures['c_host_before'])} | {spread(gain)} |"
        lines.append(row)
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus" / "python",
                        help="folder of the Python FMUs (default: fmus/python)")
    parser.add_argument("--before", type=Path, help="folder of an earlier build's Python FMUs")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--steps", type=int, default=5000, help="steps per repetition")
    parser.add_argument("--quick", action="store_true", help="3 repetitions of 300 steps")
    args = parser.parse_args(argv)
    repeats, steps = (3, 300) if args.quick else (args.repeats, args.steps)
    current = {n: args.fmus / f"{n}.fmu" for n in COMPONENTS}
    before = {n: args.before / f"{n}.fmu" for n in COMPONENTS} if args.before else None
    missing = [str(p) for p in [*current.values(), *(before or {}).values()] if not p.exists()]
    if missing:
        sys.exit(f"missing {', '.join(missing)}: build the FMUs first (python build_fmus.py)")
    print(report(measure(current, before, repeats, steps), repeats, steps, before))


if __name__ == "__main__":
    main()
