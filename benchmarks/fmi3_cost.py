"""Benchmark: an FMI 3.0 doStep cycle against the FMI 2.0 one, both native, in one C host.

    python benchmarks/fmi3_cost.py            # the full run (under a minute)
    python benchmarks/fmi3_cost.py --quick    # seconds: checks that it runs

``c_host/bench_fmi3.c`` loads a component's FMI 2.0 binary (fmus/) and its FMI 3.0 binary
(fmus/fmi3/), the same core behind two faces, and times set + doStep + get of each in
alternating blocks on the component's thesis sine at h = 1 ms; the ratio is taken within
each repetition. Medians over repetitions, range in brackets.
"""

import argparse
import tempfile
import zipfile
from pathlib import Path

from fmpy import read_model_description

from run import HERE, ROOT, Unpacked, compile_c, native_fmus, run_c_host, spread


def fmi3_place(path, directory):
    """(library, resource path, instantiation token) of an unzipped FMI 3.0 FMU."""
    target = directory / f"fmi3_{path.stem}"
    with zipfile.ZipFile(path) as archive:
        archive.extractall(target)
    description = read_model_description(str(target / "modelDescription.xml"))
    identifier = description.coSimulation.modelIdentifier
    return (str(target / "binaries" / "x86_64-linux" / f"{identifier}.so"),
            str(target / "resources") + "/", description.guid)


def measure(fmus, fmi3_fmus, repeats, steps):
    """{name: {'fmi2': [us], 'fmi3': [us], 'ratio': [...]}}."""
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        host = compile_c([HERE / "c_host" / "bench_fmi3.c"], directory / "bench_fmi3")
        unpacked = Unpacked(directory / "unpacked")
        for name in fmus:
            spec = unpacked.spec(fmus[name], name)
            library3, resources3, token3 = fmi3_place(fmi3_fmus[name], directory)
            rows = run_c_host(host, str(steps), str(repeats), spec[1], spec[2], library3,
                              resources3, spec[3], token3, spec[4], spec[5], spec[6], *spec[7:])
            results[name] = {"fmi2": [r[0] for r in rows], "fmi3": [r[1] for r in rows],
                             "ratio": [r[1] / r[0] for r in rows]}
    return results


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmus", type=Path, default=ROOT / "fmus",
                        help="folder of the native FMUs, the FMI 3.0 ones in its fmi3/")
    parser.add_argument("--quick", action="store_true", help="seconds: small sizes")
    args = parser.parse_args(argv)
    repeats, steps = (3, 300) if args.quick else (9, 20000)
    results = measure(native_fmus(args.fmus), native_fmus(args.fmus, "fmi3"), repeats, steps)
    print("# FMI 3.0 against FMI 2.0 in a C host\n")
    print(f"{repeats} repetitions of {steps} set + doStep + get cycles each; medians, range "
          f"in brackets.\n")
    print("| FMU | FMI 2.0 cycle (us) | FMI 3.0 cycle (us) | FMI 3.0 / FMI 2.0 |")
    print("|---|---|---|---|")
    for name, r in results.items():
        print(f"| {name} | {spread(r['fmi2'])} | {spread(r['fmi3'])} | {spread(r['ratio'])} |")


if __name__ == "__main__":
    main()
