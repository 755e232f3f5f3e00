"""The fit's own check: recover parameter sets the thesis never had, and predict the tests
the fit did not see.

    python benchmarks/fit_check.py [--components TrackBushRadial ...] [--figure PNG]

For each rubber component and each of two parameter sets (the thesis's Maxwell elements and
elastic polynomial scaled, SETS), the thesis's test programme (``cases``: Measurements I-IV
of spec section 5) is solved by the independent reference solver (scipy Radau, continuous
input) and sampled at up to 200 points per cycle with Gaussian noise of 0.5 % of each
test's peak-to-peak force. The fit sees Measurement I (every preload), one amplitude of
Measurement II and the slowest frequency of Measurement III (the one that carries the
long time constants); it predicts the other amplitudes, the other frequencies and the
relaxation (Measurement IV). Errors are against the noise-free reference, the largest
|predicted - true| over the whole test in % of its peak-to-peak force. Then one fit of the
whole programme (about 15 tests) is timed.

Figures are measurements, printed; nothing here is asserted (tests/test_fit.py holds the
fast round trip).
"""

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from fmu_components.verification import cases, synthetic
from fmu_components.lab.fit import fit, fitted_names
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.history import simulate

NOISE = 0.005
# per component: the amplitude of II the fit sees (the thesis's preload level)
FIT_AMPLITUDE = {"RoadWheelTyre": "II_amplitude_1mm", "TrackBushRadial": "II_amplitude_0.1mm",
                 "TrackBushTorsion": "II_amplitude_5deg"}
SETS = {
    "A": {"k": 0.6, "c": 1.4, "xi": 1.5, "elastic.a1": 1.2, "geometric.h": 1.3},
    "B": {"k": 1.7, "c": 0.7, "xi": 0.6, "elastic.a1": 0.85, "elastic.a3": 1.3,
          "geometric.h": 0.8},
}
RUBBER = ("RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion")


def programme(component):
    return [c for c in cases.CASES if c.fmu == component and c.test in ("I", "II", "III", "IV")]


def fit_names(component):
    slowest = min((c for c in programme(component) if c.test == "III"),
                  key=lambda c: synthetic._frequency(c))
    return {c.name for c in programme(component) if c.test == "I"} | {
        FIT_AMPLITUDE[component], slowest.name}


def _measure(job):
    key, values, seed = job  # a case by its key: its path is a closure, not picklable
    (case,) = [c for c in cases.CASES if c.key == key]
    return synthetic.measure(case, values, NOISE, seed)


def measurements(component, values, pool):
    jobs = [(case.key, values, seed) for seed, case in enumerate(programme(component))]
    return dict(zip([c.name for c in programme(component)], pool.map(_measure, jobs)))


def check(component, set_name, data):
    truth = synthetic.scaled(component, SETS[set_name])
    seen = fit_names(component)
    started = time.perf_counter()
    result = fit(component, [data[n][0] for n in sorted(seen)])
    wall = time.perf_counter() - started
    errors = {}
    for name, (history, true_force) in data.items():
        predicted = simulate(component, result.values, history.times, history.deflection)
        errors[name] = synthetic.peak_to_peak_error(predicted, true_force)
    print(f"\n{component}, set {set_name} ({', '.join(f'{k} x{v}' for k, v in SETS[set_name].items())}):"
          f" fit on {len(seen)} tests in {wall:.1f} s, {len(result.starts)} starts, "
          f"costs {', '.join(f'{c:.3g}' for c, _, _ in result.starts)}")
    print(f"  {'test':24s} {'role':9s} {'max error % p-p':>16s}")
    for name, error in errors.items():
        print(f"  {name:24s} {'fitted' if name in seen else 'predicted':9s} {error:16.3f}")
    held = {n: e for n, e in errors.items() if n not in seen}
    loops = max(e for n, e in held.items() if not n.startswith("IV"))
    relaxation = max(e for n, e in held.items() if n.startswith("IV"))
    print(f"  held-back loops: worst {loops:.3f} % (target 2 %); relaxation {relaxation:.3f} % "
          f"(target 5 %)")
    confidence = result.confidence()
    print(f"  {'parameter':14s} {'true':>12s} {'fitted':>12s} {'ratio':>7s} {'95% CI +-%':>10s}")
    for name in fitted_names(COMPONENTS[component]):
        ratio = result.values[name] / truth[name] if truth[name] else float("nan")
        print(f"  {name:14s} {truth[name]:12.5g} {result.values[name]:12.5g} {ratio:7.3f} "
              f"{confidence[name][2] * 100:10.1f}")
    return result, errors, loops, relaxation, wall


