"""Benchmark: what the coupling library's corrected scheme costs each native FMU in a C host.

    python benchmarks/rollback_cost.py            # the full run (under a minute)
    python benchmarks/rollback_cost.py --quick    # seconds: checks that it runs

The corrected scheme (fmu_components.coupling, docs/coupling.md) asks of each FMU per host
step: fmi2GetFMUstate into the state it keeps, a set + doStep + get cycle, fmi2SetFMUstate
back to the step's start, and the cycle again. The C host (``c_host/bench_host.c``,
``rollback``) times that corrected cycle against a plain cycle on the component's standard
input at h = 1 ms, and fmi2GetFMUstate and fmi2SetFMUstate alone, in one run per repetition,
so the ratio is taken on one machine state. Medians over repetitions, range in brackets.
"""

import argparse
import tempfile
from pathlib import Path

from run import HERE, ROOT, Unpacked, compile_c, native_fmus, run_c_host, spread


def measure(fmus, repeats, steps):
    """{name: {'plain': [us], 'corrected': [us], 'ratio': [...], 'get': [ns], 'set': [ns],
    'corrected_cpu': [us]}}: wall times, and the corrected cycle's CPU time."""
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        host = compile_c([HERE / "c_host" / "bench_host.c"], directory / "bench_host")
        unpacked = Unpacked(directory / "unpacked")
        for name, path in fmus.items():
            rows = run_c_host(host, "rollback", str(steps), str(repeats),
                              *unpacked.spec(path, name))
            results[name] = {"plain": [r[0] for r in rows], "corrected": [r[1] for r in rows],
                             "ratio": [r[1] / r[0] for r in rows],
                             "get": [r[2] for r in rows], "set": [r[3] for r in rows],
                             "corrected_cpu": [r[4] for r in rows]}
    return results


def report(results, repeats, steps):
    lines = ["# The corrected step's cost in a C host", "",
             f"{repeats} repetitions of {steps} cycles each; medians, range in brackets.", "",
             "| FMU | plain cycle (us) | corrected cycle (us) | corrected / plain | "
             "fmi2GetFMUstate (ns) | fmi2SetFMUstate (ns) |", "|---|---|---|---|---|---|"]
    for name, r in results.items():
        lines.append(f"| {name} | {spread(r['plain'])} | {spread(r['corrected'])} | "
                     f"{spread(r['ratio'])} | {spread(r['get'])} | {spread(r['set'])} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus",
                        help="folder of the native FMUs")
    parser.add_argument("--quick", action="store_true", help="seconds: small sizes")
    args = parser.parse_args(argv)
    repeats, steps = (3, 300) if args.quick else (9, 20000)
    print(report(measure(native_fmus(args.fmus), repeats, steps), repeats, steps))


if __name__ == "__main__":
    main()
