"""Each FMU at a 1 ms communication step against the independent reference solve
(fmu_components.verification.reference: plain right-hand sides, scipy Radau at rtol 1e-10), for sine
inputs across the thesis ranges. The reference applies the same co-simulation input
convention (spec section 4), so the difference is the FMU's own numerical error."""

import math

import numpy as np
import pytest
from fmpy import simulate_fmu

from fmu_components.verification import reference
from fmu_components.lab.signals import THESIS_SINES, input_table, secant_rates, sine, time_grid

from conftest import peak_to_peak
from fmu_runner import FmuRunner

ACCEPTANCE = 0.5e-2  # of the output's peak-to-peak range

CASES = [  # (FMU, mean, amplitude, frequency Hz, duration s)
    ("RoadWheelTyre", 3.5e-3, 1e-3, 1.0, 1.0),
    ("RoadWheelTyre", 3.5e-3, 1e-3, 20.0, 0.25),
    ("TrackBushRadial", 0.3e-3, 0.3e-3, 1.0, 1.0),
    ("TrackBushRadial", 0.3e-3, 0.1e-3, 20.0, 0.25),
    ("TrackBushTorsion", math.radians(10), math.radians(20), 1.0, 1.0),
    ("TrackBushTorsion", math.radians(10), math.radians(5), 5.0, 0.5),
    ("RotaryDamper", 0.0, 0.21, 0.75, 1.34),
    ("RotaryDamper", 0.0, 0.21, 8.0, 0.25),
]


@pytest.mark.parametrize("name, mean, amplitude, frequency, duration", CASES,
                         ids=[f"{c[0]}-{c[3]:g}Hz" for c in CASES])
def test_fmu_at_1_ms_matches_the_independent_solve(built_fmus, name, mean, amplitude,
                                                    frequency, duration):
    step = 1e-3
    t = time_grid(duration, step)
    x = sine(t, mean, amplitude, frequency)
    expected = reference.solve_held_rate(name, t, x, secant_rates(t, x))
    result = simulate_fmu(str(built_fmus[name]), stop_time=t[-1], output_interval=step,
                          input=input_table(name, t, x), output=list(expected))
    assert len(result) == len(t)
    for output, values in expected.items():
        error = np.max(np.abs(result[output] - values)) / peak_to_peak(values)
        assert error <= ACCEPTANCE, (output, error)


@pytest.mark.parametrize("step", [1e-7, 2.0, 100.0])
@pytest.mark.parametrize("name", sorted(THESIS_SINES))
def test_any_communication_step_matches_the_independent_solve(built_fmus, name, step):
    """Steps outside 1e-6..1 s are taken as any other (README: 'Call pattern'): a ramp at the
    thesis sine's fastest rate over 10 steps of 0.1 us; a rise by the amplitude over one
    step of 2 or 100 s, then a hold as long."""
    mean, amplitude, frequency = THESIS_SINES[name]
    if step < 1e-3:
        t = np.arange(11) * step
        x = mean + amplitude * 2 * math.pi * frequency * t
    else:
        t = np.array([0.0, step, 2 * step])
        x = np.array([mean, mean + amplitude, mean + amplitude])
    rates = secant_rates(t, x)
    expected = reference.solve_held_rate(name, t, x, rates)
    runner = FmuRunner(built_fmus[name])
    runner.initialize(x[0], rates[0])
    rows = [runner.read()]
    for k in range(len(t) - 1):
        runner.step(x[k], rates[k], step)
        rows.append(runner.read())
    runner.free()
    for output, values in expected.items():
        got = np.array([row[runner.outputs.index(output)] for row in rows])
        assert np.max(np.abs(got - values)) <= 1e-3 * peak_to_peak(values), output