def figure(component, set_name, data, result, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fmu_components.verification.report import DISPLAY

    (xf, xu), (ff, fu), _ = DISPLAY[component]
    seen = fit_names(component)
    fig, (loops, relax) = plt.subplots(1, 2, figsize=(9, 3.6))
    for i, (name, (history, truth)) in enumerate(
            (n, d) for n, d in data.items() if n not in seen and not n.startswith("IV")):
        predicted = simulate(component, result.values, history.times, history.deflection)
        last = history.times >= history.times[-1] - (history.times[-1] - history.times[0]) / 3
        loops.plot(history.deflection[last] * xf, history.force[last] * ff, ".", markersize=1,
                   color="0.7")
        loops.plot(history.deflection[last] * xf, predicted[last] * ff, linewidth=0.9,
                   color=f"C{i}", label=name.replace("_", " "))
    loops.set_xlabel(f"deflection ({xu})")
    loops.set_ylabel(f"force ({fu})")
    loops.set_title("held-back loops: measured (dots), predicted", fontsize=9)
    loops.legend(fontsize=6)
    (name,) = [n for n in data if n.startswith("IV")]
    history, truth = data[name]
    predicted = simulate(component, result.values, history.times, history.deflection)
    hold = history.times > 0.1
    relax.semilogx(history.times[hold], history.force[hold] * ff, ".", markersize=1, color="0.7",
                   label="measured (0.5 % noise)")
    relax.semilogx(history.times[hold], predicted[hold] * ff, color="C3", label="predicted")
    relax.set_xlabel("time (s)")
    relax.set_ylabel(f"force ({fu})")
    relax.set_title("held-back relaxation", fontsize=9)
    relax.legend(fontsize=7)
    fig.suptitle(f"{component}, parameter set {set_name}: fit on Measurement I, one amplitude, "
                 f"one frequency", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--components", nargs="+", default=list(RUBBER), choices=RUBBER)
    parser.add_argument("--sets", nargs="+", default=list(SETS), choices=sorted(SETS))
    parser.add_argument("--figure", help="PNG of the first component's first set")
    parser.add_argument("--timed", default="TrackBushRadial", choices=RUBBER,
                        help="the component whose whole-programme fit is timed")
    args = parser.parse_args(argv)
    summary = []
    with ProcessPoolExecutor(2) as pool:
        for component in args.components:
            for set_name in args.sets:
                data = measurements(component, synthetic.scaled(component, SETS[set_name]), pool)
                result, errors, loops, relaxation, wall = check(component, set_name, data)
                summary.append((component, set_name, loops, relaxation, wall))
                if args.figure and len(summary) == 1:
                    figure(component, set_name, data, result, args.figure)
        data = measurements(args.timed, synthetic.scaled(args.timed, SETS["A"]), pool)
    started = time.perf_counter()
    whole = fit(args.timed, [history for history, _ in data.values()])
    wall = time.perf_counter() - started
    samples = sum(len(h.times) for h, _ in data.values())
    print(f"\nwhole programme of {args.timed} (set A): {len(data)} tests, {samples} samples, "
          f"{len(whole.free)} parameters, {len(whole.starts)} starts on 2 processes: "
          f"{wall:.1f} s wall")
    print(f"\n{'component':18s} {'set':4s} {'worst held-back loop %':>22s} "
          f"{'relaxation %':>13s} {'fit s':>6s}")
    for component, set_name, loops, relaxation, wall in summary:
        print(f"{component:18s} {set_name:4s} {loops:22.3f} {relaxation:13.3f} {wall:6.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
