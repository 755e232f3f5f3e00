"""Property-based: random, physically bounded deflection histories with random step sizes.
Outputs stay finite, every closed history from the relaxed state absorbs energy
(the integral of F dx around it is >= 0), and the damper's gas spring stays inside C2."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import secant_rates

from conftest import FMU_NAMES, default_parameters
from fmu_runner import FmuRunner

# Base deflection and the excursion allowed around it: the thesis's measured ranges.
BOUNDS = {
    "RoadWheelTyre": (3.5e-3, 4.5e-3),  # -1 mm (out of contact) to 8 mm
    "TrackBushRadial": (0.3e-3, 0.3e-3),
    "TrackBushTorsion": (math.radians(10), math.radians(25)),
    "RotaryDamper": (0.0, 0.21),
}


@st.composite
def closed_history(draw, name):
    """Straight legs through random targets and back to the start, each leg cut into
    steps of random length."""
    base, excursion = BOUNDS[name]
    targets = draw(st.lists(st.floats(-1.0, 1.0), min_size=1, max_size=5))
    points = [base] + [base + excursion * f for f in targets] + [base]
    times, deflections = [0.0], [base]
    for start, end in zip(points, points[1:]):
        duration = draw(st.floats(0.05, 1.0))
        weights = draw(st.lists(st.floats(0.5, 1.5), min_size=10, max_size=40))
        fractions = np.cumsum(weights) / sum(weights)
        times += list(times[-1] + duration * fractions)
        deflections += list(start + (end - start) * fractions)
    deflections[-1] = base  # closed to the last bit
    return np.array(times), np.array(deflections)


def run_history(path, times, deflections):
    steps = np.diff(times)
    rates = secant_rates(times, deflections)
    runner = FmuRunner(path)
    runner.initialize(deflections[0], 0.0)  # at rest: no energy stored to begin with
    outputs = [runner.read()]
    for k in range(len(steps)):
        outputs.append(runner.step(deflections[k], rates[k], steps[k]))
    runner.free()
    return np.array(outputs)


def check_history(built_fmus, name, history):
    times, deflections = history
    outputs = run_history(built_fmus[name], times, deflections)
    assert np.all(np.isfinite(outputs))
    force = outputs[:, 0]
    work = np.trapezoid(force, deflections)
    scale = np.ptp(force) * np.ptp(deflections)
    assert work >= -1e-9 * scale, (work, scale)
    if name == "RotaryDamper":
        gas = [o.name for o in COMPONENTS[name].outputs].index("gas_deflection")
        assert np.all(np.abs(outputs[:, gas]) < default_parameters(name)["C2"])


@pytest.mark.parametrize("name", FMU_NAMES)
@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_random_closed_histories(built_fmus, name, data):
    check_history(built_fmus, name, data.draw(closed_history(name), label="history"))
